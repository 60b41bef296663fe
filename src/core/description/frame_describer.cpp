#include "openable/description/frame_describer.h"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "openable/error.h"

namespace openable
{
uint32_t DescriptorLayout::maxCellDistance() const
{
  return binary ? static_cast<uint32_t>(cell_length) : kFloatScale;
}

std::string DescriptorLayout::check() const
{
  const std::string fields = std::string(binary ? "binary" : "float") + " layout (cell_length " +
                             std::to_string(cell_length) + ", cell_words " + std::to_string(cell_words) + ", cells " +
                             std::to_string(cells) + ", blocks " + std::to_string(blocks) + ")";
  if (cell_length <= 0 || cell_words <= 0 || cells <= 0 || blocks <= 0)
    return fields + ": every field must be positive";
  // The words a cell needs follow from its length; a mismatch makes FrameMetric read past the cell.
  // (Division, not wordsForBits: cell_length + 63 overflows for a corrupt length near INT_MAX.)
  const int expected_words = binary ? cell_length / 64 + (cell_length % 64 != 0) : cell_length / 2 + cell_length % 2;
  if (cell_words != expected_words)
    return fields + ": " + std::to_string(cell_length) + (binary ? " bits" : " floats") + " need " +
           std::to_string(expected_words) + " words per cell";
  if (blocks > kMaxBlocks || cells % blocks != 0)
    return fields + ": cells must split into at most " + std::to_string(kMaxBlocks) + " equal blocks";
  if (frameWords() > kMaxFrameWords)
    return fields + ": " + std::to_string(frameWords()) + " words per frame; at most " +
           std::to_string(kMaxFrameWords) + " are supported";
  // FrameMetric sums cell distances of a frame in 32 bits.
  if (maxFrameDistance() > UINT32_MAX)
    return fields + ": the largest frame distance " + std::to_string(maxFrameDistance()) + " does not fit 32 bits";
  return "";
}

FrameDescriber::FrameDescriber(const Config& config) : config_(config), preprocessor_(config)
{
  config.validateOrThrow();
  extractor_ = createDescriptorExtractor(config);
  layout_.binary = extractor_->isBinary();
  layout_.cell_length = extractor_->length();
  layout_.cell_words = layout_.binary ? wordsForBits(layout_.cell_length) : (layout_.cell_length + 1) / 2;
  layout_.cells = preprocessor_.cellCount();
  layout_.blocks = config.camera_type == "panoramic" ? config.panoramas : 1;
  const std::string problem = layout_.check();
  if (!problem.empty())
    throw Error("the configuration gives an unsupported descriptor " + problem);
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
  std::vector<float> values;
  for (int i = 0; i < layout_.cells; ++i)
  {
    uint64_t* cell = out + i * layout_.cell_words;
    if (layout_.binary)
    {
      extractor_->describeBinary(patches[i], cell);
      continue;
    }
    values.assign(layout_.cell_words * 2, 0.0f);
    extractor_->describeFloat(patches[i], values.data());
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

FrameDescriptor FrameDescriber::describeImage(const cv::Mat& image) const
{
  return describe(preprocessor_.patches(image));
}

}  // namespace openable
