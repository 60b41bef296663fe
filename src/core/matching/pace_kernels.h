#pragma once

// The per-frame kernel of PaceMatcher, private to the core library:
//   pace_kernels.cpp      the portable kernel (every architecture) and the run-time choice of a kernel
//   pace_kernels_x86.cpp  AVX2 and AVX-512BW kernels (x86 only; each function carries GCC's target attribute,
//                         so the library builds without -march and runs on any x86-64)
// Every kernel computes exactly the same integers (16-bit fixed point, saturating adds, rounded products): a
// frame's costs do not depend on the CPU, and the tests compare each kernel with a plain reference.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "openable/matching/pace_matcher.h"

namespace openable
{
namespace pace_kernels
{
/// A cost of 1.0 (every bit different along the whole path) in the fixed point of the costs.
constexpr int32_t kOne = 32767;

/// One pace over a chunk: the previous costs of its places and where this frame's go (the same memory for a
/// forward pace, updated in place; another buffer for a reverse one).
struct PaceRow
{
  const int16_t* from;  ///< previous frame's costs, indexed by place in the chunk; valid from -pad to m + pad
  int16_t* to;          ///< this frame's costs, indexed by place in the chunk
  long offset;          ///< where the path comes from: -step (forward) or +step (reverse)
  int16_t slip;         ///< the cost of a slip off this line (with Chunk::slips); the faster the line, the less
};

/// One chunk of places [begin, begin + m) of a frame.
struct Chunk
{
  /// The chunk's Hamming (or quantised L2) distances at raw[tolerance + i], with `tolerance` neighbours on each
  /// side (INT32_MAX past either end of the row).
  const uint32_t* raw;
  size_t begin;
  size_t m;
  int tolerance;
  float entry_scale;  ///< the entry term of distance r: nearbyint(float(r) * entry_scale) (the weight 1 - a in it)
  int16_t keep;       ///< a in 1/32768: a product x * a is (x * keep + 2^14) >> 15
  int16_t change;     ///< the cost of a change of pace
  /// Whether a path may move one place off its line in a frame (one place further, or one fewer where the line
  /// advances), so a revisit between two of the paces followed, or drifting from one to the next, is followed
  /// without a change of pace, for its row's PaceRow::slip; false for the slip_penalty 0 of the configuration.
  bool slips;
  const int16_t* old_best;  ///< M of the previous frame, indexed by place; valid from -pad to n + pad
  int16_t* best;            ///< M of this frame, indexed by place
  const PaceRow* rows;
  size_t paces;
  /// The distinct offsets of this frame's paces (a kernel adds the change cost to M once per offset), and for
  /// each pace the index of its offset among them.
  const long* offsets;
  size_t distinct;
  const uint8_t* slot;
  // Scratch of at least m entries each.
  int16_t* entry;        ///< the entry term of the nearest distance within the tolerance
  int16_t* extra;        ///< the entry term of the place's own distance minus that one (M is judged by its own)
  int16_t* smallest;     ///< the smallest cost of each place
  int16_t* with_change;  ///< M' + change for each offset, `stride` entries each
  size_t stride;
  /// While the matcher searches (PaceMatcher's pace prior; both null otherwise): each pace's prior, and each place's
  /// cost with the prior, indexed by place as `best`: its smallest cost plus its pace's prior (the kernel keeps the
  /// running minimum here pace by pace as it writes the costs; a pass over the 17 rows after the kernel, still in
  /// L2, took as long as the kernel), plus M's own-distance term (`extra`). Unsigned: a cost and a prior are each at
  /// most kOne, so the sum is exact; saturated at 2.0. smallestDistinct() reads one value a place (adding the prior
  /// pace by pace there, over every place of the chunks it scanned again, made a searching frame at 1e5 places six
  /// times a published one).
  const uint16_t* prior = nullptr;
  uint16_t* searched = nullptr;
};

/// The chunk's first place's cost with the prior (Chunk::searched at place `begin`), or null while not searching.
inline uint16_t* searchedOf(const Chunk& c)
{
  return c.searched ? c.searched + c.begin : nullptr;
}

/// What a chunk kernel leaves for smallestDistinct(): the chunk's smallest costs (the row's mean and spread come from
/// the screen's sums, ScreenSums, which every chunk computes).
struct ChunkSums
{
  int16_t minimum = kOne;                  ///< the smallest M of the chunk
  uint16_t searched_minimum = UINT16_MAX;  ///< the smallest Chunk::searched of the chunk (while searching)
};

/// Updates every pace's costs and M for the chunk's places. Forward rows are updated in place: the portable and
/// AVX2 kernels go from the chunk's last place down (a place reads places before it, not yet overwritten), the
/// AVX-512 one up, carrying the previous costs of the places behind in a register. The chunk's padding holds the
/// previous costs of the places beyond it.
using ChunkFn = ChunkSums (*)(const Chunk&);

ChunkSums chunkPortable(const Chunk& chunk);  // pace_kernels.cpp
#if defined(__x86_64__) || defined(__i386__)
ChunkSums chunkAvx2(const Chunk& chunk);    // pace_kernels_x86.cpp
ChunkSums chunkAvx512(const Chunk& chunk);  // pace_kernels_x86.cpp
#endif

/// Places behind a block of 32 the AVX-512 kernel can read (from it and the block before): a pace's step, plus one
/// for a slip.
constexpr long kAvx512Reach = 32;

/// The kernel for `kernel` whose rows read up to `reach` places behind (max_pace + 1): kBest is the fastest this
/// CPU runs that reaches that far. Throws Error when the CPU cannot run `kernel` or it does not reach.
ChunkFn kernelFor(PaceKernel kernel, long reach);
/// Whether this CPU runs `kernel` (kBest and kPortable: always).
bool supported(PaceKernel kernel);
/// Throws Error naming `kernel` when this CPU cannot run it (kernelFor and screenFor check the same way).
void requireSupported(PaceKernel kernel);

/// One chunk of places of the screen (pace_screen.cpp): a cost a place, the entry of its own frame distance plus a
/// times the smallest screen cost of the places a path could have come from in one frame (0 to `reach` places
/// behind, and ahead with bidirectional), whatever its pace was. It follows a revisit at any pace at 2 bytes a place
/// (a path may zig-zag, so it ranks places, it does not decide): the chunks whose places it ranks first are the
/// ones PaceMatcher refines with every pace.
struct ScreenChunk
{
  const uint32_t* raw;        ///< the chunk's own frame distances, at raw[i] for place begin + i
  size_t begin;               ///< the chunk's first place
  size_t m;                   ///< its places
  long reach;                 ///< max_pace: places a path may advance in a frame
  bool bidirectional;         ///< paths may go backwards as well
  float entry_scale;          ///< the entry term of distance r: entryOf(r, entry_scale), as Chunk::entry_scale
  int16_t keep;               ///< a in 1/32768, as Chunk::keep
  const int16_t* old_screen;  ///< the previous frame's screen, indexed by place; valid from -reach to n + reach
  int16_t* screen;            ///< this frame's, indexed by place
};

struct ScreenSums
{
  uint64_t sum = 0;      ///< of the chunk's own distances (the row's mean and spread)
  uint64_t squares = 0;
  int16_t minimum = kOne;  ///< the chunk's smallest screen cost
};

/// The screen of one chunk in the version `kernel` names (kBest: the fastest this CPU runs); every version computes
/// the same integers. Throws Error as kernelFor() when the CPU lacks it.
using ScreenFn = ScreenSums (*)(const ScreenChunk&);
ScreenFn screenFor(PaceKernel kernel);  // pace_screen.cpp

/// Saturating 16-bit arithmetic of the kernels, written once for the portable kernel and the tests' reference.
inline int16_t addSaturated(int32_t a, int32_t b)
{
  const int32_t s = a + b;
  return static_cast<int16_t>(s > 32767 ? 32767 : (s < -32768 ? -32768 : s));
}
/// x * keep / 32768, rounded half up (x86's pmulhrsw, Arm's sqrdmulh).
inline int16_t scaled(int32_t x, int32_t keep)
{
  return static_cast<int16_t>((x * keep + 16384) >> 15);
}

/// A place's cost with the prior: its smallest cost plus prior, plus M's own-distance term (>= 0), saturated as
/// vpaddusw.
inline uint16_t searchedCost(uint16_t with_prior, int16_t extra)
{
  return static_cast<uint16_t>(std::min<int32_t>(UINT16_MAX, int32_t(with_prior) + extra));
}

/// The entry term of a distance: float(r) * scale, at most 1.0, rounded to the nearest (even) integer, as
/// vcvtdq2ps, vmulps, vminps and vcvtps2dq compute it.
inline int16_t entryOf(uint32_t r, float scale)
{
  const float x = std::min(static_cast<float>(static_cast<int32_t>(r)) * scale, static_cast<float>(kOne));
  return static_cast<int16_t>(std::nearbyint(x));
}

/// The entry terms of place i of the chunk. The vector kernels' tails.
inline void prepare(const Chunk& c, size_t i)
{
  const uint32_t* own = c.raw + c.tolerance;
  const uint32_t r = own[i];
  uint32_t nearest = r;
  for (long k = 1; k <= c.tolerance; ++k)
    nearest = std::min({nearest, own[static_cast<long>(i) - k], own[static_cast<long>(i) + k]});
  c.entry[i] = entryOf(nearest, c.entry_scale);
  c.extra[i] = static_cast<int16_t>(entryOf(r, c.entry_scale) - c.entry[i]);
}

/// The best previous cost of a path one place off its line, before the slip's cost: the place one further along
/// (`from` - 1 forward, + 1 reverse) and, where the line advances (offset != 0), the place one fewer. A forward row
/// updated in place from its last place down has not overwritten either yet.
inline int16_t offLine(const PaceRow& row, long from)
{
  const long further = row.from == row.to ? -1 : 1;
  const int16_t one_more = row.from[from + further];
  return row.offset != 0 ? std::min(one_more, row.from[from - further]) : one_more;
}

/// Every pace's cost and M of place i of the chunk:
///   C[j, v] = entry + a * min(C'[j + offset_v, v], M'[j + offset_v] + change, C'[j + offset_v -+ 1, v] + slip),
///   M[j] = min_v C[j, v] + extra
/// (primes: the previous frame; the slip term as offLine, when the chunk slips), and the place's smallest cost and,
/// with a prior, its smallest cost plus prior. The vector kernels' tails.
inline void update(const Chunk& c, size_t i, ChunkSums& sums)
{
  const size_t j = c.begin + i;
  int16_t best = static_cast<int16_t>(kOne);
  uint16_t with_prior = UINT16_MAX;
  for (size_t v = 0; v < c.paces; ++v)
  {
    const PaceRow& row = c.rows[v];
    const long from = static_cast<long>(i) + row.offset;
    int16_t path = std::min(row.from[from], addSaturated(c.old_best[static_cast<long>(j) + row.offset], c.change));
    if (c.slips)
      path = std::min(path, addSaturated(offLine(row, from), row.slip));
    const int16_t cost = addSaturated(c.entry[i], scaled(path, c.keep));
    row.to[i] = cost;
    best = std::min(best, cost);
    if (c.prior)
      with_prior = std::min(with_prior, static_cast<uint16_t>(static_cast<uint16_t>(cost) + c.prior[v]));
  }
  c.best[j] = addSaturated(best, c.extra[i]);
  sums.minimum = std::min(sums.minimum, c.best[j]);
  if (c.prior)
  {
    c.searched[j] = searchedCost(with_prior, c.extra[i]);
    sums.searched_minimum = std::min(sums.searched_minimum, c.searched[j]);
  }
}

}  // namespace pace_kernels
}  // namespace openable
