#include <cstring>

#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"

namespace openable
{
void DldbExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  if (patch.disparity.empty() || patch.valid.empty())
    throw Error(
        "D-LDB needs a disparity patch and its validity mask (camera_type stereo: describe a left image "
        "with its right image or disparity)");
  if (patch.disparity.type() != CV_32FC1 || patch.disparity.size() != patch.intensity.size())
    throw Error("D-LDB needs a CV_32F disparity patch of the intensity patch's size");
  if (patch.valid.type() != CV_8UC1 || patch.valid.size() != patch.intensity.size())
    throw Error("D-LDB needs a CV_8U validity mask of the intensity patch's size");

  constexpr int kWords = (kLdbBits + 63) / 64;
  std::memset(words, 0, sizeof(uint64_t) * wordsForBits(length()));
  computeLdb(patch.intensity, cv::Mat(), words);
  // Invalid disparities are left out of every cell mean (the mask), never turned into huge or zero values.
  uint64_t depth[kWords];
  computeLdb(patch.disparity, patch.valid, depth);
  // Bit-pack the disparity LDB right after the intensity one: bit i of it becomes bit kLdbBits + i.
  for (int i = 0; i < kLdbBits; ++i)
    if ((depth[i >> 6] >> (i & 63)) & 1u)
    {
      const int bit = kLdbBits + i;
      words[bit >> 6] |= uint64_t(1) << (bit & 63);
    }
}

}  // namespace openable
