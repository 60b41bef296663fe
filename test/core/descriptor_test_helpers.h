// What the descriptor tests share: configurations per descriptor, a descriptor with its normalised distance,
// real patches, fingerprints of golden values.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "openable/descriptors/descriptor_registry.h"
#include "openable/description/frame_describer.h"
#include "openable/description/preprocessor.h"
#include "openable/error.h"
#include "test_util.h"

namespace descriptor_test
{
using namespace openable;
using openable_test::gardensPoint;
using openable_test::sharedData;

const std::vector<std::string> kMonoNames = {"LDB", "BRIEF", "BRISK", "ORB", "FREAK", "SIFT", "SURF", "HOG", "HOG-B"};

inline Config configFor(const std::string& name, int patch_size = 64)
{
  Config config;
  config.descriptor = name;
  config.patch_size = patch_size;
  const DescriptorInfo* row = findDescriptor(name);
  if (row && row->needs_disparity)
    config.camera_type = "stereo";
  return config;
}

/// One descriptor, binary or float, with a distance normalised to 0..1 (Hamming / bits, or L2 of unit
/// vectors / 2), so that every descriptor's numbers read alike.
struct Described
{
  bool binary = true;
  std::vector<uint64_t> words;
  std::vector<float> values;

  double distance(const Described& o) const
  {
    if (binary)
    {
      double bits = 0;
      for (size_t i = 0; i < words.size(); ++i)
        bits += __builtin_popcountll(words[i] ^ o.words[i]);
      return bits / length;
    }
    double s = 0;
    for (size_t i = 0; i < values.size(); ++i)
      s += (values[i] - o.values[i]) * double(values[i] - o.values[i]);
    return std::sqrt(s) / 2.0;
  }
  bool operator==(const Described& o) const
  {
    return words == o.words && values == o.values;
  }
  int length = 0;
};

inline Described describe(const DescriptorExtractor& extractor, const Patch& patch)
{
  Described d;
  d.binary = extractor.isBinary();
  d.length = extractor.length();
  if (d.binary)
  {
    // One spare word filled with a marker: nothing may be written past wordsForBits(length()).
    d.words.assign(wordsForBits(d.length) + 1, 0xA5A5A5A5A5A5A5A5ULL);
    extractor.describeBinary(patch, d.words.data());
    EXPECT_EQ(d.words.back(), 0xA5A5A5A5A5A5A5A5ULL) << extractor.name() << " wrote past its words";
    d.words.pop_back();
    if (d.length % 64)
    {
      EXPECT_EQ(d.words.back() >> (d.length % 64), 0u) << extractor.name() << ": unused bits must be 0";
    }
  }
  else
  {
    std::vector<float> raw(d.length);
    extractor.describeFloat(patch, raw.data());
    double norm = 0;
    for (float v : raw)
    {
      EXPECT_TRUE(std::isfinite(v)) << extractor.name();
      norm += double(v) * v;
    }
    norm = std::sqrt(norm);
    for (float v : raw)
      d.values.push_back(norm > 0 ? static_cast<float>(v / norm) : 0.0f);
  }
  return d;
}

inline Patch patchOf(const cv::Mat& image, int patch_size = 64)
{
  Config config;
  config.patch_size = patch_size;
  return Preprocessor(config).patches(image).at(0);
}

/// FNV-1a over the bits: a golden value that changes if the pattern or the tests change.
inline uint64_t fingerprint(const std::vector<uint64_t>& words)
{
  uint64_t h = 1469598103934665603ULL;
  for (uint64_t w : words)
    for (int b = 0; b < 8; ++b)
      h = (h ^ ((w >> (8 * b)) & 0xFF)) * 1099511628211ULL;
  return h;
}

}  // namespace descriptor_test
