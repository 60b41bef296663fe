// The DescriptorExtractor implementations besides LDB (openable/ldb.h), one class per descriptor; their
// code is in src/core/descriptors/. Most callers need only the interface and the factory,
// openable/descriptor_extractor.h.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "openable/descriptors/descriptor_extractor.h"
#include "openable/descriptors/ldb.h"

namespace openable
{
/// The descriptors the paper offers besides LDB. Every one describes the whole patch with its keypoint at
/// the patch centre, upright and at one fixed scale tied to patch_size, and is deterministic. Each is built
/// for one patch_size (its pattern or window is scaled to it) and throws Error for a patch of another size.
/// The vector descriptors (SURF, SIFT, HOG) write raw values; FrameDescriber scales them to unit length.

/// BRIEF (Calonder et al., ECCV 2010): Gaussian-smoothed patch, 256 intensity tests on a fixed pattern.
class BriefExtractor : public DescriptorExtractor
{
public:
  static constexpr int kBits = 256;
  explicit BriefExtractor(int patch_size);
  std::string name() const override
  {
    return "BRIEF";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return kBits;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;

  /// The fixed pattern in patch units: x1, y1, x2, y2 of each pair in [-0.5, 0.5).
  static const std::vector<float>& unitPattern();

private:
  int patch_size_;
  std::vector<int> points_;  ///< x1, y1, x2, y2 per pair, pixels of a patch_size patch
  std::vector<double> kernel_;
};

/// FREAK (Alahi et al., CVPR 2012): 43 receptive fields on 7 rings whose smoothing grows with the radius,
/// 512 fixed pairs of fields compared coarse to fine.
class FreakExtractor : public DescriptorExtractor
{
public:
  static constexpr int kBits = 512;
  static constexpr int kFields = 43;
  explicit FreakExtractor(int patch_size);
  std::string name() const override
  {
    return "FREAK";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return kBits;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;

  struct Field
  {
    double x, y;   ///< centre, patch pixels
    double sigma;  ///< half side of the averaging box, patch pixels
    int ring;      ///< 0 = centre field, 1 = innermost ring .. 7 = outermost
  };
  const std::vector<Field>& fields() const
  {
    return fields_;
  }
  /// The fixed 512 pairs (field indices), in bit order.
  static const std::vector<std::pair<int, int>>& pairs();

private:
  int patch_size_;
  std::vector<Field> fields_;
};

/// Upright SURF-64 (Bay et al., CVIU 2008) of one keypoint at the patch centre, scale s = patch_size / 20 so
/// that the 20s descriptor window is the patch.
class SurfExtractor : public DescriptorExtractor
{
public:
  static constexpr int kLength = 64;
  explicit SurfExtractor(int patch_size);
  std::string name() const override
  {
    return "SURF";
  }
  bool isBinary() const override
  {
    return false;
  }
  int length() const override
  {
    return kLength;
  }
  void describeFloat(const Patch& patch, float* values) const override;

private:
  int patch_size_;
};

/// OpenCV's ORB (256 bits), upright, its sampling pattern spanning the patch.
class OrbExtractor : public DescriptorExtractor
{
public:
  explicit OrbExtractor(int patch_size);
  std::string name() const override
  {
    return "ORB";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return 256;
  }
  int minPatchSize() const override
  {
    return 16;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;

private:
  int patch_size_;
  cv::Ptr<cv::Feature2D> orb_;
};

/// OpenCV's BRISK (512 bits), upright, its sampling pattern spanning the patch.
class BriskExtractor : public DescriptorExtractor
{
public:
  explicit BriskExtractor(int patch_size);
  std::string name() const override
  {
    return "BRISK";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return 512;
  }
  int minPatchSize() const override
  {
    return 16;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;

private:
  int patch_size_;
  cv::Ptr<cv::Feature2D> brisk_;
};

/// OpenCV's SIFT (128 floats), upright, its 4x4 histogram window spanning the patch.
class SiftExtractor : public DescriptorExtractor
{
public:
  explicit SiftExtractor(int patch_size);
  std::string name() const override
  {
    return "SIFT";
  }
  bool isBinary() const override
  {
    return false;
  }
  int length() const override
  {
    return 128;
  }
  int minPatchSize() const override
  {
    return 16;
  }
  void describeFloat(const Patch& patch, float* values) const override;

private:
  int patch_size_;
  cv::Ptr<cv::Feature2D> sift_;
};

/// OpenCV's HOGDescriptor with the patch as its window: 4x4 cells, blocks of 2x2 cells moved by one cell,
/// 9 unsigned orientation bins: 3 * 3 * 4 * 9 = 324 floats. A patch_size that is not a multiple of 4 is
/// first resized (area interpolation) to the multiple of 4 below it, so that cells tile the window exactly.
/// The gradients are OpenCV's (HOGDescriptor::computeGradient); the block histograms are computed here, with
/// OpenCV's weights, order of additions and normalisation (the same floats: test_descriptors), from tables
/// built once instead of at every call.
class HogExtractor : public DescriptorExtractor
{
public:
  static constexpr int kCells = 4;
  static constexpr int kBins = 9;
  static constexpr int kLength = (kCells - 1) * (kCells - 1) * 4 * kBins;
  explicit HogExtractor(int patch_size);
  std::string name() const override
  {
    return "HOG";
  }
  bool isBinary() const override
  {
    return false;
  }
  int length() const override
  {
    return kLength;
  }
  void describeFloat(const Patch& patch, float* values) const override;

private:
  struct Blocks;
  int patch_size_;
  int window_;
  std::shared_ptr<const Blocks> blocks_;
};

/// D-LDB (paper section II-C): LDB of the intensity patch, then LDB of the disparity patch over its valid
/// pixels only. The second LDB is bit-packed right after the first (bit kLdbBits onwards), so length() is
/// exactly 2 * 1386 bits, every bit is a real test, and the 44 words hold no padding in between.
class DldbExtractor : public DescriptorExtractor
{
public:
  std::string name() const override
  {
    return "D-LDB";
  }
  bool isBinary() const override
  {
    return true;
  }
  int length() const override
  {
    return 2 * kLdbBits;
  }
  int minPatchSize() const override
  {
    return 10;
  }
  void describeBinary(const Patch& patch, uint64_t* words) const override;
};

}  // namespace openable
