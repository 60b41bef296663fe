#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "openable/matching/frame_metric.h"
#include "openable/map/place_database.h"
#include "openable/matching/row_matcher.h"

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
class SequenceMatcher : public RowMatcher
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
  void setSequenceLength(int sequence_length) override;
  void setBidirectional(bool bidirectional) override;
  /// Forgets every query frame and every sequence.
  void reset() override;

  /// Adds the next query frame and computes its row against reference positions [0, candidates).
  /// The reference may have grown or lost its oldest frames since the last call.
  void match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates) override;

  /// The current row covers reference ids [firstId(), firstId() + columns()).
  uint64_t firstId() const override
  {
    return first_id_;
  }
  size_t columns() const override
  {
    return forward_.size();
  }
  /// Query frames seen since the last reset.
  uint64_t queries() const
  {
    return queries_;
  }

  uint32_t forwardSum(size_t column) const
  {
    return forward_.sum(column);
  }
  uint16_t forwardCount(size_t column) const
  {
    return forward_.count[column];
  }
  uint32_t reverseSum(size_t column) const
  {
    return reverse_.sum(column);
  }
  uint16_t reverseCount(size_t column) const
  {
    return reverse_.count[column];
  }

  /// Mean term of the sequence in `column` divided by the largest frame distance: 0 = identical,
  /// 1 = every bit different. With bidirectional matching, the smaller of the two directions; `direction`
  /// (optional) receives +1 (same direction) or -1 (reverse).
  /// Sequences of fewer than `min_terms` frames are left out (NaN when neither direction has enough).
  float normalized(size_t column, int* direction = nullptr, int min_terms = 1) const override;
  uint16_t terms(size_t column, int direction) const override
  {
    return direction > 0 ? forwardCount(column) : reverseCount(column);
  }
  /// normalized() for every column.
  void normalizedRow(std::vector<float>& out, std::vector<int8_t>* directions = nullptr, int min_terms = 1) const;

  /// The best distinct places of the current row, as a detector picks them: repeatedly the column with the
  /// smallest normalized(column, nullptr, min_terms) (the lowest column on ties) that lies more than `window`
  /// columns from every column already taken, until `count` are taken or none is left. Returns the number
  /// of columns with a distance (normalized() finite). The same as scanning normalizedRow() `count` times,
  /// but runs of columns whose sequences are all full are summarised by their smallest sum while matching,
  /// so this reads the row's state only where a summary does not answer (the start of the stream, a chosen
  /// column's neighbourhood).
  size_t smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& columns) const override;

private:
  /// The chains of one direction: a sum and a term count a column. The sums are 16-bit when every possible sum
  /// fits (L times the largest frame distance below 65536: HOG-B up to L = 170), else 32-bit: the sums are the
  /// state read and written every frame beside the descriptors, so narrow ones save memory traffic.
  class Chains
  {
  public:
    /// `columns` empty chains.
    void assign(size_t columns, bool narrow);
    size_t size() const
    {
      return count.size();
    }
    /// New columns get empty chains.
    void resize(size_t columns);
    void eraseFront(size_t columns);
    uint32_t sum(size_t column) const
    {
      return narrow_ ? narrow_sums_[column] : wide_sums_[column];
    }
    void set(size_t column, uint32_t sum, uint16_t terms)
    {
      if (narrow_)
        narrow_sums_[column] = static_cast<uint16_t>(sum);
      else
        wide_sums_[column] = sum;
      count[column] = terms;
    }
    /// f(pointer to the first sum), whichever their width.
    template <typename F>
    auto withSums(F f)
    {
      return narrow_ ? f(narrow_sums_.data()) : f(wide_sums_.data());
    }
    /// f(pointer to the first sum, pointer to `terms` leaving terms of the sums' width): the scratch of
    /// FrameMetric::chainStep, kept from one call to the next (its last L terms are the next call's first).
    template <typename F>
    auto withSumsAndLeaving(size_t terms, F f)
    {
      if (narrow_)
      {
        narrow_leaving_.resize(terms);
        return f(narrow_sums_.data(), narrow_leaving_.data());
      }
      wide_leaving_.resize(terms);
      return f(wide_sums_.data(), wide_leaving_.data());
    }

    std::vector<uint16_t> count;

  private:
    bool narrow_ = false;
    std::vector<uint16_t> narrow_sums_;
    std::vector<uint32_t> wide_sums_;
    std::vector<uint16_t> narrow_leaving_;
    std::vector<uint32_t> wide_leaving_;
  };
  /// One chunk of columns after match(): when `full`, every chain in it (both directions with bidirectional)
  /// holds L terms and `minimum` is the smallest of their sums.
  struct ChunkSummary
  {
    uint32_t minimum = 0;
    bool full = false;
  };
  struct Carry  ///< the previous frame's chain of the column before a chunk, already overwritten in place
  {
    uint32_t sum = 0;
    uint16_t count = 0;
  };
  /// True when L times the largest frame distance fits 16 bits: the chains keep 16-bit sums (see Chains).
  bool narrowSums() const;
  const uint64_t* recentQuery(size_t age) const;
  float meanTerm(uint32_t sum, uint16_t count) const;
  /// `was_full`: the previous frame's summaries show that every chain this chunk continues was full.
  void advanceForward(const PlaceDatabase& reference, size_t begin, size_t end, bool was_full, Carry& carry,
                      ChunkSummary& summary);
  void advanceReverse(const PlaceDatabase& reference, size_t begin, size_t end, size_t old_columns, bool was_full,
                      ChunkSummary& summary);
  float chunkMinimum(size_t chunk, int min_terms, const std::vector<size_t>& taken, size_t window,
                     size_t* finite) const;

  FrameMetric metric_;
  int sequence_length_;
  bool bidirectional_;
  uint64_t queries_ = 0;
  uint64_t first_id_ = 0;
  Chains forward_;  ///< updated in place: no second buffer streamed through memory every frame
  Chains reverse_;
  std::vector<ChunkSummary> summaries_;           ///< per chunk of columns; empty when the chains changed since match()
  std::vector<ChunkSummary> previous_summaries_;  ///< the frame before's, while match() runs
  std::vector<uint64_t> recent_;                  ///< ring of the last L + 1 query descriptors
  /// The forward chains' leaving terms d(t - L, j - L) of the L columns before this one are in forward_'s
  /// scratch (withSumsAndLeaving), left there by the chunk before; none at the start of a frame.
  size_t leaving_ready_at_ = SIZE_MAX;
  // Scratch for one chunk of columns.
  std::vector<uint32_t> entering_;      ///< d(t, j)
  std::vector<uint32_t> leaving_;       ///< d(t - L, j -/+ L)
  std::vector<int32_t> change_;         ///< entering - leaving
  std::vector<uint32_t> previous_sum_;  ///< the previous frame's chains of the columns each one continues
  std::vector<uint16_t> previous_count_;
};

}  // namespace openable
