#include "openable/map/streamed_block.h"

#include <algorithm>
#include <cstdlib>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace openable
{
namespace
{
constexpr size_t kAlignment = 64;
constexpr size_t kHugePage = size_t(2) << 20;
/// From here on a block goes on 2 MiB pages where the kernel has them: on 4 KiB pages a 480 MB map is 120,000
/// TLB misses a pass, and a matcher's 340 MB of costs, read in 17 runs a chunk, took a frame 4x as long on a
/// virtual machine (218 against 44 ms at 1e7 places; README, "Matching at any pace"). The block is rounded up
/// to whole huge pages, so the threshold keeps that rounding below 6 %.
constexpr size_t kHugePagesFrom = size_t(32) << 20;

size_t alignmentFor(size_t bytes)
{
  return bytes < kHugePagesFrom ? kAlignment : kHugePage;
}
}  // namespace

size_t streamedBlockBytes(size_t bytes)
{
  const size_t alignment = alignmentFor(bytes);
  return (std::max<size_t>(bytes, 1) + alignment - 1) / alignment * alignment;
}

void* allocateStreamedBlock(size_t bytes)
{
  const size_t alignment = alignmentFor(bytes);
  const size_t rounded = streamedBlockBytes(bytes);
  void* block = std::aligned_alloc(alignment, rounded);
#ifdef MADV_HUGEPAGE
  if (block && alignment == kHugePage)
    madvise(block, rounded, MADV_HUGEPAGE);  // advice only: without huge pages it works the same
#endif
  return block;
}
}  // namespace openable
