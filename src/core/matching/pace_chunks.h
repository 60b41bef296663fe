#pragma once

// What PaceMatcher's files share (pace_matcher.cpp, pace_matcher_screening.cpp), private to the core library.

#include <cstddef>

namespace openable
{
namespace pace_chunks
{
/// Columns processed together: a chunk's distances and scratch stay in L1/L2, its costs are one run of memory
/// of 17 x 4 KB (256 columns: a frame at 1e7 places took 73 ms, 1024: 54, 2048: 55, 4096: 54, while 1e5 places
/// slowed down past 2048), and each chunk gets one minimum for smallestDistinct().
constexpr size_t kChunk = 2048;
}  // namespace pace_chunks
}  // namespace openable
