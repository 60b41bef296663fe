// Real outcomes on real images: Gardens Point Walking (QUT; Suenderhauf et al. 2015). Image NNN is the
// same place in every traversal.
#include <gtest/gtest.h>

#include "openable/description/frame_describer.h"
#include "openable/detection/loop_detector.h"
#include "test_util.h"

using namespace openable;

namespace
{
/// Fraction of query frames whose best match is within `tolerance` frames of the same index.
double recallAtOne(const Config& config, const std::string& reference, const std::string& query, int tolerance)
{
  const FrameDescriber describer(config);
  PlaceDatabase map(describer.layout());
  for (int i = 0; i < 200; ++i)
    map.add(describer.describeImage(openable_test::gardensPoint(reference, i)));
  LoopDetector detector(config, map);
  int hits = 0;
  for (int i = 0; i < 200; ++i)
  {
    const Detection d = detector.process(describer.describeImage(openable_test::gardensPoint(query, i)));
    hits += std::abs(long(d.best.id) - i) <= tolerance;
  }
  return hits / 200.0;
}
}  // namespace

TEST(RealData, GardensPointDayLeftVsDayRightWithSequencesOfFive)
{
  Config config = Config::paper();
  config.sequence_length = 5;
  const double single = recallAtOne(Config::paper(), "day_left", "day_right", 2);
  const double sequences = recallAtOne(config, "day_left", "day_right", 2);
  RecordProperty("recall_at_1_L1", std::to_string(single));
  RecordProperty("recall_at_1_L5", std::to_string(sequences));
  // Measured on this data: 0.465 with single images (0.475 before the two-step area downsampling of the
  // preprocessor), 0.645 with L = 5 (deterministic descriptors, so a drop below these is a regression, not
  // noise).
  EXPECT_GE(single, 0.46);
  EXPECT_GE(sequences, 0.64);
}
