#include "openable/frame_describer.h"

#include <cmath>
#include <cstring>

#include "openable/error.h"

namespace openable
{
uint32_t DescriptorLayout::maxCellDistance() const
{
  return binary ? static_cast<uint32_t>(cell_length) : kFloatScale;
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
