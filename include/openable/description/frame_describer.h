#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/descriptors/descriptor_extractor.h"
#include "openable/descriptors/descriptor_layout.h"
#include "openable/descriptors/descriptor_registry.h"
#include "openable/description/preprocessor.h"

namespace openable
{
/// The layout of a frame's descriptor under `config`, from the descriptor registry and the cell grid alone
/// (no extractor is built). Throws Error for an unknown descriptor or camera, or an unsupported layout.
DescriptorLayout descriptorLayout(const Config& config);

/// Config::descriptor_bits: sets bit j of `kept` (zeroed by the caller, kept_bits <= all_bits) to bit
/// floor(j x all_bits / kept_bits) of `all`.
void keepBitsEvenly(const uint64_t* all, int all_bits, uint64_t* kept, int kept_bits);

/// The extractor named by config.descriptor, for its patch_size. Throws Error for an unknown name (listing
/// the valid ones), for a descriptor that needs disparity outside stereo mode, or for a patch_size the
/// extractor cannot use.
std::unique_ptr<DescriptorExtractor> createDescriptorExtractor(const Config& config);

/// Image -> patches -> descriptors, as the configuration says.
class FrameDescriber
{
public:
  /// Validates the config and builds the extractor. Throws Error.
  explicit FrameDescriber(const Config& config);
  explicit FrameDescriber(const ValidConfig& config);

  const DescriptorLayout& layout() const
  {
    return layout_;
  }
  const Preprocessor& preprocessor() const
  {
    return preprocessor_;
  }
  const DescriptorExtractor& extractor() const
  {
    return *extractor_;
  }
  /// The descriptor's registry row (descriptor_registry.h): whether it needs disparity, its form, length.
  const DescriptorInfo& descriptor() const
  {
    return *row_;
  }

  /// Describes patches as returned by the preprocessor (exactly layout().cells of them, of one side: patch_size, or
  /// a small image's own, Preprocessor; the extractor for that side is built once, when first needed).
  FrameDescriptor describe(const std::vector<Patch>& patches) const;
  void describe(const std::vector<Patch>& patches, uint64_t* out) const;

  /// Shorthand: preprocess + describe one mono or panoramic image.
  FrameDescriptor describeImage(const cv::Mat& image) const;

private:
  Config config_;
  Preprocessor preprocessor_;
  const DescriptorInfo* row_;
  DescriptorLayout layout_;
  std::unique_ptr<DescriptorExtractor> extractor_;
  /// The extractor for patches of `side` pixels: extractor_ at patch_size, else one of smaller_.
  const DescriptorExtractor& extractorFor(int side) const;
  /// Extractors for the smaller patches of small images, by side; behind a pointer so the describer stays movable.
  struct SmallerExtractors
  {
    std::mutex mutex;
    std::map<int, std::unique_ptr<DescriptorExtractor>> by_side;
  };
  std::unique_ptr<SmallerExtractors> smaller_ = std::make_unique<SmallerExtractors>();
};

}  // namespace openable
