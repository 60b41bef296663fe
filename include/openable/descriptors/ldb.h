#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

#include "openable/descriptors/descriptor_extractor.h"

namespace openable
{
/// LDB (Local Difference Binary, Yang & Cheng, TPAMI 2014) of a whole patch.
///
/// The patch is divided into 2x2, 3x3, 4x4 and 5x5 grids (cell borders at round(i * size / n)). For every
/// cell: the mean value, the mean x gradient (mean of the right half minus mean of the left half) and the
/// mean y gradient (bottom half minus top half), all from one integral image. For every pair (a, b), a < b,
/// of cells of the same grid (cells row-major) and each of the three values f: bit = f(a) < f(b).
/// Grids in order 2..5, pairs in lexicographic order, the three tests in the order mean, gx, gy:
/// 3 * (6 + 36 + 120 + 300) = 1386 bits.
constexpr int kLdbBits = 1386;

/// `values`: CV_32F (or CV_8U) patch, at least 10x10. `mask` (optional, CV_8U, non-zero = valid, same
/// size): means are taken over valid pixels only; a cell half without valid pixels has value 0.
/// Writes wordsForBits(kLdbBits) = 22 words.
void computeLdb(const cv::Mat& values, const cv::Mat& mask, uint64_t* words);

class LdbExtractor : public DescriptorExtractor
{
public:
  std::string name() const override
  {
    return "LDB";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return kLdbBits;
  }
  int minPatchSize() const override
  {
    return 10;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;
};

}  // namespace openable
