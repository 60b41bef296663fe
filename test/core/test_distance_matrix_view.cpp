// DistanceMatrixView: bounded, min-pooled display of the distance matrix (no ROS, no master).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "openable/view/distance_matrix_view.h"
#include "openable/error.h"

using openable::DistanceMatrixView;

namespace
{
const float kNaN = std::numeric_limits<float>::quiet_NaN();

// Row of query t in a loop-closure stream of `t + 1` stored frames: distance 0.5 everywhere, the frame
// itself and the `excluded` frames before it not compared (NaN), and an optional loop at `loop_to`.
std::vector<float> streamRow(int t, int excluded, int loop_to = -1, float loop_distance = 0.05f)
{
  std::vector<float> row(size_t(t + 1), 0.5f);
  for (int j = std::max(0, t - excluded); j <= t; ++j)
  {
    row[size_t(j)] = kNaN;
  }
  if (loop_to >= 0)
  {
    row[size_t(loop_to)] = loop_distance;
  }
  return row;
}
}  // namespace

TEST(DistanceMatrixView, RejectsTinySize)
{
  EXPECT_THROW(DistanceMatrixView(1), openable::Error);
  DistanceMatrixView view(4);
  EXPECT_THROW(view.setSize(0), openable::Error);
}

TEST(DistanceMatrixView, SmallStreamIsShownCellForCell)
{
  DistanceMatrixView view(8);
  for (int t = 0; t < 5; ++t)
  {
    view.addRow(0, streamRow(t, 1));
  }
  EXPECT_EQ(view.rows(), 5);
  EXPECT_EQ(view.columns(), 5);
  EXPECT_EQ(view.rowScale(), 1u);
  const cv::Mat cells = view.cells();
  ASSERT_EQ(cells.rows, 5);
  EXPECT_FLOAT_EQ(cells.at<float>(4, 0), 0.5f);
  // The frame itself and the excluded one are marked as excluded, the future as unknown.
  EXPECT_FLOAT_EQ(cells.at<float>(4, 4), DistanceMatrixView::kExcluded);
  EXPECT_FLOAT_EQ(cells.at<float>(4, 3), DistanceMatrixView::kExcluded);
  EXPECT_TRUE(std::isnan(cells.at<float>(1, 3)));
}

TEST(DistanceMatrixView, WholeHistoryStaysBoundedAndKeepsLoopsByMinPooling)
{
  const int size = 16;
  DistanceMatrixView view(size);
  const int frames = 1000;
  for (int t = 0; t < frames; ++t)
  {
    // One single low cell in the whole matrix: query 900 revisits frame 100.
    view.addRow(0, streamRow(t, 10, t == 900 ? 100 : -1));
    ASSERT_LE(view.rows(), size);
    ASSERT_LE(view.columns(), size);
  }
  EXPECT_EQ(view.rowScale(), 64u);  // 1000 rows in 16 cells: 64 frames per cell
  EXPECT_EQ(view.columnScale(), 64u);
  const cv::Mat cells = view.cells();
  // The loop survives pooling, in the cell that covers (900, 100).
  EXPECT_FLOAT_EQ(cells.at<float>(900 / 64, 100 / 64), 0.05f);
  double low = 0;
  cv::Mat finite = cells.clone();
  cv::patchNaNs(finite, 1.0);
  cv::minMaxLoc(finite, &low);
  EXPECT_FLOAT_EQ(float(low), 0.05f);
  // Exactly one cell holds it.
  EXPECT_EQ(cv::countNonZero(finite < 0.1f), 1);
}

TEST(DistanceMatrixView, RollingWindowKeepsTheLastRows)
{
  const int size = 10;
  DistanceMatrixView view(size, DistanceMatrixView::Mode::kRollingWindow);
  for (int t = 0; t < 25; ++t)
  {
    view.addRow(0, streamRow(t, 0, t == 22 ? 3 : -1));
  }
  EXPECT_EQ(view.rows(), size);
  EXPECT_EQ(view.rowScale(), 1u);
  // 25 reference frames in 10 columns: pooled twice.
  EXPECT_EQ(view.columnScale(), 4u);
  const cv::Mat cells = view.cells();
  // Rows are queries 15..24, oldest first; query 22 is row 7 and its loop to frame 3 is in column 0.
  EXPECT_FLOAT_EQ(cells.at<float>(7, 0), 0.05f);
  EXPECT_FLOAT_EQ(cells.at<float>(6, 0), 0.5f);
  // The newest row's own frame (24) is excluded and lies in column 6.
  EXPECT_FLOAT_EQ(cells.at<float>(9, 24 / 4), DistanceMatrixView::kExcluded);
}

TEST(DistanceMatrixView, EvictedReferencesAndLocalisationMaps)
{
  // A bounded history: rows start at ids that grow; the view keeps its first column.
  DistanceMatrixView view(8);
  view.addRow(10, std::vector<float>(4, 0.3f));  // references 10..13
  view.addRow(12, std::vector<float>(4, 0.2f));  // references 12..15: 10, 11 evicted
  view.addRow(5, std::vector<float>(8, 0.1f));   // ids before 10 are ignored
  const cv::Mat cells = view.cells();
  ASSERT_EQ(cells.cols, 6);
  EXPECT_FLOAT_EQ(cells.at<float>(1, 2), 0.2f);
  EXPECT_TRUE(std::isnan(cells.at<float>(1, 0)));
  EXPECT_FLOAT_EQ(cells.at<float>(2, 0), 0.1f);  // id 10
  EXPECT_FLOAT_EQ(cells.at<float>(2, 2), 0.1f);  // id 12 (the last of 5..12)
  EXPECT_TRUE(std::isnan(cells.at<float>(2, 3)));
}

TEST(DistanceMatrixView, SetSizeRepoolsWhatIsShown)
{
  DistanceMatrixView view(32);
  for (int t = 0; t < 30; ++t)
  {
    view.addRow(0, streamRow(t, 2, t == 25 ? 5 : -1));
  }
  view.setSize(8);
  EXPECT_LE(view.rows(), 8);
  EXPECT_LE(view.columns(), 8);
  EXPECT_EQ(view.rowScale(), 4u);
  EXPECT_FLOAT_EQ(view.cells().at<float>(25 / 4, 5 / 4), 0.05f);
  // Growing again keeps the picture and the scale, and new rows go on where they belong.
  view.setSize(64);
  EXPECT_EQ(view.rowScale(), 4u);
  view.addRow(0, streamRow(30, 2, 1));
  EXPECT_FLOAT_EQ(view.cells().at<float>(30 / 4, 0), 0.05f);

  DistanceMatrixView rolling(16, DistanceMatrixView::Mode::kRollingWindow);
  for (int t = 0; t < 40; ++t)
  {
    rolling.addRow(0, streamRow(t, 0, t == 38 ? 0 : -1));
  }
  rolling.setSize(4);
  EXPECT_EQ(rolling.rows(), 4);
  rolling.addRow(0, streamRow(40, 0));
  // Queries 37..40 shown; 38 (row 1) has its loop in column 0.
  EXPECT_FLOAT_EQ(rolling.cells().at<float>(1, 0), 0.05f);
}

TEST(DistanceMatrixView, RenderIsBoundedColouredAndMarksLoops)
{
  DistanceMatrixView view(64);
  EXPECT_TRUE(view.render({}).empty());
  for (int t = 0; t < 20; ++t)
  {
    view.addRow(0, streamRow(t, 3, t == 15 ? 2 : -1));
    if (t == 15)
    {
      view.addLoop(2);
    }
  }
  DistanceMatrixView::RenderOptions options;
  options.mark_loops = false;
  const cv::Mat plain = view.render(options);
  ASSERT_EQ(plain.type(), CV_8UC3);
  // Always size x size: 20 cells scaled by 3.2 (64 / 20) fill it.
  EXPECT_EQ(plain.rows, 64);
  EXPECT_EQ(plain.cols, 64);
  auto at = [](int cell) { return int((cell + 0.5) * 3.2); };  // the pixel in the middle of a cell
  // Unknown (upper triangle) black, excluded blue-grey, distances coloured.
  EXPECT_EQ(plain.at<cv::Vec3b>(at(0), at(18)), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(plain.at<cv::Vec3b>(at(18), at(18)), cv::Vec3b(90, 60, 50));
  EXPECT_NE(plain.at<cv::Vec3b>(at(18), at(0)), plain.at<cv::Vec3b>(at(15), at(2)));

  options.mark_loops = true;
  const cv::Mat marked = view.render(options);
  EXPECT_GT(cv::norm(marked, plain, cv::NORM_L1), 0.0);

  // Eq. 9: the loop cell white-on-black inverted (0 where distance < theta), the rest 255.
  options.threshold = 0.1;
  options.mark_loops = false;
  const cv::Mat binary = view.render(options);
  EXPECT_EQ(binary.at<cv::Vec3b>(at(15), at(2)), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(binary.at<cv::Vec3b>(at(18), at(0)), cv::Vec3b(255, 255, 255));

  options.threshold = -1;
  options.color_map = 12;
  EXPECT_THROW(view.render(options), openable::Error);
}

TEST(DistanceMatrixView, ALoopConfirmedRowsLaterIsDrawnOnItsOwnRow)
{
  // A confirmed loop closure (confirm_frames) arrives with a later row: marked rows_ago rows back, it is the
  // same picture as marked with its own row.
  DistanceMatrixView at_once(64), later(64);
  for (int t = 0; t < 20; ++t)
  {
    at_once.addRow(0, streamRow(t, 3, t == 15 ? 2 : -1));
    later.addRow(0, streamRow(t, 3, t == 15 ? 2 : -1));
    if (t == 15)
      at_once.addLoop(2);
    if (t == 18)
      later.addLoop(2, 3);
  }
  EXPECT_EQ(later.loops(), 1u);
  EXPECT_EQ(cv::norm(at_once.render({}), later.render({}), cv::NORM_L1), 0.0);
  later.addLoop(2, 20);  // before the first row: nothing to mark
  EXPECT_EQ(later.loops(), 1u);
}

TEST(DistanceMatrixView, RenderKeepsItsSizeWhileTheHistoryGrowsAndIsPooled)
{
  // The picture used to be the cells integer-upscaled: 504, 506, ... pixels, then 257 after a pooling;
  // rviz re-laid out its panel on every publish. Now it is size x size whatever the shape of the cells.
  for (const auto mode : {DistanceMatrixView::Mode::kWholeHistory, DistanceMatrixView::Mode::kRollingWindow})
  {
    DistanceMatrixView view(64, mode);
    for (int t = 0; t < 300; ++t)
    {
      view.addRow(0, streamRow(t, 3));
      const cv::Mat image = view.render({});
      ASSERT_EQ(image.rows, 64) << "frame " << t;
      ASSERT_EQ(image.cols, 64) << "frame " << t;
    }
  }
  // Localisation: a few query rows against a long map; the map's side fills the picture, the rest is black.
  DistanceMatrixView view(64);
  view.addRow(0, std::vector<float>(1000, 0.5f));
  const cv::Mat image = view.render({});
  ASSERT_EQ(image.size(), cv::Size(64, 64));
  EXPECT_EQ(image.at<cv::Vec3b>(63, 63), cv::Vec3b(0, 0, 0));
  EXPECT_NE(image.at<cv::Vec3b>(0, 63), cv::Vec3b(0, 0, 0));
}

TEST(DistanceMatrixView, ClearAndModeChangeStartOver)
{
  DistanceMatrixView view(8);
  view.addRow(0, streamRow(0, 0));
  view.addLoop(0);
  view.clear();
  EXPECT_EQ(view.rows(), 0);
  EXPECT_EQ(view.loops(), 0u);
  view.addRow(0, streamRow(0, 0));
  view.setMode(DistanceMatrixView::Mode::kRollingWindow);
  EXPECT_EQ(view.rows(), 0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
