#include <algorithm>
#include <cstring>
#include <vector>

#include "descriptors/descriptor_implementations.h"

namespace openable
{
HogBinaryExtractor::HogBinaryExtractor(int patch_size) : hog_(patch_size) {}

void HogBinaryExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  float values[kBits];
  hog_.describeFloat(patch, values);
  // The threshold is the descriptor's own lower median (the 162nd smallest of 324 values): no training, no
  // random choice, and the same on every machine. Comparing with it keeps which bins carry more than half
  // of the gradient mass and forgets by how much, which is what survives day -> night (doc/results.md).
  float sorted[kBits];
  std::memcpy(sorted, values, sizeof(values));
  std::nth_element(sorted, sorted + kBits / 2 - 1, sorted + kBits);
  const float median = sorted[kBits / 2 - 1];
  std::memset(words, 0, sizeof(uint64_t) * wordsForBits(kBits));
  for (int i = 0; i < kBits; ++i)
    words[i / 64] |= uint64_t(values[i] > median) << (i % 64);
}

}  // namespace openable
