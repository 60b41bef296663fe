// HOG-B, a descriptor in one file: the class stays private to this file and the registry builds it through
// createHogBinary (its row in descriptor_registry.cpp). doc/architecture.md shows it as the example of
// adding a descriptor.
#include <algorithm>
#include <cstring>
#include <memory>

#include "descriptors/descriptor_implementations.h"

namespace openable
{
namespace
{
/// HOG-B: the compact binary signature. HOG as HogExtractor computes it (324 values), each bit 1 when its
/// value is above the descriptor's own lower median (the 162nd smallest value), so about half the bits are
/// set. 324 bits in 6 words (48 bytes a place; HOG is 1,296), matched with Hamming distance. Training-free
/// and deterministic; measured against HOG, LDB and other binarisations in doc/results.md.
class HogBinaryExtractor : public DescriptorExtractor
{
public:
  static constexpr int kBits = HogExtractor::kLength;

  explicit HogBinaryExtractor(int patch_size) : hog_(patch_size) {}
  std::string name() const override
  {
    return "HOG-B";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return kBits;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override
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

private:
  HogExtractor hog_;  // the 324 values HOG-B thresholds (HOG's own minimum patch size applies)
};
}  // namespace

std::unique_ptr<DescriptorExtractor> createHogBinary(int patch_size)
{
  return std::make_unique<HogBinaryExtractor>(patch_size);
}

}  // namespace openable
