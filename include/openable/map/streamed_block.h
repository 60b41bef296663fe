#pragma once

#include <cstddef>

namespace openable
{
/// A block of memory that every frame streams through whole (a map's descriptors, a matcher's costs):
/// 64-byte aligned, so vectors load and store whole cache lines, and from 32 MiB on aligned to 2 MiB and
/// advised onto transparent huge pages, so a pass does not miss the TLB every 4 KiB. Null when out of memory;
/// freed with std::free.
void* allocateStreamedBlock(size_t bytes);
/// What such a block of `bytes` really takes (rounded up to its alignment).
size_t streamedBlockBytes(size_t bytes);
}  // namespace openable
