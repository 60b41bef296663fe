#include "openable/description/frame_describer.h"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "openable/error.h"

namespace openable
{
void keepBitsEvenly(const uint64_t* all, int all_bits, uint64_t* kept, int kept_bits)
{
  // Bit j of the kept ones is bit floor(j x all / kept) of all: spread over the whole descriptor, so a HOG-B keeps
  // bins of every block rather than dropping the last blocks.
  for (int j = 0; j < kept_bits; ++j)
  {
    const int from = static_cast<int>(int64_t(j) * all_bits / kept_bits);
    if ((all[from / 64] >> (from % 64)) & 1u)
      kept[j / 64] |= uint64_t(1) << (j % 64);
  }
}

DescriptorLayout descriptorLayout(const Config& config)
{
  const DescriptorInfo& row = descriptorInfo(config.descriptor);
  DescriptorLayout layout;
  layout.binary = row.binary();
  layout.cell_length = layout.binary && config.descriptor_bits > 0 ? config.descriptor_bits : row.length;
  layout.cell_words = layout.binary ? wordsForBits(layout.cell_length) : (layout.cell_length + 1) / 2;
  const PreprocessOptions cells = PreprocessOptions::from(config);
  layout.cells = cells.cellsAcross() * cells.cellsDown();
  layout.blocks = config.camera() == CameraType::Panoramic ? config.panoramas : 1;
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("the configuration gives an unsupported descriptor " + problem);
  return layout;
}

std::unique_ptr<DescriptorExtractor> createDescriptorExtractor(const Config& config)
{
  const DescriptorInfo& row = descriptorInfo(config.descriptor);
  if (row.needs_disparity && config.camera() != CameraType::Stereo)
    throw Error("descriptor " + config.descriptor + " describes disparity and needs camera_type stereo (got " +
                config.camera_type + ")");
  if (config.patch_size < row.min_patch_size)
    throw Error("patch_size " + std::to_string(config.patch_size) + " is too small for " + row.name +
                "; expected at least " + std::to_string(row.min_patch_size));
  return row.create(config.patch_size);
}

FrameDescriber::FrameDescriber(const Config& config) : FrameDescriber(ValidConfig(config)) {}

FrameDescriber::FrameDescriber(const ValidConfig& config)
  : config_(*config),
    preprocessor_(*config),
    row_(&descriptorInfo(config->descriptor)),
    layout_(descriptorLayout(*config)),
    extractor_(createDescriptorExtractor(*config))
{
  // The registry's row and the extractor it builds must agree (test_descriptors checks every row).
  if (extractor_->isBinary() != layout_.binary || extractor_->length() != row_->length)
    throw Error("descriptor " + config->descriptor + ": its registry row does not match its extractor");
}

FrameDescriptor FrameDescriber::describe(const std::vector<Patch>& patches) const
{
  FrameDescriptor out(layout_.frameWords());
  describe(patches, out.data());
  return out;
}

void FrameDescriber::describe(const std::vector<Patch>& patches, uint64_t* out) const
{
  if (static_cast<int>(patches.size()) != layout_.cells)
    throw Error("got " + std::to_string(patches.size()) + " patches; the configuration describes " +
                std::to_string(layout_.cells) + " cells per frame");
  std::memset(out, 0, sizeof(uint64_t) * layout_.frameWords());
  const DescriptorExtractor& extractor = extractorFor(patches.empty() ? config_.patch_size : patches[0].intensity.cols);
  std::vector<float> values;
  std::vector<uint64_t> all;  // descriptor_bits: a cell's every bit, before some are kept
  for (int i = 0; i < layout_.cells; ++i)
  {
    uint64_t* cell = out + i * layout_.cell_words;
    if (layout_.binary && layout_.cell_length == row_->length)
    {
      extractor.describeBinary(patches[i], cell);
      continue;
    }
    if (layout_.binary)
    {
      all.assign(wordsForBits(row_->length), 0);
      extractor.describeBinary(patches[i], all.data());
      keepBitsEvenly(all.data(), row_->length, cell, layout_.cell_length);
      continue;
    }
    values.assign(layout_.cell_words * 2, 0.0f);
    extractor.describeFloat(patches[i], values.data());
    // Unit length: L2 distances then lie in [0, 2] whatever the descriptor's own scale, so they can be
    // normalised and summed like Hamming distances. An all-zero vector (a flat patch) stays zero.
    double norm = 0.0;
    for (float v : values)
      norm += double(v) * v;
    norm = std::sqrt(norm);
    if (norm > 0.0)
      for (float& v : values)
        v = static_cast<float>(v / norm);
    std::memcpy(cell, values.data(), sizeof(float) * values.size());
  }
}

const DescriptorExtractor& FrameDescriber::extractorFor(int side) const
{
  // A smaller side comes from a small image (Preprocessor), never below the descriptor's smallest patch. Any other
  // side is the configured extractor's, which refuses a patch that is not its size, naming both.
  if (side >= config_.patch_size || side < row_->min_patch_size)
    return *extractor_;
  std::lock_guard<std::mutex> lock(smaller_->mutex);
  std::unique_ptr<DescriptorExtractor>& extractor = smaller_->by_side[side];
  if (!extractor)
    extractor = row_->create(side);
  return *extractor;
}

FrameDescriptor FrameDescriber::describeImage(const cv::Mat& image) const
{
  return describe(preprocessor_.patches(image));
}

}  // namespace openable
