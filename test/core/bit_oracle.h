#pragma once

// Random descriptors and the naive bit count every Hamming kernel is checked against. Standard C++ only, so
// that the Hamming test also builds without OpenCV or ROS (scripts/cross_check_aarch64.sh).

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

namespace openable_test
{
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
