#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "openable/frame_metric.h"
#include "openable/place_database.h"

namespace openable
{
/// Sequence distances of a stream of query frames against a reference database, updated online.
///
/// For the query frame t and a reference frame j, the forward sequence distance is
///   S(t, j) = sum_{k < n} d(t - k, j - k)
/// over the n = min(L, available) most recent terms, where a term is available when both frames exist and
/// the pair was comparable when the older query arrived (the "chain" of cells along the diagonal). It is
/// kept incrementally in O(N) per frame, whatever L is:
///   S_t[j] = S_{t-1}[j-1] + d(t, j) - d(t-L, j-L)      (the last term only once the chain holds L terms)
/// with exact integers and one row of state (no N x N matrix, no drift). With `bidirectional`, the reverse
/// sequence (the reference driven in the opposite direction) is kept the same way along anti-diagonals:
///   R_t[j] = R_{t-1}[j+1] + d(t, j) - d(t-L, j+L).
/// Each cell also keeps its term count n, so partial sequences (at the start of a stream, or of a new
/// chain) are compared by their mean term. A change of L restarts every chain.
class SequenceMatcher
{
public:
  SequenceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional);

  int sequenceLength() const
  {
    return sequence_length_;
  }
  bool bidirectional() const
  {
    return bidirectional_;
  }
  /// Restarts every sequence (the history of query frames is kept).
  void setSequenceLength(int sequence_length);
  void setBidirectional(bool bidirectional);
  /// Forgets every query frame and every sequence.
  void reset();

  /// Adds the next query frame and computes its row against reference positions [0, candidates).
  /// The reference may have grown or lost its oldest frames since the last call.
  void match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates);

  /// The current row covers reference ids [firstId(), firstId() + columns()).
  uint64_t firstId() const
  {
    return first_id_;
  }
  size_t columns() const
  {
    return forward_.sum.size();
  }
  /// Query frames seen since the last reset.
  uint64_t queries() const
  {
    return queries_;
  }

  uint32_t forwardSum(size_t column) const
  {
    return forward_.sum[column];
  }
  uint16_t forwardCount(size_t column) const
  {
    return forward_.count[column];
  }
  uint32_t reverseSum(size_t column) const
  {
    return reverse_.sum[column];
  }
  uint16_t reverseCount(size_t column) const
  {
    return reverse_.count[column];
  }

  /// Mean term of the sequence in `column` divided by the largest frame distance: 0 = identical,
  /// 1 = every bit different. With bidirectional matching, the smaller of the two directions; `direction`
  /// (optional) receives +1 (same direction) or -1 (reverse).
  /// Sequences of fewer than `min_terms` frames are left out (NaN when neither direction has enough).
  float normalized(size_t column, int* direction = nullptr, int min_terms = 1) const;
  /// normalized() for every column.
  void normalizedRow(std::vector<float>& out, std::vector<int8_t>* directions = nullptr, int min_terms = 1) const;

private:
  struct Chains
  {
    std::vector<uint32_t> sum;
    std::vector<uint16_t> count;
  };
  const uint64_t* recentQuery(size_t age) const;
  void advanceForward(const PlaceDatabase& reference, size_t columns);
  void advanceReverse(const PlaceDatabase& reference, size_t columns);

  FrameMetric metric_;
  int sequence_length_;
  bool bidirectional_;
  uint64_t queries_ = 0;
  uint64_t first_id_ = 0;
  Chains forward_;
  Chains reverse_;
  Chains next_;                   ///< the next frame's chains are built here, then swapped in (no copy)
  std::vector<uint64_t> recent_;  ///< ring of the last L + 1 query descriptors
  std::vector<uint32_t> current_distances_;
  std::vector<uint32_t> dropped_distances_;
};

}  // namespace openable
