// Regression tests of the recommended configurations (config/gardens_point.yaml, config/nordland.yaml) on
// real data, through the core library as the offline tool and the nodelets use it: FrameDescriber + a
// LoopDetector in localisation mode against a reference map. The values asserted are the ones measured
// with openable_offline + openable_eval (doc/results.md); every descriptor is deterministic, so the
// margins only absorb rounding, and a drop below them is a regression.
//
// Data: Gardens Point Walking (QUT; Suenderhauf et al., "On the performance of ConvNet features for
// place recognition", 2015) and the Nordland summer/winter sample of OpenSeqSLAM2.0 (NRK, CC BY), both in
// ../shared/data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/detection/loop_detector.h"
#include "test_util.h"

using namespace openable;

namespace
{
struct Outcome
{
  int evaluated = 0;  ///< queries counted (near-black ones left out when asked)
  int hits = 0;       ///< best match within the tolerance of the same index
  double recall() const
  {
    return evaluated ? double(hits) / evaluated : 0.0;
  }
};

/// Matches every query frame against a map of the reference frames (same index = same place) and counts
/// the queries whose best match lies within `tolerance` frames. Near-black query frames (mean intensity
/// < 10, the rule of `openable_eval --mask-dark`) are matched (they still feed the sequence) but not
/// counted when `mask_dark` is set.
Outcome localise(const Config& config, const std::vector<cv::Mat>& reference, const std::vector<cv::Mat>& query,
                 int tolerance, bool mask_dark)
{
  const FrameDescriber describer(config);
  PlaceDatabase map(describer.layout());
  for (const cv::Mat& image : reference)
    map.add(describer.describeImage(image));
  LoopDetector detector(config, map);
  Outcome out;
  for (size_t i = 0; i < query.size(); ++i)
  {
    const Detection d = detector.process(describer.describeImage(query[i]));
    if (mask_dark)
    {
      cv::Mat grey;
      query[i].convertTo(grey, CV_64F);
      if (cv::mean(grey.reshape(1))[0] < 10.0)
        continue;
    }
    ++out.evaluated;
    out.hits += d.has_candidates && std::abs(long(d.best.id) - long(i)) <= tolerance;
  }
  return out;
}

std::vector<cv::Mat> gardensPointTraversal(const std::string& traversal)
{
  std::vector<cv::Mat> images;
  for (int i = 0; i < 200; ++i)
  {
    images.push_back(openable_test::gardensPoint(traversal, i));
    EXPECT_FALSE(images.back().empty()) << traversal << " frame " << i;
  }
  return images;
}

/// Nordland frames `first` .. `first + count - 1` (0-based position in the 1800-frame sequence).
std::vector<cv::Mat> nordlandTraversal(const std::string& season, int first, int count)
{
  std::vector<cv::Mat> images;
  for (int i = first; i < first + count; ++i)
  {
    char name[32];
    std::snprintf(name, sizeof(name), "/images-%05d.png", (i + 1) * 10);
    images.push_back(cv::imread(openable_test::sharedData("nordland/" + season + name), cv::IMREAD_COLOR));
    EXPECT_FALSE(images.back().empty()) << season << " frame " << i;
  }
  return images;
}

Config shipped(const std::string& name)
{
  return Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/" + name);
}
}  // namespace

TEST(RecommendedConfigs, GardensPointDayRightToNightRight)
{
  const Config config = shipped("gardens_point.yaml");
  ASSERT_EQ(config.descriptor, "HOG-B");
  const std::vector<cv::Mat> day_right = gardensPointTraversal("day_right");
  const std::vector<cv::Mat> night_right = gardensPointTraversal("night_right");
  const Outcome night = localise(config, day_right, night_right, 2, false);
  RecordProperty("recall_at_1_day_right_night_right", std::to_string(night.recall()));
  // openable_eval on openable_offline's matrix, same config (doc/results.md): recall@1 0.990 (198 of 200);
  // HOG, the descriptor before HOG-B, 0.910.
  EXPECT_EQ(night.evaluated, 200);
  EXPECT_GE(night.recall(), 0.985);
  // Issue 3's target for this pair.
  EXPECT_GE(night.recall(), 0.6);
}

TEST(RecommendedConfigs, GardensPointDayLeftToNightRight)
{
  const Config config = shipped("gardens_point.yaml");
  const Outcome shifted =
      localise(config, gardensPointTraversal("day_left"), gardensPointTraversal("night_right"), 2, false);
  RecordProperty("recall_at_1_day_left_night_right", std::to_string(shifted.recall()));
  // Measured: recall@1 0.600 (120 of 200; HOG: 0.445 with the earlier preprocessing); issue 3's target is 0.3.
  EXPECT_GE(shifted.recall(), 0.595);
}

TEST(RecommendedConfigs, NordlandSummerToWinterFirstHalf)
{
  // Frames 0 .. 899 as traversals of their own: the other half of the route, not the one the test below
  // uses. Measured with openable_offline + openable_eval --mask-dark: 0.9143 near-black masked with the pace
  // matcher (64 px patch, memory of 30 frames); 0.9209 with the diagonal sums of 50 frames on a 32 px patch.
  const Config config = shipped("nordland.yaml");
  ASSERT_EQ(config.descriptor, "HOG-B");
  const Outcome masked =
      localise(config, nordlandTraversal("summer", 0, 900), nordlandTraversal("winter", 0, 900), 1, true);
  RecordProperty("recall_at_1_masked", std::to_string(masked.recall()));
  std::printf("[ measured ] Nordland frames 0 .. 899: recall@1 %.4f (%d of %d)\n", masked.recall(), masked.hits,
              masked.evaluated);
  EXPECT_GE(masked.recall(), 0.91);
}

TEST(RecommendedConfigs, NordlandSummerToWinterSecondHalf)
{
  // Frames 900 .. 1799 (files images-09010 .. images-18000) as traversals of their own: 900 queries,
  // 32 of them near-black. A subset keeps the test short and starts both traversals mid-route.
  const Config config = shipped("nordland.yaml");
  ASSERT_EQ(config.sequence_length, 30);
  const std::vector<cv::Mat> summer = nordlandTraversal("summer", 900, 900);
  const std::vector<cv::Mat> winter = nordlandTraversal("winter", 900, 900);
  const Outcome masked = localise(config, summer, winter, 1, true);
  const Outcome all = localise(config, summer, winter, 1, false);
  RecordProperty("recall_at_1_masked", std::to_string(masked.recall()));
  RecordProperty("recall_at_1_all", std::to_string(all.recall()));
  std::printf("[ measured ] Nordland frames 900 .. 1799: recall@1 %.4f (%d of %d) masked, %.4f all\n",
              masked.recall(), masked.hits, masked.evaluated, all.recall());
  // Measured with config/nordland.yaml (the pace matcher, a memory of 30 frames): recall@1 1.000 (868 of 868)
  // with near-black queries masked and over all 900 queries. The diagonal sums of 50 frames gave 0.9435 and
  // 0.9456: their first 49 queries had no full sequence yet; the pace matcher's costs carry evidence from
  // the first frame on.
  EXPECT_EQ(masked.evaluated, 868);
  EXPECT_GE(masked.recall(), 0.995);
  EXPECT_GE(all.recall(), 0.995);
}
