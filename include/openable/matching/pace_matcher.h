#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "openable/map/streamed_block.h"
#include "openable/matching/frame_metric.h"
#include "openable/matching/row_matcher.h"

namespace openable
{
namespace pace_kernels  // the per-frame kernels, private to the core library (src/core/matching/pace_kernels.h)
{
struct Chunk;
struct ChunkSums;
struct ScreenChunk;
struct ScreenSums;
struct PaceRow;
}  // namespace pace_kernels

/// Sequence matching at any pace: the revisit may advance from 1 / max_pace to max_pace places of the
/// reference per query frame, and change pace along the way (an online Viterbi over places and paces, after
/// Hansen & Browning, ICRA 2014, in min-plus form, with SeqSLAM's straight trajectories as its states).
///
/// Each place j and pace v (17 slopes from 1/3 to 3 for max_pace 3, in steps of 15 %, plus one beyond each end) keeps
/// the cost of the best path of query frames ending in j at that pace, an exponentially weighted mean of frame
/// distances along it with a memory of L frames (a = 1 - 1/L):
///   C_t[j, v] = (1 - a) * d(t, j) + a * min(C_{t-1}[j - s, v], M_{t-1}[j - s] + pace_penalty,
///                                           C_{t-1}[j - s -+ 1, v] + slip_penalty * pace_penalty),
///   M_t[j] = min_v C_t[j, v]
/// where s = floor((t + 1) v) - floor(t v) is the places that pace advances at frame t (a straight line, as
/// SeqSLAM searches), d the normalised frame distance (0 = identical, 1 = every bit different), and M_t[j]
/// the place's cost at its best pace: a path keeps its pace for free and changes it for `pace_penalty`, so a
/// revisit that speeds up or slows down is followed, while a path cannot zig-zag through the row picking the
/// smallest distance of every frame (which would make every place look alike). The third term (with
/// `slip_penalty` > 0) lets a path move one place off its line in a frame, one further or, where the line
/// advances, one fewer, for a fraction of a change of pace: a revisit at a pace between two of those followed
/// (1.25x lies between 1.15x and 1.32x; a straight line at the wrong one drifts a place every few frames), or one
/// whose pace drifts, stays on its place without paying a whole change of pace at every drift. With
/// `bidirectional`, the reverse (places visited backwards: j + s) is kept the same way. One pass over the
/// descriptors per frame, whatever L and max_pace are, fused with one pass over the costs, chunk by chunk (the
/// chunk's distances stay in L1): the costs are 16-bit fixed point (1.0 = 32767, products rounded, sums
/// saturated), 2 bytes a place and pace, so a frame moves 48 + 17 x 4 bytes a place rather than 48 + 17 x 8, and a
/// vector holds 16 or 32 places. The rounding moves a cost by at most about 3 L units of 1 / 32767 from the float
/// recurrence (test_pace checks it); every kernel (portable, AVX2, AVX-512BW, chosen at run time) computes the
/// same integers (test_pace_kernels).
///
/// A place that joins the row (the reference grew, or the exclusion window let it in) starts from the mean
/// distance of the previous frame's row: a path that has seen nothing is typical, neither good nor bad.
///
/// A large row is screened (PaceOptions::screen_chunks): beyond 64 chunks of 2048 places (131,072 places), every
/// place also keeps one screen cost, a path that may take any step of 0 to max_pace places a frame for free
/// (pace_kernels::ScreenChunk; 2 bytes a place read and written), and only the chunks whose smallest screen cost
/// ranks among the first 16 of the previous frame, each with the chunk after it (where a forward path goes on), and
/// those refined the frame before that still rank among the first 32, keep and update every pace's costs, in a pool
/// of slots (49 chunks' costs, not every chunk's). At most 4 chunks start to be refined in a frame; each starts every
/// pace from its places' screen costs, raised by how far a refined place's cost lay above its screen cost on average
/// (the screen's paths may zig-zag: lower, most of all where nothing matches). Candidates come from refined chunks
/// only. A frame then moves the descriptors and 4 bytes a place, plus every pace's costs of at most 48 chunks; a row
/// of up to 64 chunks is refined whole, as without the screen (below that the screen saves too little: at 100,000
/// places, 49 chunks, it would refine most of them anyway).
///
/// The kernels of a frame's update; each one gives the same numbers (kBest: the fastest this CPU runs).
enum class PaceKernel
{
  kBest,
  kPortable,
  kAvx2,
  kAvx512
};
std::string paceKernelName(PaceKernel kernel);
/// Kernels this CPU runs, slowest first (kBest not among them).
std::vector<PaceKernel> supportedPaceKernels();

/// Storage for costs every frame streams through (allocateStreamedBlock): the kernels' vectors load and store
/// whole cache lines, and a large row sits on huge pages.
template <typename T>
struct CacheAligned
{
  using value_type = T;
  CacheAligned() = default;
  template <typename U>
  CacheAligned(const CacheAligned<U>&)
  {
  }
  T* allocate(size_t n)
  {
    void* block = allocateStreamedBlock(n * sizeof(T));
    if (!block)
      throw std::bad_alloc();
    return static_cast<T*>(block);
  }
  void deallocate(T* p, size_t)
  {
    std::free(p);
  }
  bool operator==(const CacheAligned&) const
  {
    return true;
  }
  bool operator!=(const CacheAligned&) const
  {
    return false;
  }
};
using AlignedCosts = std::vector<int16_t, CacheAligned<int16_t>>;

/// How PaceMatcher follows a revisit (Config's max_pace, pace_penalty, slip_penalty, pace_tolerance).
struct PaceOptions
{
  int max_pace = 3;      ///< paces from 1 / max_pace to max_pace places per frame
  float penalty = 3.0f;  ///< a change of pace, in standard deviations of a path's cost under noise
  float slip = 0.0f;     ///< a path one place off its line in a frame, as a fraction of `penalty` (0 = never)
  int tolerance = 1;     ///< places a path may be off its line in each frame (0 .. 2)
  float prior = 0.0f;    ///< while searching, a pace 30 % or more from 1x pays this fraction of `penalty` (0 = off)
  /// A row of more than this many chunks of 2048 places is screened: every place keeps one screen cost, and only
  /// the quarter as many chunks the screen ranks first (at least one; and the chunk after each) keep every pace's
  /// costs. 0 = every chunk, always.
  size_t screen_chunks = 64;
  PaceKernel kernel = PaceKernel::kBest;  ///< tests and benchmarks pick one; Error when the CPU lacks it
};

class PaceMatcher : public RowMatcher
{
public:
  /// Throws Error when sequence_length < 1 or an option is out of range.
  PaceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional, const PaceOptions& options);

  void match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates) override
  {
    matchShifted(query, nullptr, 0, reference, candidates);
  }
  void matchShifted(const uint64_t* query, const uint64_t* shifted, size_t views, const PlaceDatabase& reference,
                    size_t candidates) override;
  uint64_t firstId() const override
  {
    return first_id_;
  }
  size_t columns() const override
  {
    return columns_;
  }
  float normalized(size_t column, int* direction = nullptr, int min_terms = 1) const override;
  uint16_t terms(size_t column, int direction) const override;
  float rowSpread() const override
  {
    return evidence_ > 0 ? spread_ : std::nanf("");
  }
  float pace(size_t column) const override
  {
    return static_cast<float>(placesPerFrame(slopes_[paceIndex(column)]));
  }
  /// A pace followed (paces()) as places a frame, whatever its direction.
  static double placesPerFrame(const std::pair<int, int>& slope)
  {
    return static_cast<double>(std::abs(slope.first)) / static_cast<double>(slope.second);
  }
  /// At a fast (or slow) pace, the end of the best path placed between its pace and the neighbouring one whose
  /// costs say the revisit lies between them (pace_matcher.cpp); elsewhere `column`.
  size_t refinedColumn(size_t column) const override;
  size_t smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& columns) const override;
  void setSequenceLength(int sequence_length) override;
  void setBidirectional(bool bidirectional) override;
  void setSearching(bool searching) override
  {
    searching_ = searching;
  }
  void reset() override;

  int maxPace() const
  {
    return max_pace_;
  }
  /// The paces followed, as fractions (places, frames): slowest first, then the reverse ones with bidirectional.
  const std::vector<std::pair<int, int>>& paces() const
  {
    return slopes_;
  }
  /// The chunks of `places` places, as PaceOptions::screen_chunks counts them (0: 0, never screened).
  static size_t chunksOf(size_t places);
  /// Query frames matched since the last reset.
  uint64_t queries() const
  {
    return queries_;
  }

private:
  /// Keeps the rows aligned with the reference: drops evicted places, appends new ones at `prior`.
  void align(const PlaceDatabase& reference, size_t candidates);
  /// raw_ for the chunk of columns [begin, begin + m), with tolerance_ neighbours on each side: the smallest of the
  /// distances of the frame's queries (query_views_, set once a frame by matchShifted).
  void distances(const PlaceDatabase& reference, size_t begin, size_t m);
  /// A screen cost as a path's cost where a chunk is not refined: plus screen_offset_.
  int16_t screenedCost(int16_t screen) const;
  /// Whether column `column`'s chunk keeps every pace's costs this frame.
  bool isRefined(size_t column) const;
  /// At least min_terms (at most L) frames matched since the last reset.
  bool enoughEvidence(int min_terms) const;
  /// refined_ for this frame's `chunks` chunks, from the previous frame's screen (screen_minimum_); whether any is
  /// screened out.
  bool chooseRefined(size_t chunks);
  /// Before the kernel updates refined chunk `k` (m places) of `chunks`: its stale places started from the screen, its
  /// segments' padding, each pace's rows, and the last frame's M of its neighbours that were screened out.
  void prepareChunk(size_t k, size_t chunks, size_t m, std::vector<pace_kernels::PaceRow>& rows);
  /// Every pace's costs of chunk `chunk`'s stale places start from their screen costs of the last frame.
  void startFromScreen(size_t chunk);
  /// Keeps a buffer of costs aligned: drops `front` evicted places, keeps `size` places, new ones at `prior`.
  void resizeCosts(AlignedCosts& costs, size_t front, size_t size);
  /// The costs of pace `pace` over chunk `chunk` of a buffer, at place 0 of the chunk.
  int16_t* segment(AlignedCosts& costs, size_t chunk, size_t pace) const
  {
    return slotSegment(costs, static_cast<size_t>(slot_[chunk]), pace);
  }
  /// The costs of pace `pace` in slot `slot` of a buffer (a chunk's place in it: slot_), at its place 0.
  int16_t* slotSegment(AlignedCosts& costs, size_t slot, size_t pace) const
  {
    return costs.data() + (slot * slopes_.size() + pace) * segment_ + margin_;
  }
  /// While screening, the buffers hold a pool of slots, one for each refined chunk; otherwise one slot for every
  /// chunk, in order. These switch between the two (after chooseRefined): refined chunks keep their costs.
  void placeRefinedChunks(bool screening);
  void pool();
  void unpool();
  /// align() of a pooled row: `front` evicted places leave, every refined chunk's costs move with its places.
  void rekeyPool(size_t front, size_t size);
  /// The buffer that holds a pace's costs of the last frame.
  AlignedCosts& current(size_t pace);
  const AlignedCosts& current(size_t pace) const;
  /// The smallest normalized() of chunk `chunk`, leaving out columns within `window` of a taken one.
  float chunkMinimum(size_t chunk, const std::vector<size_t>& taken, size_t window) const;
  float value(size_t column, int* direction) const;
  /// The cost of this frame's pace v: C[j, v] from the buffer that holds it.
  int16_t costAt(size_t column, size_t pace) const;
  /// The index in slopes_ of the pace of the column's best path (the first of the smallest costs).
  size_t paceIndex(size_t column) const;

  FrameMetric metric_;
  int sequence_length_;
  int max_pace_;
  bool bidirectional_;
  float step_penalty_;
  float slip_penalty_;  ///< fraction of a change of pace; 0 = paths never leave their line
  int tolerance_;
  float prior_fraction_;  ///< PaceOptions::prior
  bool searching_ = true;
  bool prior_active_ = false;         ///< the last frame's costs carry the prior (searching, prior_fraction_ > 0)
  std::vector<uint16_t> pace_prior_;  ///< per pace, in the fixed point, for the last frame
  /// Per place, while the prior is active: M - min_v C[j, v] + min_v (C[j, v] + prior[v]) in the fixed point (M
  /// differs from min_v C by the own-distance term of pace_tolerance), as the kernel wrote it.
  std::vector<uint16_t> searched_;
  pace_kernels::ChunkSums (*kernel_)(const pace_kernels::Chunk&);  ///< chosen once: the CPU and max_pace decide
  std::vector<std::pair<int, int>> slopes_;                        ///< paces as fractions p / q (negative: reverse)
  float keep_ = 0.0f;                                              ///< a = 1 - 1/L, the weight of the path so far
  uint64_t queries_ = 0;
  uint64_t evidence_ = 0;  ///< query frames that had places to match since the last reset
  uint64_t first_id_ = 0;
  float spread_ = 0.0f;  ///< the previous row's standard deviation of frame distances
  int16_t prior_ = 0;    ///< the previous row's mean frame distance: the start of a place that joins the row
  /// C[j, v]: per chunk of kChunk places, per pace, a segment of pad_ places, the chunk's places and pad_ more
  /// (paces read up to pad_ places beyond the chunk; the padding holds copies of those).
  AlignedCosts costs_;
  AlignedCosts reverse_;           ///< with bidirectional: reverse paces read one buffer and write the other
  bool flipped_ = false;           ///< the reverse paces' last costs are in reverse_
  size_t pad_ = 4;                 ///< more places than any pace advances in a frame
  size_t margin_ = 32;             ///< pad_ rounded up to whole vectors: every segment's places start on a cache line
  size_t segment_ = 0;             ///< kChunk + 2 margin_
  std::vector<int16_t> best_;      ///< M[j] at pad_ + j: the smallest of a place's costs, judged by its own distance
  std::vector<int16_t> old_best_;  ///< the previous frame's M, while match() runs
  size_t columns_ = 0;
  std::vector<float> chunk_minimum_;  ///< per chunk of columns, both directions, after match()
  size_t screen_chunks_;              ///< PaceOptions::screen_chunks
  size_t refined_limit_;              ///< the chunks refined while screening: a quarter of that, at least one
  pace_kernels::ScreenSums (*screen_kernel_)(const pace_kernels::ScreenChunk&);  ///< chosen once, as kernel_
  /// The screen's costs of this and the previous frame, pad_ typical places on each side (as best_).
  std::vector<int16_t> screen_, old_screen_;
  std::vector<int16_t> screen_minimum_;  ///< per chunk, the smallest screen cost of the last frame
  std::vector<uint8_t> refined_;         ///< per chunk, whether every pace's costs are updated this frame
  /// Places [begin, end) of a chunk whose costs in the buffers are not the last frame's (it was not refined).
  struct Stale
  {
    size_t begin = 0, end = 0;
    bool empty() const
    {
      return begin >= end;
    }
    bool holds(size_t place) const
    {
      return place >= begin && place < end;
    }
  };
  std::vector<Stale> stale_;   ///< per chunk
  int16_t screen_offset_ = 0;  ///< the last frame's mean of a refined place's M less its screen cost (>= 0)
  std::vector<int32_t> slot_;  ///< per chunk, its slot in costs_ (and reverse_), -1 for none (screened out)
  bool pooled_ = false;        ///< the buffers hold pool_slots_ slots (screening), not one a chunk
  std::vector<int32_t> free_slots_;
  size_t pool_slots_ = 0;  ///< slots of the pool while pooled_
  // Scratch for one chunk of columns.
  std::vector<uint32_t> raw_;       ///< frame distances
  std::vector<const uint64_t*> query_views_;  ///< this frame's query, then its shifted views (rowNearest's)
  AlignedCosts entry_;              ///< the entry terms of the kernel
  AlignedCosts extra_;
  AlignedCosts smallest_;
  AlignedCosts with_change_;
};

}  // namespace openable
