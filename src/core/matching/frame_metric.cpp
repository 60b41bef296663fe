#include "openable/matching/frame_metric.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "openable/error.h"
#include "openable/hamming/hamming.h"

namespace openable
{
namespace
{
/// L2 distance of two unit float vectors (0..2) as an integer 0..kFloatScale. Cells holding NaN or
/// infinity (a corrupt map: the describer never writes them) are as far as cells can be; converting NaN to
/// an integer would be undefined (found by fuzzing the map loader).
uint32_t quantizedL2(const uint64_t* a, const uint64_t* b, int length)
{
  const float d = l2Distance(reinterpret_cast<const float*>(a), reinterpret_cast<const float*>(b), length);
  const double scaled = std::round(double(d) * 0.5 * kFloatScale);
  if (!(scaled < kFloatScale))
    return kFloatScale;
  return static_cast<uint32_t>(scaled);
}
}  // namespace

FrameMetric::FrameMetric(const DescriptorLayout& layout) : layout_(layout)
{
  // Every distance below trusts the layout: a corrupt one would read past the descriptors.
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("FrameMetric: unsupported descriptor " + problem);
}

uint32_t FrameMetric::blockDistance(const uint64_t* a, const uint64_t* b) const
{
  const int cells_per_block = layout_.cells / layout_.blocks;
  if (layout_.binary)
    return hamming(a, b, static_cast<size_t>(cells_per_block) * layout_.cell_words);
  uint32_t sum = 0;
  for (int c = 0; c < cells_per_block; ++c)
    sum += quantizedL2(a + c * layout_.cell_words, b + c * layout_.cell_words, layout_.cell_length);
  return sum;
}

uint32_t FrameMetric::distance(const uint64_t* a, const uint64_t* b, int* shift) const
{
  if (shift)
    *shift = 0;
  const int blocks = layout_.blocks;
  if (blocks == 1)
    return blockDistance(a, b);
  // Every block of a against every block of b, then the one circular shift s whose sum of
  // d(a_i, b_{(i+s) mod blocks}) is smallest: a panorama seen from a rotated heading.
  const size_t words = layout_.blockWords();
  std::vector<uint32_t> d(static_cast<size_t>(blocks) * blocks);
  for (int i = 0; i < blocks; ++i)
    for (int j = 0; j < blocks; ++j)
      d[i * blocks + j] = blockDistance(a + i * words, b + j * words);
  uint32_t best = UINT32_MAX;
  for (int s = 0; s < blocks; ++s)
  {
    uint32_t sum = 0;
    for (int i = 0; i < blocks; ++i)
      sum += d[i * blocks + (i + s) % blocks];
    if (sum < best)
    {
      best = sum;
      if (shift)
        *shift = s;
    }
  }
  return best;
}

void FrameMetric::row(const uint64_t* query, const uint64_t* rows, size_t count, uint32_t* out) const
{
  const size_t stride = layout_.frameWords();
  if (layout_.binary && layout_.blocks == 1)
  {
    hammingRow(query, rows, stride, stride, count, out);
    return;
  }
  for (size_t i = 0; i < count; ++i)
    out[i] = distance(query, rows + i * stride);
}

void FrameMetric::rowNearest(const uint64_t* const* queries, size_t nq, const uint64_t* rows, size_t count,
                             uint32_t* out) const
{
  if (nq == 0)
    throw Error("FrameMetric::rowNearest: no query");
  const size_t stride = layout_.frameWords();
  if (layout_.binary && layout_.blocks == 1)
  {
    hammingRowNearest(queries, nq, rows, stride, stride, count, out);
    return;
  }
  for (size_t i = 0; i < count; ++i)
  {
    uint32_t nearest = distance(queries[0], rows + i * stride);
    for (size_t q = 1; q < nq; ++q)
      nearest = std::min(nearest, distance(queries[q], rows + i * stride));
    out[i] = nearest;
  }
}

void FrameMetric::rowDifference(const uint64_t* qa, const uint64_t* rows_a, const uint64_t* qb, const uint64_t* rows_b,
                                size_t count, int32_t* out) const
{
  const size_t stride = layout_.frameWords();
  if (layout_.binary && layout_.blocks == 1)
  {
    hammingRowDifference(qa, rows_a, qb, rows_b, stride, stride, count, out);
    return;
  }
  for (size_t i = 0; i < count; ++i)
    out[i] = int32_t(distance(qa, rows_a + i * stride)) - int32_t(distance(qb, rows_b + i * stride));
}

template <typename Sum>
uint32_t FrameMetric::chainStepOf(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                                  uint32_t carry, Sum* sums, Sum* leaving) const
{
  const size_t stride = layout_.frameWords();
  if (layout_.binary && layout_.blocks == 1)
    return hammingChainStep(qa, qb, rows, stride, stride, count, L, carry, sums, leaving);
  uint32_t smallest = UINT32_MAX;
  Sum before = static_cast<Sum>(carry);
  for (size_t i = 0; i < count; ++i)
  {
    const uint64_t* row = rows + i * stride;
    leaving[i + L] = static_cast<Sum>(distance(qb, row));
    const Sum old = sums[i];
    sums[i] = static_cast<Sum>(before + distance(qa, row) - leaving[i]);
    smallest = std::min<uint32_t>(smallest, sums[i]);
    before = old;
  }
  return smallest;
}

uint32_t FrameMetric::chainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                                uint32_t carry, uint32_t* sums, uint32_t* leaving) const
{
  return chainStepOf(qa, qb, rows, count, L, carry, sums, leaving);
}

uint32_t FrameMetric::chainStep(const uint64_t* qa, const uint64_t* qb, const uint64_t* rows, size_t count, size_t L,
                                uint32_t carry, uint16_t* sums, uint16_t* leaving) const
{
  return chainStepOf(qa, qb, rows, count, L, carry, sums, leaving);
}

}  // namespace openable
