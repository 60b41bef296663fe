#include "openable/descriptors/descriptor_layout.h"

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

}  // namespace openable
