#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "openable/descriptors/descriptor_layout.h"

namespace openable
{
/// Distance between two frame descriptors (integers, 0 = identical, at most layout.maxFrameDistance()).
/// Binary: Hamming (Eq. 4). Float: per-cell L2 (Eq. 8) of unit vectors, scaled to integers.
/// Panoramic layouts (blocks > 1): the minimum, over circular shifts s of the sub-panoramas, of the summed
/// block distances d(a_b, b_{(b+s) mod blocks}): one consistent shift for the whole panorama.
class FrameMetric
{
public:
  explicit FrameMetric(const DescriptorLayout& layout);

  const DescriptorLayout& layout() const
  {
    return layout_;
  }
  uint32_t distance(const uint64_t* a, const uint64_t* b, int* shift = nullptr) const;
  /// distance() as a fraction of the largest possible one: 0 = identical, 1 = every bit (or unit vector) apart.
  double normalizedDistance(const uint64_t* a, const uint64_t* b) const
  {
    return static_cast<double>(distance(a, b)) / static_cast<double>(std::max<uint64_t>(1, layout_.maxFrameDistance()));
  }
  /// out[i] = distance(query, rows + i * frameWords()) for i < count.
  void row(const uint64_t* query, const uint64_t* rows, size_t count, uint32_t* out) const;
  /// out[i] = the smallest distance(queries[q], rows + i * frameWords()) over q < nq (nq >= 1): a frame and its
  /// views shifted sideways, each row read once (hammingRowNearest for plain binary layouts).
  void rowNearest(const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t count, uint32_t* out) const;
  /// out[i] = distance(qa, rows_a + i * frameWords()) - distance(qb, rows_b + i * frameWords()) for i < count,
  /// in one pass over both (hammingRowDifference for plain binary layouts).
  void rowDifference(const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b,
                     size_t count, int32_t* out) const;
  /// The steady-state step of sequence sums, in place, each row read once (hammingChainStep for plain binary
  /// layouts): for i < count, leaving[i + L] = distance(qb, row i) and sums[i] = before(i) + distance(qa, row i)
  /// - leaving[i], where before(0) = carry and before(i) is the old sums[i - 1]. `leaving` holds count + L terms,
  /// the first L the caller's. Returns the smallest new sum. 16-bit sums only where they fit.
  uint32_t chainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                     uint32_t carry, uint32_t* sums, uint32_t* leaving) const;
  uint32_t chainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                     uint32_t carry, uint16_t* sums, uint16_t* leaving) const;

private:
  template <typename Sum>
  uint32_t chainStepOf(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                       uint32_t carry, Sum* sums, Sum* leaving) const;
  uint32_t blockDistance(const uint64_t* a, const uint64_t* b) const;
  DescriptorLayout layout_;
};

}  // namespace openable
