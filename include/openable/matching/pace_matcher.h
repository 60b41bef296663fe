#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <utility>
#include <vector>

#include "openable/matching/frame_metric.h"
#include "openable/matching/row_matcher.h"

namespace openable
{
/// Sequence matching at any pace: the revisit may advance from 1 / max_pace to max_pace places of the
/// reference per query frame, and change pace along the way (an online Viterbi over places and paces, after
/// Hansen & Browning, ICRA 2014, in min-plus form, with SeqSLAM's straight trajectories as its states).
///
/// Each place j and pace v (17 slopes from 1/3 to 3 for max_pace 3, in steps of 15 %, plus one beyond each end) keeps the
/// cost of the best path of query frames ending in j at that pace, an exponentially weighted mean of frame
/// distances along it with a memory of L frames (a = 1 - 1/L):
///   C_t[j, v] = (1 - a) * d(t, j) + a * min(C_{t-1}[j - s, v], M_{t-1}[j - s] + pace_penalty),
///   M_t[j] = min_v C_t[j, v]
/// where s = floor((t + 1) v) - floor(t v) is the places that pace advances at frame t (a straight line, as
/// SeqSLAM searches), d the normalised frame distance (0 = identical, 1 = every bit different), and M_t[j]
/// the place's cost at its best pace: a path keeps its pace for free and changes it for `pace_penalty`, so a
/// revisit that speeds up or slows down is followed, while a path cannot zig-zag through the row picking the
/// smallest distance of every frame (which would make every place look alike). With `bidirectional`, the
/// reverse (places visited backwards: j + s) is kept the same way. One pass over the descriptors per frame,
/// whatever L and max_pace are, plus one over the costs (a float a place and pace).
///
/// A place that joins the row (the reference grew, or the exclusion window let it in) starts from the mean
/// distance of the previous frame's row: a path that has seen nothing is typical, neither good nor bad.
/// How PaceMatcher follows a revisit (Config's max_pace, pace_penalty, pace_tolerance).
struct PaceOptions
{
  int max_pace = 3;        ///< paces from 1 / max_pace to max_pace places per frame
  float penalty = 3.0f;    ///< a change of pace, in standard deviations of a path's cost under noise
  int tolerance = 1;       ///< places a path may be off its line in each frame (0 .. 2)
};

class PaceMatcher : public RowMatcher
{
public:
  /// Throws Error when sequence_length < 1 or an option is out of range.
  PaceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional, const PaceOptions& options);

  void match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates) override;
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
  float pace(size_t column) const override
  {
    const auto& slope = slopes_[pace_[column]];
    return static_cast<float>(std::abs(slope.first)) / static_cast<float>(slope.second);
  }
  size_t smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& columns) const override;
  void setSequenceLength(int sequence_length) override;
  void setBidirectional(bool bidirectional) override;
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
  /// Query frames matched since the last reset.
  uint64_t queries() const
  {
    return queries_;
  }

private:
  /// Keeps the row aligned with the reference: drops evicted places, appends new ones at `prior`.
  void align(const PlaceDatabase& reference, size_t candidates);
  /// exact_ and near_ for the chunk of columns [begin, begin + m).
  void prepareChunk(const uint64_t* query, const PlaceDatabase& reference, size_t begin, size_t m);
  /// The smallest normalized() of chunk `chunk`, leaving out columns within `window` of a taken one.
  float chunkMinimum(size_t chunk, const std::vector<size_t>& taken, size_t window) const;
  float value(size_t column, int* direction) const;

  FrameMetric metric_;
  int sequence_length_;
  int max_pace_;
  bool bidirectional_;
  float step_penalty_;
  int tolerance_;
  std::vector<std::pair<int, int>> slopes_;  ///< paces as fractions p / q (negative: reverse)
  float keep_ = 0.0f;  ///< a = 1 - 1/L, the weight of the path so far
  float inverse_max_distance_ = 0.0f;
  uint64_t queries_ = 0;
  uint64_t evidence_ = 0;  ///< query frames that had places to match since the last reset
  uint64_t first_id_ = 0;
  float prior_ = 0.0f;
  float spread_ = 0.0f;  ///< the previous row's standard deviation of frame distances  ///< the previous row's mean frame distance: the start of a place that joins the row
  std::vector<std::vector<float>> rows_;  ///< C[j, v]: one row of places per pace, and pad_ typical ones after
  size_t pad_ = 4;  ///< more places than any pace advances in a frame
  std::vector<float> best_;      ///< M[j] at pad_ + j: the smallest of a place's costs, judged by its own distance
  std::vector<float> old_best_;  ///< the previous frame's M, while match() runs
  std::vector<uint8_t> pace_;  ///< the index in slopes_ of the pace M[j] comes from
  uint8_t one_ = 0;            ///< the index of pace 1
  size_t columns_ = 0;
  std::vector<float> chunk_minimum_;  ///< per chunk of columns, both directions, after match()
  // Scratch for one chunk of columns.
  std::vector<uint32_t> raw_;        ///< integer frame distances
  std::vector<float> exact_;  ///< d(t, j), normalised
  std::vector<float> near_;   ///< the smallest d(t, .) within pace_tolerance of j
  std::vector<float> old_;    ///< one pace's previous costs around a chunk
  std::vector<float> carry_;  ///< per pace, the previous frame's costs of the pad_ places before the chunk
  std::vector<long> steps_;   ///< places each pace advances this frame
  std::vector<int32_t> pace_chunk_;  ///< the chunk's best paces while match() runs
};

}  // namespace openable
