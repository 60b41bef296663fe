#pragma once

#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

namespace openable_test
{
/// Real data beside the repository (../shared/data), as on developer machines and in CI.
inline std::string sharedData(const std::string& relative)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/../shared/data/" + relative;
}

/// Data bundled with the package (data/sample).
inline std::string sampleData(const std::string& relative)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/data/sample/" + relative;
}

/// Gardens Point frame `index` of a traversal (day_left, day_right, night_right).
inline cv::Mat gardensPoint(const std::string& traversal, int index)
{
  char name[32];
  std::snprintf(name, sizeof(name), "/Image%03d.jpg", index);
  return cv::imread(sharedData("gardens_point/" + traversal + name), cv::IMREAD_COLOR);
}

inline std::vector<uint64_t> randomWords(std::mt19937_64& rng, size_t words)
{
  std::vector<uint64_t> out(words);
  for (auto& w : out)
    w = rng();
  return out;
}

/// Bit count the slow, obvious way: the reference every kernel is checked against.
inline uint32_t naiveBitCount(const uint64_t* a, const uint64_t* b, size_t words)
{
  uint32_t n = 0;
  for (size_t i = 0; i < words; ++i)
    for (int bit = 0; bit < 64; ++bit)
      n += ((a[i] ^ b[i]) >> bit) & 1u;
  return n;
}

}  // namespace openable_test
