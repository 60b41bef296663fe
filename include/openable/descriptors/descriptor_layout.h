// How one frame's descriptor is laid out in memory, what every stage after description needs to know of
// it (the map, the matchers, the map file), without building an extractor or a preprocessor.
// descriptorLayout(config) (openable/description/frame_describer.h) derives it from the descriptor registry.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace openable
{
/// How one frame's descriptor is laid out in memory: `cells` cell descriptors of `cell_words` 64-bit words
/// each, grouped into `blocks` equal blocks (sub-panoramas; 1 otherwise). Binary cells hold bits; float
/// cells hold `cell_length` floats (two per word), scaled to unit length.
struct DescriptorLayout
{
  bool binary = true;
  int cell_length = 0;  ///< bits or floats per cell
  int cell_words = 0;   ///< 64-bit words per cell
  int cells = 1;
  int blocks = 1;

  /// In size_t: two ints of a loaded (untrusted) layout can multiply past INT_MAX. Only meaningful for a
  /// layout that check() accepts.
  size_t frameWords() const
  {
    return static_cast<size_t>(cell_words) * static_cast<size_t>(cells);
  }
  size_t blockWords() const
  {
    return frameWords() / static_cast<size_t>(blocks);
  }
  /// Empty when the layout is one FrameDescriber can produce and FrameMetric can measure: positive
  /// fields, cell_words matching cell_length, cells a multiple of blocks, at most kMaxFrameWords words,
  /// at most kMaxBlocks blocks, and frame distances that fit 32 bits. Otherwise what is wrong.
  std::string check() const;
  /// Largest distance between two cells (bits for binary, kFloatScale for float).
  uint32_t maxCellDistance() const;
  /// Largest frame distance: the normalisation of every distance the library reports.
  uint64_t maxFrameDistance() const
  {
    return uint64_t(maxCellDistance()) * cells;
  }
  bool operator==(const DescriptorLayout& o) const
  {
    return binary == o.binary && cell_length == o.cell_length && cell_words == o.cell_words && cells == o.cells &&
           blocks == o.blocks;
  }
  bool operator!=(const DescriptorLayout& o) const
  {
    return !(*this == o);
  }
};

/// Largest descriptor of one frame: 2^24 words = 128 MiB (a grid of 64x64 cells of 128 floats is 2^18).
constexpr size_t kMaxFrameWords = size_t(1) << 24;
/// Largest number of sub-panoramas: FrameMetric compares every block with every block (blocks^2 distances).
constexpr int kMaxBlocks = 1024;

/// Float cell distances are the L2 distance of unit vectors (0..2) scaled to integers 0..kFloatScale, so
/// that sequence sums are exact integer arithmetic for every descriptor.
constexpr uint32_t kFloatScale = 1u << 15;

/// One frame's descriptor: frameWords() words.
using FrameDescriptor = std::vector<uint64_t>;

/// Words of 64 bits holding `bits` bits.
inline int wordsForBits(int bits)
{
  return (bits + 63) / 64;
}

}  // namespace openable
