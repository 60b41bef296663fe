// The interface every descriptor implements (DescriptorExtractor, over a Patch). The descriptors themselves
// and their factories: openable/descriptors/descriptor_registry.h.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/descriptors/descriptor_layout.h"

namespace openable
{
/// One cell to describe: a patch_size x patch_size CV_32F intensity patch (grey 0..255, or the
/// illumination-invariant image), and for stereo the disparity patch (CV_32F, pixels, scaled to the
/// patch) with its validity mask (CV_8U, 255 = valid). The keypoint is always the patch centre.
struct Patch
{
  cv::Mat intensity;
  cv::Mat disparity;
  cv::Mat valid;
};

/// Describes one patch as a whole. Binary extractors write bits, float extractors write values; a
/// descriptor is deterministic: the same patch gives the same output on every run and machine.
class DescriptorExtractor
{
public:
  virtual ~DescriptorExtractor() = default;
  virtual std::string name() const = 0;
  virtual bool isBinary() const = 0;
  /// Bits (binary) or float values (vector descriptors) written per patch.
  virtual int length() const = 0;
  /// Binary: writes length() bits, bit i at words[i / 64] >> (i % 64); unused bits of the last word are 0.
  virtual void describeBinary(const Patch& patch, uint64_t* words) const;
  /// Float: writes length() values.
  virtual void describeFloat(const Patch& patch, float* values) const;
  /// Smallest patch side this extractor can describe.
  virtual int minPatchSize() const
  {
    return 8;
  }
};

}  // namespace openable
