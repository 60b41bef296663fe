// Every descriptor of issue 3: the registry, factory, determinism, known properties, real images, patch sizes,
// bad input.
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

namespace
{
class EveryDescriptor : public ::testing::TestWithParam<std::string>
{
};
}  // namespace

// ---------------------------------------------------------------------------------------------------------
TEST(DescriptorFactory, BuildsEveryNameWithItsLength)
{
  const std::map<std::string, int> lengths = {{"LDB", 1386}, {"D-LDB", 2772}, {"BRIEF", 256}, {"BRISK", 512},
                                              {"ORB", 256},  {"FREAK", 512},  {"SIFT", 128},  {"SURF", 64},
                                              {"HOG", 324},  {"HOG-B", 324}};
  ASSERT_EQ(descriptorNames().size(), lengths.size());
  for (const auto& name : descriptorNames())
  {
    const Config config = configFor(name);
    const auto extractor = createDescriptorExtractor(config);
    ASSERT_TRUE(extractor) << name;
    EXPECT_EQ(extractor->name(), name);
    EXPECT_EQ(extractor->isBinary(), descriptorInfo(name).binary()) << name;
    EXPECT_EQ(extractor->length(), lengths.at(name)) << name;
  }
}

// Every row of the registry says what its extractor does: form, length, the smallest patch (built there,
// refused below it), and the layout derived from the row alone equals the one FrameDescriber builds.
TEST(DescriptorRegistry, EveryRowMatchesItsExtractor)
{
  ASSERT_FALSE(descriptorRegistry().empty());
  for (const DescriptorInfo& row : descriptorRegistry())
  {
    SCOPED_TRACE(row.name);
    const auto extractor = row.create(64);
    ASSERT_TRUE(extractor);
    EXPECT_EQ(extractor->name(), row.name);
    EXPECT_EQ(extractor->isBinary(), row.binary());
    EXPECT_EQ(extractor->length(), row.length);
    EXPECT_EQ(extractor->minPatchSize(), row.min_patch_size);
    EXPECT_TRUE(row.create(row.min_patch_size));
    Config config = configFor(row.name);
    EXPECT_EQ(descriptorLayout(config), FrameDescriber(config).layout());
    config.patch_size = row.min_patch_size - 1;
    try
    {
      createDescriptorExtractor(config);
      ADD_FAILURE() << "patch_size " << config.patch_size << " was accepted";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find("patch_size"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(findDescriptor("SUFR"), nullptr);
  EXPECT_THROW(descriptorInfo("SUFR"), Error);
  EXPECT_EQ(descriptorNames().size(), descriptorRegistry().size());
}

// Names and rules come from the rows: a descriptor that needs disparity is refused outside stereo by
// validation, with the reason.
TEST(DescriptorRegistry, ValidationFollowsTheRows)
{
  for (const DescriptorInfo& row : descriptorRegistry())
  {
    Config mono;
    mono.descriptor = row.name;
    const auto errors = mono.validate();
    if (!row.needs_disparity)
    {
      EXPECT_TRUE(errors.empty()) << row.name;
      continue;
    }
    ASSERT_EQ(errors.size(), 1u) << row.name;
    EXPECT_NE(errors[0].find("needs camera_type stereo"), std::string::npos) << errors[0];
  }
}

TEST(DescriptorFactory, RejectsUnknownNamesAndDldbInMono)
{
  try
  {
    createDescriptorExtractor(configFor("SUFR"));
    FAIL() << "expected Error";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("SUFR"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("BRISK"), std::string::npos) << e.what();  // lists valid names
  }
  Config mono = configFor("D-LDB");
  mono.camera_type = "mono";
  EXPECT_THROW(createDescriptorExtractor(mono), Error);
}

// ---------------------------------------------------------------------------------------------------------
TEST_P(EveryDescriptor, IsDeterministicAndAtDistanceZeroFromItself)
{
  const cv::Mat image = gardensPoint("day_left", 10);
  ASSERT_FALSE(image.empty());
  const Patch patch = patchOf(image);
  // Two independently built extractors, several calls: the same bits / values every time.
  const auto a = createDescriptorExtractor(configFor(GetParam()));
  const auto b = createDescriptorExtractor(configFor(GetParam()));
  const Described first = describe(*a, patch);
  for (int i = 0; i < 3; ++i)
    EXPECT_TRUE(describe(*b, patch) == first);
  EXPECT_EQ(first.distance(describe(*a, patch)), 0.0);
  // Not degenerate: a different place gives a different descriptor.
  const Described other = describe(*a, patchOf(gardensPoint("day_left", 150)));
  EXPECT_GT(first.distance(other), 0.05) << GetParam();
}

// A camera 5 grey levels brighter (added to the 8-bit image, so bright sky saturates: not a pure offset)
// moves every descriptor far less than going to another place does. Measured over day_left frames 0..195
// step 15 against frame i + 100: the worst ratio of the two distances, per descriptor.
TEST_P(EveryDescriptor, BrightnessChangeIsSmallComparedToAnotherPlace)
{
  // Measured (rounded up at the 4th decimal). Every descriptor is invariant to a pure offset; what is left
  // comes from the saturated pixels. HOG-B's bits flip where two bins are nearly equal: the largest ratio.
  const std::map<std::string, double> measured_worst_ratio = {{"LDB", 0.0037},  {"BRIEF", 0.0102}, {"BRISK", 0.0086},
                                                              {"ORB", 0.0181},  {"FREAK", 0.0068}, {"SIFT", 0.0158},
                                                              {"SURF", 0.0097}, {"HOG", 0.0296},   {"HOG-B", 0.0456}};
  const auto extractor = createDescriptorExtractor(configFor(GetParam()));
  double worst_ratio = 0.0;
  for (int i = 0; i < 200; i += 15)
  {
    const cv::Mat image = gardensPoint("day_left", i);
    cv::Mat brighter;
    cv::add(image, cv::Scalar::all(5), brighter);  // saturates at 255
    const Described base = describe(*extractor, patchOf(image));
    const double brightness = base.distance(describe(*extractor, patchOf(brighter)));
    const double other_place = base.distance(describe(*extractor, patchOf(gardensPoint("day_left", (i + 100) % 200))));
    ASSERT_GT(other_place, 0.0);
    worst_ratio = std::max(worst_ratio, brightness / other_place);
  }
  std::printf("[ measured ] %s brightness +5 / other place, worst: %.4f\n", GetParam().c_str(), worst_ratio);
  EXPECT_LE(worst_ratio, measured_worst_ratio.at(GetParam()));
}

// Gardens Point day_left frame i against day_right (the same path walked on the other side), 40 frames
// (every 5th). Two measured numbers per descriptor, grey 64 px patches:
// - pairs: of all (i, j) with j another place (|i - j| >= 10 frames), how often day_right i is closer to
//   day_left i than day_right j is ("the same frame is closer than different frames");
// - hits: how many of the 40 find exactly their own frame as nearest of the 40 (much stricter: neighbours
//   5 frames away look alike, and the traversals are laterally shifted).
TEST_P(EveryDescriptor, RealImagesFindTheSamePlaceAcrossTraversals)
{
  // Measured: { pairs fraction (rounded down at the 4th decimal), hits of 40 }.
  const std::map<std::string, std::pair<double, int>> measured = {
      {"LDB", {0.9129, 16}},  {"BRIEF", {0.8421, 12}}, {"BRISK", {0.8751, 12}},
      {"ORB", {0.8832, 12}},  {"FREAK", {0.7745, 8}},  {"SIFT", {0.9568, 26}},
      {"SURF", {0.8299, 15}}, {"HOG", {0.9223, 21}},   {"HOG-B", {0.8846, 16}}};
  const auto extractor = createDescriptorExtractor(configFor(GetParam()));
  std::vector<Described> left, right;
  std::vector<Patch> left_patches, right_patches;
  for (int i = 0; i < 200; i += 5)
  {
    left_patches.push_back(patchOf(gardensPoint("day_left", i)));
    right_patches.push_back(patchOf(gardensPoint("day_right", i)));
  }
  const int64 start = cv::getTickCount();
  for (size_t i = 0; i < left_patches.size(); ++i)
  {
    left.push_back(describe(*extractor, left_patches[i]));
    right.push_back(describe(*extractor, right_patches[i]));
  }
  const double us_per_patch = 1e6 * (cv::getTickCount() - start) / cv::getTickFrequency() / (2.0 * left.size());
  int hits = 0, closer = 0, compared = 0;
  for (size_t i = 0; i < left.size(); ++i)
  {
    const double same = left[i].distance(right[i]);
    size_t best = 0;
    for (size_t j = 0; j < right.size(); ++j)
    {
      const double d = left[i].distance(right[j]);
      if (d < left[i].distance(right[best]))
        best = j;
      if (std::abs(int(i) - int(j)) * 5 >= 10)
      {
        closer += same < d;
        ++compared;
      }
    }
    hits += best == i;
  }
  const double fraction = double(closer) / compared;
  std::printf(
      "[ measured ] %s day_left -> day_right: same frame closer than another place in %.4f of pairs; "
      "nearest is the same frame for %d / %zu; %.0f us per patch\n",
      GetParam().c_str(), fraction, hits, left.size(), us_per_patch);
  EXPECT_GE(fraction, measured.at(GetParam()).first);
  EXPECT_GE(hits, measured.at(GetParam()).second);
}

// Every patch size gives a descriptor of the right length, or (below minPatchSize) a clear Error; OpenCV must
// never silently drop the centre keypoint.
TEST_P(EveryDescriptor, EveryPatchSizeGivesADescriptorOrAClearError)
{
  const cv::Mat image = gardensPoint("day_right", 42);
  for (int size : {8, 9, 12, 15, 16, 17, 24, 31, 32, 48, 63, 64, 100, 128, 256})
  {
    const Config config = configFor(GetParam(), size);
    std::unique_ptr<DescriptorExtractor> extractor;
    try
    {
      extractor = createDescriptorExtractor(config);
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find("patch_size"), std::string::npos) << e.what();
      continue;
    }
    EXPECT_GE(size, extractor->minPatchSize());
    const Described d = describe(*extractor, patchOf(image, size));
    const Described other = describe(*extractor, patchOf(gardensPoint("day_right", 160), size));
    EXPECT_GT(d.distance(other), 0.0) << GetParam() << " at patch_size " << size;
  }
}

TEST_P(EveryDescriptor, RejectsBadPatches)
{
  const auto extractor = createDescriptorExtractor(configFor(GetParam()));
  auto run = [&](const Patch& p)
  {
    std::vector<uint64_t> words(64);
    std::vector<float> values(1024);
    if (extractor->isBinary())
      extractor->describeBinary(p, words.data());
    else
      extractor->describeFloat(p, values.data());
  };
  Patch empty;
  EXPECT_THROW(run(empty), Error);
  Patch eight;
  eight.intensity = cv::Mat(64, 64, CV_8UC3, cv::Scalar(1, 2, 3));
  EXPECT_THROW(run(eight), Error);
  if (GetParam() != "LDB")  // LDB describes any size >= 10 by design; the others are built for one size
  {
    Patch wrong_size;
    wrong_size.intensity = cv::Mat(48, 64, CV_32F, cv::Scalar(3));
    EXPECT_THROW(run(wrong_size), Error);
    Patch nan = patchOf(gardensPoint("day_left", 0));
    nan.intensity.at<float>(30, 30) = std::nanf("");
    EXPECT_THROW(run(nan), Error);
  }
  // The wrong form: binary extractors have no float form and vice versa.
  const Patch good = patchOf(gardensPoint("day_left", 0));
  std::vector<uint64_t> words(64);
  std::vector<float> values(1024);
  if (extractor->isBinary())
    EXPECT_THROW(extractor->describeFloat(good, values.data()), Error);
  else
    EXPECT_THROW(extractor->describeBinary(good, words.data()), Error);
}

TEST_P(EveryDescriptor, FlatPatchIsDescribedWithoutNaN)
{
  const auto extractor = createDescriptorExtractor(configFor(GetParam()));
  Patch flat;
  flat.intensity = cv::Mat(64, 64, CV_32F, cv::Scalar(77));
  const Described d = describe(*extractor, flat);  // describe() checks finiteness
  EXPECT_EQ(d.distance(d), 0.0);
}

// ---------------------------------------------------------------------------------------------------------
// Upright: the paper describes the patch without rotation. A patch turned by 180 degrees must give a very
// different descriptor; a rotation-invariant one (OpenCV's BRISK without the no-long-pairs pattern) would
// give nearly the same. Measured distances (normalised) in the comments.
TEST(Upright, HalfTurnChangesTheDescriptor)
{
  const Patch patch = patchOf(gardensPoint("day_left", 60));
  Patch turned;
  cv::rotate(patch.intensity, turned.intensity, cv::ROTATE_180);
  // Measured (rounded down at the 4th decimal).
  const std::map<std::string, double> measured = {{"BRIEF", 0.4257}, {"BRISK", 0.5214}, {"ORB", 0.2968},
                                                  {"FREAK", 0.6776}, {"SIFT", 0.2640},  {"SURF", 0.2139}};
  for (const auto& [name, expected] : measured)
  {
    const auto extractor = createDescriptorExtractor(configFor(name));
    const double d = describe(*extractor, patch).distance(describe(*extractor, turned));
    std::printf("[ measured ] %s half turn distance %.4f\n", name.c_str(), d);
    EXPECT_GE(d, expected) << name;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Golden values of the own patterns: they must not change between machines or builds (maps saved with them
// would silently stop matching).
TEST(OwnPatterns, AreFixed)
{
  const auto& unit = BriefExtractor::unitPattern();
  ASSERT_EQ(unit.size(), 4u * 256u);
  for (float c : unit)
  {
    EXPECT_GE(c, -0.5f);
    EXPECT_LT(c, 0.5f);
  }
  std::printf("[ golden ] BRIEF first pair %.9g %.9g %.9g %.9g\n", unit[0], unit[1], unit[2], unit[3]);
  EXPECT_EQ(unit[0], -0.0439449959f);
  EXPECT_EQ(unit[1], 0.179408923f);
  EXPECT_EQ(unit[2], -0.0401613228f);
  EXPECT_EQ(unit[3], -0.315773875f);

  const auto& pairs = FreakExtractor::pairs();
  ASSERT_EQ(pairs.size(), 512u);
  FreakExtractor freak(64);
  ASSERT_EQ(freak.fields().size(), 43u);
  for (const auto& p : pairs)
    EXPECT_LE(std::abs(freak.fields()[p.first].ring - freak.fields()[p.second].ring), 2);
  // Coarse to fine: the first pair lies on the outermost ring.
  EXPECT_EQ(freak.fields()[pairs.front().first].ring, 7);
  EXPECT_EQ(freak.fields()[pairs.front().second].ring, 7);
  for (const auto& f : freak.fields())  // every field inside the patch
  {
    EXPECT_GE(f.x - f.sigma, -1e-9);
    EXPECT_LE(f.x + f.sigma, 64 + 1e-9);
  }

  // A synthetic patch from integer arithmetic only (no JPEG decoder, no resampling), so these values must be
  // the same on every machine.
  Patch patch;
  patch.intensity.create(64, 64, CV_32F);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      patch.intensity.at<float>(y, x) = float(((x * 7 + y * 13) % 31) * 4 + (x * y) % 17 + 2 * x);
  const std::map<std::string, uint64_t> golden = {{"BRIEF", 0x72aafd52329161a1ULL}, {"FREAK", 0x988afd9c3fb0f60aULL}};
  for (const auto& [name, expected] : golden)
  {
    const auto extractor = createDescriptorExtractor(configFor(name));
    const uint64_t print = fingerprint(describe(*extractor, patch).words);
    std::printf("[ golden ] %s fingerprint 0x%016llx\n", name.c_str(), static_cast<unsigned long long>(print));
    EXPECT_EQ(print, expected) << name;
  }
  float surf[64];
  SurfExtractor(64).describeFloat(patch, surf);
  std::printf("[ golden ] SURF %.7f %.7f %.7f %.7f\n", surf[0], surf[1], surf[2], surf[3]);
  EXPECT_NEAR(surf[0], 0.0049571, 1e-6);
  EXPECT_NEAR(surf[1], 0.0053346, 1e-6);
  EXPECT_NEAR(surf[2], -0.0014645, 1e-6);
  EXPECT_NEAR(surf[3], 0.0042913, 1e-6);
}

// The OpenCV descriptors see the patch through one 8-bit rule, a per-patch min-max stretch: an affine change
// of the intensities (gain 0.5, offset -40, e.g. the scale of Eq. 6 values is arbitrary) gives the same 8-bit
// image and so exactly the same descriptor.
TEST(EightBitRule, AffineIntensityChangeGivesTheSameOpenCvDescriptor)
{
  const Patch patch = patchOf(gardensPoint("day_left", 33));
  Patch changed;
  patch.intensity.convertTo(changed.intensity, CV_32F, 0.5, -40.0);
  for (const std::string name : {"ORB", "BRISK", "SIFT", "HOG", "HOG-B"})
  {
    const auto extractor = createDescriptorExtractor(configFor(name));
    EXPECT_EQ(describe(*extractor, patch).distance(describe(*extractor, changed)), 0.0) << name;
  }
}

// The illumination-invariant image (Eq. 6) has values around 0, often negative: every descriptor describes it
// (the OpenCV ones through the min-max stretch to 8 bits) and still tells places apart.
TEST_P(EveryDescriptor, DescribesIlluminationInvariantPatches)
{
  Config config = configFor(GetParam());
  config.illumination_invariance = true;
  const Preprocessor preprocessor(config);
  const auto extractor = createDescriptorExtractor(config);
  const Patch a = preprocessor.patches(gardensPoint("day_right", 20)).at(0);
  const Patch b = preprocessor.patches(gardensPoint("day_right", 120)).at(0);
  double low = 0, high = 0;
  cv::minMaxLoc(a.intensity, &low, &high);
  ASSERT_LT(high - low, 10.0);  // far from the 0..255 grey range
  const Described da = describe(*extractor, a);
  EXPECT_EQ(da.distance(describe(*extractor, a)), 0.0);
  EXPECT_GT(da.distance(describe(*extractor, b)), 0.05) << GetParam();
}

// HOG-B becomes HOG_B: gtest names allow letters, digits and underscores only.
INSTANTIATE_TEST_SUITE_P(Descriptors, EveryDescriptor, ::testing::ValuesIn(kMonoNames),
                         [](const ::testing::TestParamInfo<std::string>& info)
                         {
                           std::string name = info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });
