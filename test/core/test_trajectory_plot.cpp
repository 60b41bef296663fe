// The trajectory picture: layout (one metric scale, x right, z up), tick steps, and loops drawn green
// where the ground truth agrees and red where not, on a made-up square and on KITTI 06.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/evaluation/evaluation.h"
#include "openable/evaluation/loop_list.h"
#include "openable/view/trajectory_plot.h"
#include "test_util.h"

using openable::LoopPair;
using openable::TrajectoryPlot;

namespace
{
bool isRed(const cv::Vec3b& bgr)
{
  return bgr[2] > 180 && bgr[1] < 70 && bgr[0] < 70;
}

bool isGreen(const cv::Vec3b& bgr)
{
  return bgr[1] > 120 && bgr[2] < 70 && bgr[0] < 70;
}

cv::Vec3b pixel(const cv::Mat& image, const cv::Point2d& p)
{
  return image.at<cv::Vec3b>(static_cast<int>(std::lround(p.y)), static_cast<int>(std::lround(p.x)));
}

/// A 100 m square driven anticlockwise seen from above, one frame per metre, ending where it started.
std::vector<cv::Vec3d> square()
{
  std::vector<cv::Vec3d> positions;
  for (int i = 0; i < 100; ++i)
    positions.emplace_back(i, 0.0, 0.0);
  for (int i = 0; i < 100; ++i)
    positions.emplace_back(100.0, 0.0, i);
  for (int i = 0; i < 100; ++i)
    positions.emplace_back(100.0 - i, 0.0, 100.0);
  for (int i = 0; i <= 100; ++i)
    positions.emplace_back(0.0, 0.0, 100.0 - i);
  return positions;
}
}  // namespace

TEST(TrajectoryPlot, NiceTickSteps)
{
  EXPECT_DOUBLE_EQ(openable::niceTickStep(100.0, 8), 20.0);
  EXPECT_DOUBLE_EQ(openable::niceTickStep(1.0, 5), 0.2);
  EXPECT_DOUBLE_EQ(openable::niceTickStep(7.0, 7), 1.0);
  EXPECT_DOUBLE_EQ(openable::niceTickStep(450.0, 8), 100.0);
  EXPECT_DOUBLE_EQ(openable::niceTickStep(0.0, 8), 1.0);
}

TEST(TrajectoryPlot, SeenFromAboveWithOneScaleForBothAxes)
{
  const TrajectoryPlot plot(square(), cv::Size(1000, 800));
  const cv::Point2d origin = plot.toPixel({0, 0, 0});
  const cv::Point2d right = plot.toPixel({100, 0, 0});
  const cv::Point2d forward = plot.toPixel({0, 0, 100});
  EXPECT_GT(right.x, origin.x + 100);  // x to the right
  EXPECT_NEAR(right.y, origin.y, 1e-9);
  EXPECT_LT(forward.y, origin.y - 100);  // z (forward) up
  EXPECT_NEAR(forward.x, origin.x, 1e-9);
  EXPECT_NEAR(right.x - origin.x, origin.y - forward.y, 1e-9);  // a metre is a metre both ways
  EXPECT_NEAR(plot.toPixel({0, -50, 0}).y, origin.y, 1e-9);     // height (y) does not show
  // The whole path is inside the picture.
  for (const cv::Vec3d& p : square())
  {
    const cv::Point2d q = plot.toPixel(p);
    EXPECT_TRUE(q.x > 0 && q.x < 1000 && q.y > 0 && q.y < 800) << q;
  }
  EXPECT_THROW(TrajectoryPlot({}, cv::Size(1000, 800)), openable::Error);
  EXPECT_THROW(TrajectoryPlot(square(), cv::Size(100, 100)), openable::Error);
  EXPECT_THROW(TrajectoryPlot({cv::Vec3d(0, 0, std::nan(""))}), openable::Error);
}

TEST(TrajectoryPlot, LoopsAreGreenWhenTheGroundTruthAgreesAndRedWhenNot)
{
  const TrajectoryPlot plot(square(), cv::Size(1000, 800));
  // 400 closes the loop on 0 (right); 250 claims to be the place of 50 (the opposite side: wrong).
  std::vector<LoopPair> loops = {{400, 0}, {398, 2}, {250, 50}};
  loops[0].agrees = loops[1].agrees = true;
  const cv::Mat image = plot.draw(loops, "square");
  ASSERT_EQ(image.size(), cv::Size(1000, 800));
  ASSERT_EQ(image.type(), CV_8UC3);
  EXPECT_TRUE(isGreen(pixel(image, plot.framePixel(398)))) << pixel(image, plot.framePixel(398));
  EXPECT_TRUE(isGreen(pixel(image, plot.framePixel(2))));
  const cv::Point2d middle = 0.5 * (plot.framePixel(250) + plot.framePixel(50));
  EXPECT_TRUE(isRed(pixel(image, middle))) << pixel(image, middle);
  EXPECT_TRUE(isRed(pixel(image, plot.framePixel(250))));
  // The path itself is neither (at a frame without loop).
  EXPECT_FALSE(isRed(pixel(image, plot.framePixel(150))) || isGreen(pixel(image, plot.framePixel(150))));
  EXPECT_THROW(plot.draw({{401, 0}}, ""), openable::Error);
}

TEST(TrajectoryPlot, Kitti06LoopsWhereTheSequenceRevisitsItsStart)
{
  // KITTI 06 with its published loop ground truth as the detections, plus three wrong pairs (frames far
  // apart on the map). The published pairs mostly agree with the ground truth from the poses (6 m, 100
  // frames, as openable_eval makes it); the picture is judged against the published pairs themselves.
  const std::string published_file = openable_test::sharedData("kitti/loop_ground_truth/kitti06GroundTruth.txt");
  const std::vector<cv::Vec3d> positions =
      openable::loadKittiPositions(openable_test::sharedData("kitti/poses/06.txt"));
  ASSERT_EQ(positions.size(), 1101u);
  std::vector<LoopPair> loops = openable::loadLoopPairs(published_file);
  ASSERT_GT(loops.size(), 3000u);
  const size_t published = loops.size();
  const std::vector<LoopPair> wrong = {{450, 120}, {550, 15}, {1000, 400}};
  loops.insert(loops.end(), wrong.begin(), wrong.end());
  openable::judgeLoops(loops, openable::posesGroundTruth(positions));
  size_t agreeing = 0;
  for (size_t i = 0; i < published; ++i)
    agreeing += loops[i].agrees ? 1 : 0;
  EXPECT_GT(agreeing, published * 95 / 100);
  openable::judgeLoops(loops, openable::loadPairsGroundTruth(published_file));
  for (size_t i = 0; i < loops.size(); ++i)
    EXPECT_EQ(loops[i].agrees, i < published) << loops[i].query << "-" << loops[i].match;

  const TrajectoryPlot plot(positions, cv::Size(1000, 800));
  const cv::Mat image = plot.draw(loops, "KITTI 06");
  // Red along each wrong loop (its middle and both ends).
  for (const LoopPair& loop : wrong)
  {
    const cv::Point2d a = plot.framePixel(loop.query), b = plot.framePixel(loop.match);
    for (const cv::Point2d& p : {a, b, 0.5 * (a + b)})
      EXPECT_TRUE(isRed(pixel(image, p))) << loop.query << "-" << loop.match << " at " << p << ": " << pixel(image, p);
  }
  // Green where 06 returns to its start (frames 829..1100 drive again over frames 0..297) ...
  int green = 0, checked = 0;
  for (size_t i = 0; i < published; i += 50)
  {
    if (!loops[i].agrees)
      continue;
    ++checked;
    green += isGreen(pixel(image, plot.framePixel(loops[i].query))) ? 1 : 0;
  }
  EXPECT_GE(green, checked * 9 / 10) << green << " of " << checked;
  // ... and nowhere else: the far end of the route (frames 400..700) has no loop.
  for (int frame = 400; frame <= 700; frame += 25)
    EXPECT_FALSE(isGreen(pixel(image, plot.framePixel(frame)))) << frame;
}
