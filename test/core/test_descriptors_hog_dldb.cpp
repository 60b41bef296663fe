// HOG against OpenCV, HOG-B against its naive reference and golden values, D-LDB on real stereo pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "descriptor_test_helpers.h"
#include "descriptors/descriptor_implementations.h"
#include "openable/descriptors/ldb.h"
#include "openable/description/stereo.h"

using namespace openable;
using namespace descriptor_test;

// ---------------------------------------------------------------------------------------------------------
// HOG computes its block histograms itself, from OpenCV's gradients: every value must be the float OpenCV's
// HOGDescriptor::compute gives (same weights, same order of additions), or maps saved before would drift. Every
// patch size of the shipped and tested configurations, real patches of every traversal and noise.
TEST(Hog, EqualsOpenCvsHogDescriptorBitForBit)
{
  cv::RNG rng(3);
  for (int patch_size : {16, 32, 64, 80, 128, 130})
  {
    const HogExtractor hog(patch_size);
    const int window = patch_size / 4 * 4, cell = window / 4;
    const cv::HOGDescriptor reference(cv::Size(window, window), cv::Size(2 * cell, 2 * cell), cv::Size(cell, cell),
                                      cv::Size(cell, cell), 9);
    // 8-bit images spanning 0 .. 255, so that the extractor's own stretch to 8 bits gives them back.
    std::vector<cv::Mat> images;
    for (const auto& [traversal, frame] : std::vector<std::pair<std::string, int>>{
             {"day_left", 10}, {"day_right", 77}, {"night_right", 0}, {"night_right", 150}})
    {
      images.emplace_back();
      cv::normalize(patchOf(gardensPoint(traversal, frame), patch_size).intensity, images.back(), 0, 255,
                    cv::NORM_MINMAX, CV_8U);
    }
    images.emplace_back(patch_size, patch_size, CV_8U);
    rng.fill(images.back(), cv::RNG::UNIFORM, 0, 256);
    images.back().at<uint8_t>(0, 0) = 0, images.back().at<uint8_t>(0, 1) = 255;
    for (const cv::Mat& image : images)
    {
      Patch patch;
      image.convertTo(patch.intensity, CV_32F);
      std::vector<float> values(324), expected;
      hog.describeFloat(patch, values.data());
      cv::Mat window_image = image;
      if (window != patch_size)
        cv::resize(image, window_image, cv::Size(window, window), 0, 0, cv::INTER_AREA);
      reference.compute(window_image, expected);
      ASSERT_EQ(expected.size(), values.size());
      for (size_t i = 0; i < values.size(); ++i)
        ASSERT_EQ(values[i], expected[i]) << "patch " << patch_size << ", value " << i;  // exact, not near
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// HOG-B against a naive reference: HOG's 324 values fully sorted, the 162nd smallest as the threshold, one bit
// per value in order. On real patches of every traversal (day, night, left, right).
TEST(HogB, IsHogAboveItsOwnLowerMedian)
{
  const HogExtractor hog(128);
  const auto hog_b_extractor = descriptorInfo("HOG-B").create(128);
  const DescriptorExtractor& hog_b = *hog_b_extractor;
  for (const auto& [traversal, frame] : std::vector<std::pair<std::string, int>>{
           {"day_left", 10}, {"day_right", 77}, {"night_right", 0}, {"night_right", 150}})
  {
    const Patch patch = patchOf(gardensPoint(traversal, frame), 128);
    std::vector<float> values(324);
    hog.describeFloat(patch, values.data());
    std::vector<float> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    std::vector<uint64_t> expected(6, 0);
    int ones = 0;
    for (int i = 0; i < 324; ++i)
      if (values[i] > sorted[161])
      {
        expected[i / 64] |= uint64_t(1) << (i % 64);
        ++ones;
      }
    const Described d = describe(hog_b, patch);  // also checks the spare word and the unused bits
    EXPECT_EQ(d.words, expected) << traversal << " " << frame;
    // Half of the bits set: at most 162 (values above the 162nd smallest), fewer only through ties.
    EXPECT_LE(ones, 162);
    EXPECT_GE(ones, 150) << traversal << " " << frame;
  }
}

// Golden values: a map saved with HOG-B must keep matching on every machine and build. The synthetic patch
// comes from integer arithmetic only; the real one through the JPEG decoder and the preprocessor.
TEST(HogB, IsPinned)
{
  Patch synthetic;
  synthetic.intensity.create(64, 64, CV_32F);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      synthetic.intensity.at<float>(y, x) = float(((x * 7 + y * 13) % 31) * 4 + (x * y) % 17 + 2 * x);
  const uint64_t synthetic_print = fingerprint(describe(*descriptorInfo("HOG-B").create(64), synthetic).words);
  const uint64_t real_print =
      fingerprint(describe(*descriptorInfo("HOG-B").create(128), patchOf(gardensPoint("day_left", 10), 128)).words);
  std::printf("[ golden ] HOG-B fingerprints: synthetic 0x%016llx, day_left 10 0x%016llx\n",
              static_cast<unsigned long long>(synthetic_print), static_cast<unsigned long long>(real_print));
  EXPECT_EQ(synthetic_print, 0x003854793f580529ULL);
  EXPECT_EQ(real_print, 0xe6771c1d88bdb6edULL);
}

// ---------------------------------------------------------------------------------------------------------
namespace openable_test
{
/// Defined in test_stereo.cpp: a EuRoC pair rectified with its calibration.
void eurocRectifiedPair(int pair, cv::Mat* left, cv::Mat* right);
}  // namespace openable_test

namespace
{
std::vector<Patch> stereoPatches(int pair, const Config& config)
{
  cv::Mat left, right;
  openable_test::eurocRectifiedPair(pair, &left, &right);
  EXPECT_FALSE(left.empty());
  return Preprocessor(config).patchesWithDisparity(left, disparityFromPair(left, right, config));
}
}  // namespace

TEST(Dldb, IsLdbOfIntensityThenLdbOfValidDisparityBitPacked)
{
  const Config config = configFor("D-LDB");
  const Patch patch = stereoPatches(2, config).at(0);
  ASSERT_FALSE(patch.disparity.empty());
  const auto extractor = createDescriptorExtractor(config);
  const Described d = describe(*extractor, patch);
  ASSERT_EQ(d.words.size(), 44u);

  uint64_t grey[22], depth[22];
  computeLdb(patch.intensity, cv::Mat(), grey);
  computeLdb(patch.disparity, patch.valid, depth);
  auto bit = [](const uint64_t* w, int i) { return (w[i >> 6] >> (i & 63)) & 1u; };
  for (int i = 0; i < kLdbBits; ++i)
  {
    ASSERT_EQ(bit(d.words.data(), i), bit(grey, i)) << i;
    ASSERT_EQ(bit(d.words.data(), kLdbBits + i), bit(depth, i)) << i;
  }
  // Invalid disparities are masked: whatever value they hold, the descriptor does not change.
  Patch poisoned = patch;
  poisoned.disparity = patch.disparity.clone();
  poisoned.disparity.setTo(1e30f, patch.valid == 0);
  ASSERT_GT(cv::countNonZero(patch.valid == 0), 0);
  EXPECT_TRUE(describe(*extractor, poisoned) == d);
  // The disparity half carries information: changing depth alone changes it.
  Patch nearer = patch;
  nearer.disparity = patch.disparity.clone();
  nearer.disparity(cv::Rect(0, 0, 32, 64)) += 20.0f;
  EXPECT_GT(d.distance(describe(*extractor, nearer)), 0.0);
}

// Grid mode: every cell gets its own intensity and disparity LDB, through the FrameDescriber as the tools use it.
TEST(Dldb, DescribesEveryCellOfAGrid)
{
  Config config = configFor("D-LDB", 32);
  config.description_type = "grid";
  config.grid_x = 3;
  config.grid_y = 2;
  const FrameDescriber describer(config);
  ASSERT_EQ(describer.layout().cells, 6);
  ASSERT_EQ(describer.layout().cell_words, 44);
  cv::Mat left, right;
  openable_test::eurocRectifiedPair(0, &left, &right);
  const auto patches = describer.preprocessor().patchesWithDisparity(left, disparityFromPair(left, right, config));
  const FrameDescriptor a = describer.describe(patches);
  EXPECT_EQ(a, describer.describe(patches));
  for (int cell = 0; cell < 6; ++cell)  // the disparity half of every cell holds bits
  {
    int disparity_bits = 0;
    for (int i = kLdbBits; i < 2 * kLdbBits; ++i)
      disparity_bits += (a[cell * 44 + (i >> 6)] >> (i & 63)) & 1u;
    EXPECT_GT(disparity_bits, 0) << "cell " << cell;
  }
}

TEST(Dldb, RejectsPatchesWithoutDisparity)
{
  const auto extractor = createDescriptorExtractor(configFor("D-LDB"));
  Patch patch = patchOf(gardensPoint("day_left", 0));
  std::vector<uint64_t> words(44);
  EXPECT_THROW(extractor->describeBinary(patch, words.data()), Error);
  patch.disparity = cv::Mat(64, 64, CV_32F, cv::Scalar(5));
  patch.valid = cv::Mat(32, 32, CV_8U, cv::Scalar(255));
  EXPECT_THROW(extractor->describeBinary(patch, words.data()), Error);
}

// EuRoC V1_01: pair 0 revisits the place of pair 1 about 98 s later; pairs 2 and 3 are elsewhere.
TEST(Dldb, EurocRevisitIsTheNearestPair)
{
  const Config config = configFor("D-LDB");
  const auto extractor = createDescriptorExtractor(config);
  std::vector<Described> pairs;
  for (int k = 0; k < 4; ++k)
    pairs.push_back(describe(*extractor, stereoPatches(k, config).at(0)));
  std::printf("[ measured ] D-LDB distance pair 0 -> 1, 2, 3: %.4f %.4f %.4f\n", pairs[0].distance(pairs[1]),
              pairs[0].distance(pairs[2]), pairs[0].distance(pairs[3]));
  // For comparison, the intensity half alone (plain LDB).
  Config mono = configFor("LDB");
  const auto ldb = createDescriptorExtractor(mono);
  std::vector<Described> grey;
  for (int k = 0; k < 4; ++k)
    grey.push_back(describe(*ldb, stereoPatches(k, config).at(0)));
  std::printf("[ measured ] LDB distance pair 0 -> 1, 2, 3: %.4f %.4f %.4f\n", grey[0].distance(grey[1]),
              grey[0].distance(grey[2]), grey[0].distance(grey[3]));
  EXPECT_LT(pairs[0].distance(pairs[1]), pairs[0].distance(pairs[2]));
  EXPECT_LT(pairs[0].distance(pairs[1]), pairs[0].distance(pairs[3]));
}

// descriptor_bits: a binary descriptor keeps that many of its bits, evenly spread. Known answer on one word, and
// against a naive reference (each kept bit read one at a time from the whole descriptor) on real HOG-B.
TEST(DescriptorBits, KeepsBitsEvenlySpread)
{
  const uint64_t all[1] = {0xB3u};  // bits 0, 1, 4, 5, 7
  uint64_t kept[1] = {0};
  keepBitsEvenly(all, 8, kept, 4);  // bits 0, 2, 4, 6 of all
  EXPECT_EQ(kept[0], 0x5u);         // 1, 0, 1, 0
  uint64_t same[1] = {0};
  keepBitsEvenly(all, 8, same, 8);
  EXPECT_EQ(same[0], all[0]);
}

TEST(DescriptorBits, ARealHogBKeepsTheNaivelySelectedBitsAndFewerBytes)
{
  Config whole = configFor("HOG-B");
  Config fewer = whole;
  fewer.descriptor_bits = 128;
  const FrameDescriber all_bits(whole), some_bits(fewer);
  ASSERT_EQ(some_bits.layout().cell_length, 128);
  ASSERT_EQ(some_bits.layout().cell_words, 2);  // 16 bytes a place instead of 48
  EXPECT_EQ(descriptorLayout(fewer), some_bits.layout());
  for (int frame : {0, 77, 150})
  {
    const cv::Mat image = gardensPoint("day_left", frame);
    const FrameDescriptor a = all_bits.describeImage(image), k = some_bits.describeImage(image);
    ASSERT_EQ(k.size(), 2u);
    for (int j = 0; j < 128; ++j)
    {
      const int from = j * 324 / 128;
      EXPECT_EQ((k[j / 64] >> (j % 64)) & 1u, (a[from / 64] >> (from % 64)) & 1u) << "bit " << j;
    }
  }
}

TEST(DescriptorBits, RefusesMoreBitsThanTheDescriptorHasAndAFloatDescriptor)
{
  Config c = configFor("HOG-B");
  c.descriptor_bits = 325;
  EXPECT_FALSE(c.problems().empty());
  c.descriptor_bits = 324;
  EXPECT_TRUE(c.problems().empty());
  c.view_channel_bits = 400;
  ASSERT_EQ(c.validate().size(), 1u);
  EXPECT_NE(c.validate()[0].find("view_channel_bits"), std::string::npos) << c.validate()[0];
  Config hog = configFor("HOG");
  ASSERT_GT(hog.view_channel_bits, 0);
  EXPECT_TRUE(hog.problems().empty());  // a float descriptor's view channel keeps every value
  EXPECT_EQ(hog.viewChannel().descriptor_bits, 0);
  hog.descriptor_bits = 100;
  ASSERT_EQ(hog.validate().size(), 1u);
  EXPECT_NE(hog.validate()[0].find("float descriptor"), std::string::npos) << hog.validate()[0];
  EXPECT_THROW(FrameDescriber{hog}, Error);
}
