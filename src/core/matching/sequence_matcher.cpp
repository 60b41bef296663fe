#include "openable/matching/sequence_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "openable/error.h"

namespace openable
{
namespace
{
/// One chain one frame on: the previous frame's chain (sum, count) of the column before (forward) or after
/// (reverse) takes the entering term; a full chain of L terms drops its leaving term too, when that term
/// still exists (`can_leave`), else it starts again (the frame leaving was evicted from a bounded history).
inline void extendChain(uint32_t previous_sum, uint16_t previous_count, uint32_t entering, uint32_t leaving,
                        bool can_leave, size_t L, uint32_t& sum, uint16_t& count)
{
  if (previous_count == 0)
  {
    sum = entering;
    count = 1;
  }
  else if (previous_count < L)
  {
    sum = previous_sum + entering;
    count = previous_count + 1;
  }
  else if (can_leave)
  {
    sum = previous_sum + entering - leaving;
    count = static_cast<uint16_t>(L);
  }
  else
  {
    sum = entering;
    count = 1;
  }
}

/// Columns processed together: their descriptors (and those L frames earlier) stay in cache between the
/// two distance computations of the recurrence, and each chunk gets one summary for smallestDistinct().
constexpr size_t kChunk = 256;

/// True when every count equals `value`.
bool allEqual(const uint16_t* counts, size_t n, uint16_t value)
{
  uint16_t differences = 0;
  for (size_t i = 0; i < n; ++i)
    differences |= counts[i] ^ value;  // no early exit and no bool: the loop vectorises
  return differences == 0;
}

/// out[i] = previous[i] + change[i] for i < n, and their minimum: the steady-state recurrence, branch-free so
/// that it vectorises. The sums are exact: a chain's sum minus its leaving term is never negative.
template <typename Sum>
uint32_t addChanges(const uint32_t* __restrict previous, const int32_t* __restrict change, size_t n,
                    Sum* __restrict out)
{
  uint32_t minimum = UINT32_MAX;
  for (size_t i = 0; i < n; ++i)
  {
    out[i] = static_cast<Sum>(previous[i] + static_cast<uint32_t>(change[i]));
    minimum = std::min<uint32_t>(minimum, out[i]);
  }
  return minimum;
}
}  // namespace

void SequenceMatcher::Chains::assign(size_t columns, bool narrow)
{
  narrow_ = narrow;
  narrow_sums_.assign(narrow ? columns : 0, 0);
  wide_sums_.assign(narrow ? 0 : columns, 0);
  count.assign(columns, 0);
}

void SequenceMatcher::Chains::resize(size_t columns)
{
  if (narrow_)
    narrow_sums_.resize(columns);
  else
    wide_sums_.resize(columns);
  count.resize(columns);
}

void SequenceMatcher::Chains::eraseFront(size_t columns)
{
  const auto erase = [&](auto& values)
  { values.erase(values.begin(), values.begin() + static_cast<long>(std::min(columns, values.size()))); };
  erase(narrow_sums_);
  erase(wide_sums_);
  erase(count);
}

SequenceMatcher::SequenceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional)
  : metric_(layout), sequence_length_(1), bidirectional_(bidirectional)
{
  setSequenceLength(sequence_length);
  entering_.resize(kChunk);
  leaving_.resize(kChunk);
  change_.resize(kChunk);
  previous_sum_.resize(kChunk);
  previous_count_.resize(kChunk);
}

void SequenceMatcher::setSequenceLength(int sequence_length)
{
  if (sequence_length < 1 || sequence_length > std::numeric_limits<uint16_t>::max())
    throw Error("sequence_length " + std::to_string(sequence_length) + " is out of range; expected 1..65535");
  // Sums are 32-bit: L full-distance frames must fit.
  if (uint64_t(sequence_length) * metric_.layout().maxFrameDistance() > std::numeric_limits<uint32_t>::max())
    throw Error("sequence_length " + std::to_string(sequence_length) +
                " is too long for descriptors of this size (sequence sums would overflow)");
  sequence_length_ = sequence_length;
  // Keep the last L + 1 query descriptors: the recurrence needs the frame that leaves the sequence.
  const size_t words = metric_.layout().frameWords();
  std::vector<uint64_t> recent(words * (sequence_length_ + 1), 0);
  recent_.swap(recent);
  forward_.assign(forward_.size(), narrowSums());
  reverse_.assign(reverse_.size(), narrowSums());
  summaries_.clear();
  // Chains restart: the ring no longer holds the frames that would leave them. Count queries from here.
  queries_ = 0;
}

void SequenceMatcher::setBidirectional(bool bidirectional)
{
  if (bidirectional && !bidirectional_)
  {
    reverse_.assign(forward_.size(), narrowSums());
  }
  bidirectional_ = bidirectional;
  summaries_.clear();
}

void SequenceMatcher::reset()
{
  queries_ = 0;
  first_id_ = 0;
  forward_.assign(0, narrowSums());
  reverse_.assign(0, narrowSums());
  summaries_.clear();
}

bool SequenceMatcher::narrowSums() const
{
  return uint64_t(sequence_length_) * metric_.layout().maxFrameDistance() <= UINT16_MAX;
}

const uint64_t* SequenceMatcher::recentQuery(size_t age) const
{
  const size_t slots = sequence_length_ + 1;
  const uint64_t index = queries_ - 1 - age;  // queries_ - 1 is the current query
  return recent_.data() + (index % slots) * metric_.layout().frameWords();
}

float SequenceMatcher::meanTerm(uint32_t sum, uint16_t count) const
{
  return static_cast<float>(sum / (count * double(metric_.layout().maxFrameDistance())));
}

void SequenceMatcher::match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates)
{
  if (reference.layout() != metric_.layout())
    throw Error("SequenceMatcher: reference database descriptors do not match the query descriptors");
  candidates = std::min(candidates, reference.size());
  const size_t words = metric_.layout().frameWords();
  std::memcpy(recent_.data() + (queries_ % (sequence_length_ + 1)) * words, query, sizeof(uint64_t) * words);
  ++queries_;

  // The previous frame's summaries say which chunks held only full chains, so that their counts need not be
  // read again. Valid while the columns stay where they were (cleared when the chains restart).
  previous_summaries_.swap(summaries_);
  // Frames evicted from the front of the reference take their columns with them.
  const uint64_t new_first = reference.firstId();
  if (new_first != first_id_)
  {
    previous_summaries_.clear();
    const size_t gone = static_cast<size_t>(std::min<uint64_t>(new_first - first_id_, forward_.size()));
    forward_.eraseFront(gone);
    reverse_.eraseFront(gone);
    first_id_ = new_first;
  }

  // The chains are updated in place, one chunk of columns after the other, both directions in the same pass
  // over the descriptors. Columns that did not exist in the previous frame start with count 0 (no chain).
  const size_t columns = candidates;
  const size_t old_forward_columns = forward_.size();
  forward_.resize(columns);
  const size_t old_reverse_columns = reverse_.size();
  if (bidirectional_ && old_reverse_columns < columns)
    reverse_.resize(columns);
  summaries_.assign((columns + kChunk - 1) / kChunk, ChunkSummary());
  const auto wasFull = [&](size_t chunk)
  { return chunk < previous_summaries_.size() && previous_summaries_[chunk].full; };
  Carry carry;                   // column -1 has no chain
  leaving_ready_at_ = SIZE_MAX;  // a new query leaves: its terms are not computed yet
  for (size_t begin = 0; begin < columns; begin += kChunk)
  {
    const size_t end = std::min(columns, begin + kChunk);
    const size_t chunk = begin / kChunk;
    ChunkSummary& summary = summaries_[chunk];
    // Forward chains continue columns begin - 1 .. end - 2 (the first one is the carry's), reverse ones
    // columns begin + 1 .. end (the last one in the next chunk).
    advanceForward(reference, begin, end, wasFull(chunk) && end - 1 <= old_forward_columns, carry, summary);
    if (bidirectional_)
      advanceReverse(reference, begin, end, old_reverse_columns, wasFull(chunk) && wasFull(chunk + 1), summary);
  }
  if (bidirectional_)
  {
    // Only now: the reverse chain of the last column continued the previous frame's of the next one.
    reverse_.resize(columns);
  }
}

// S_t[j] = S_{t-1}[j - 1] + d(t, j) - d(t - L, j - L), in place: column j takes the old sum of j - 1, so the
// old values of the chunk are copied aside first (one chunk, in cache) and the old value of the chunk's last
// column is carried to the next chunk, whose first column needs it. Ascending: in the steady state each
// descriptor is read once (its leaving term is kept for the column L on, below); elsewhere the descriptors L
// columns back, read for the leaving term, were read one or two chunks ago and are still in cache.
void SequenceMatcher::advanceForward(const PlaceDatabase& reference, size_t begin, size_t end, bool was_full,
                                     Carry& carry, ChunkSummary& summary)
{
  const size_t L = sequence_length_;
  const size_t n = end - begin;
  uint16_t* count = forward_.count.data();
  const uint64_t* query = recentQuery(0);
  const Carry before = carry;
  carry = Carry{forward_.sum(end - 1), count[end - 1]};
  uint32_t* entering = entering_.data();

  if (L == 1)
  {
    // Every sequence is the current frame alone: nothing to carry over or drop.
    metric_.row(query, reference.descriptor(begin), n, entering);
    for (size_t i = 0; i < n; ++i)
      forward_.set(begin + i, entering[i], 1);
    summary.minimum = *std::min_element(entering, entering + n);
    summary.full = true;
    return;
  }
  const bool can_drop = queries_ > L;  // the query L frames ago exists
  const uint64_t* leaving_query = can_drop ? recentQuery(L) : nullptr;

  // The steady state: every chain of the previous frame's columns begin - 1 .. end - 2 was full, so every new
  // one is. One fused pass adds the entering and drops the leaving terms in place; the counts stay L (only the
  // last column's is new: the others already held L).
  // Each descriptor is read once: its distance to the query L frames ago is kept for the column L on, and
  // chunk after chunk those terms carry over (only a frame's first steady chunk computes its L first ones).
  if (can_drop && begin >= L && before.count == L &&
      (was_full || allEqual(count + begin, n - 1, static_cast<uint16_t>(L))))
  {
    summary.minimum = forward_.withSumsAndLeaving(
        kChunk + L,
        [&](auto* sums, auto* leaving)
        {
          using Term = std::remove_pointer_t<decltype(leaving)>;
          if (leaving_ready_at_ != begin)
            for (size_t i = 0; i < L; ++i)
              leaving[i] = static_cast<Term>(metric_.distance(leaving_query, reference.descriptor(begin - L + i)));
          const uint32_t minimum = metric_.chainStep(query, leaving_query, reference.descriptor(begin), n, L,
                                                     before.sum, sums + begin, leaving);
          std::memmove(leaving, leaving + n, L * sizeof(Term));
          return minimum;
        });
    leaving_ready_at_ = end;
    summary.full = true;
    count[end - 1] = static_cast<uint16_t>(L);
    return;
  }

  uint32_t* previous_sum = previous_sum_.data();
  uint16_t* previous_count = previous_count_.data();
  previous_sum[0] = before.sum;
  previous_count[0] = before.count;
  for (size_t i = 1; i < n; ++i)
  {
    previous_sum[i] = forward_.sum(begin + i - 1);
    previous_count[i] = count[begin + i - 1];
  }
  metric_.row(query, reference.descriptor(begin), n, entering);
  const size_t drop_begin = std::max(begin, L);  // d(t - L, j - L) where j - L is stored
  if (can_drop && drop_begin < end)
    metric_.row(leaving_query, reference.descriptor(drop_begin - L), end - drop_begin,
                leaving_.data() + (drop_begin - begin));
  summary.full = false;
  for (size_t i = 0; i < n; ++i)
  {
    const size_t c = begin + i;
    uint32_t sum;
    uint16_t terms;
    extendChain(previous_sum[i], previous_count[i], entering[i], leaving_[i], c >= L && can_drop, L, sum, terms);
    forward_.set(c, sum, terms);
  }
}

// R_t[j] = R_{t-1}[j + 1] + d(t, j) - d(t - L, j + L), in place: column j takes the old sum of j + 1, which
// ascending order has not overwritten yet (the next chunk's first column included). The leaving descriptors
// L columns ahead come from memory here and are in cache when the forward pass reaches them.
void SequenceMatcher::advanceReverse(const PlaceDatabase& reference, size_t begin, size_t end, size_t old_columns,
                                     bool was_full, ChunkSummary& summary)
{
  const size_t L = sequence_length_;
  const size_t n = end - begin;
  const size_t stored = reference.size();
  const bool can_drop = queries_ > L;
  const uint64_t* query = recentQuery(0);
  const uint64_t* leaving_query = can_drop ? recentQuery(L) : nullptr;
  const size_t drop_end = std::min(end, stored > L ? stored - L : 0);  // d(t - L, j + L) where j + L is stored
  uint16_t* count = reverse_.count.data();
  uint32_t* previous_sum = previous_sum_.data();
  uint16_t* previous_count = previous_count_.data();

  if (can_drop && end <= drop_end && end < old_columns &&
      (was_full || allEqual(count + begin + 1, n, static_cast<uint16_t>(L))))
  {
    metric_.rowDifference(query, reference.descriptor(begin), leaving_query, reference.descriptor(begin + L), n,
                          change_.data());
    const uint32_t minimum = reverse_.withSums(
        [&](auto* sums)
        {
          std::copy(sums + begin + 1, sums + end + 1, previous_sum);
          return addChanges(previous_sum, change_.data(), n, sums + begin);
        });
    summary.minimum = std::min(summary.minimum, minimum);
    count[begin] = static_cast<uint16_t>(L);
    return;
  }

  summary.full = false;
  uint32_t* entering = entering_.data();
  metric_.row(query, reference.descriptor(begin), n, entering);
  if (can_drop && begin < drop_end)
    metric_.row(leaving_query, reference.descriptor(begin + L), drop_end - begin, leaving_.data());
  for (size_t i = 0; i < n; ++i)
  {
    const size_t c = begin + i;
    previous_count[i] = c + 1 < old_columns ? count[c + 1] : 0;
    previous_sum[i] = c + 1 < old_columns ? reverse_.sum(c + 1) : 0;
  }
  for (size_t i = 0; i < n; ++i)
  {
    const size_t c = begin + i;
    uint32_t sum;
    uint16_t terms;
    extendChain(previous_sum[i], previous_count[i], entering[i], leaving_[i], c < drop_end && can_drop, L, sum, terms);
    reverse_.set(c, sum, terms);
  }
}

float SequenceMatcher::normalized(size_t column, int* direction, int min_terms) const
{
  const int needed = std::max(1, min_terms);
  const uint16_t n = forward_.count[column];
  float best = n >= needed ? meanTerm(forward_.sum(column), n) : std::nanf("");
  int dir = 1;
  if (bidirectional_)
  {
    const uint16_t r = reverse_.count[column];
    if (r >= needed)
    {
      const float reverse = meanTerm(reverse_.sum(column), r);
      if (!(reverse >= best))  // also when best is NaN
      {
        best = reverse;
        dir = -1;
      }
    }
  }
  if (direction)
    *direction = dir;
  return best;
}

void SequenceMatcher::normalizedRow(std::vector<float>& out, std::vector<int8_t>* directions, int min_terms) const
{
  out.resize(columns());
  if (directions)
    directions->resize(columns());
  for (size_t c = 0; c < columns(); ++c)
  {
    int dir = 1;
    out[c] = normalized(c, &dir, min_terms);
    if (directions)
      (*directions)[c] = static_cast<int8_t>(dir);
  }
}

float SequenceMatcher::chunkMinimum(size_t chunk, int min_terms, const std::vector<size_t>& taken, size_t window,
                                    size_t* finite) const
{
  const size_t begin = chunk * kChunk;
  const size_t end = std::min(columns(), begin + kChunk);
  const auto masked = [&](size_t c)
  {
    for (size_t t : taken)
      if (c + window >= t && c <= t + window)
        return true;
    return false;
  };
  bool any_masked = false;
  for (size_t t : taken)
    any_masked |= t + window >= begin && t <= end - 1 + window;
  // A full chunk's smallest normalized distance is that of its smallest sum (all have L terms, and the
  // division is monotonic): the same float a scan of the chunk would find.
  if (!any_masked && chunk < summaries_.size() && summaries_[chunk].full && sequence_length_ >= std::max(1, min_terms))
  {
    if (finite)
      *finite += end - begin;
    return meanTerm(summaries_[chunk].minimum, static_cast<uint16_t>(sequence_length_));
  }
  float best = std::nanf("");
  for (size_t c = begin; c < end; ++c)
  {
    if (any_masked && masked(c))
      continue;
    const float d = normalized(c, nullptr, min_terms);
    if (!std::isfinite(d))
      continue;
    if (finite)
      ++*finite;
    if (!(d >= best))  // also when best is NaN
      best = d;
  }
  return best;
}

size_t SequenceMatcher::smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& taken) const
{
  taken.clear();
  const size_t chunks = (columns() + kChunk - 1) / kChunk;
  std::vector<float> minimum(chunks);
  size_t finite = 0;
  for (size_t k = 0; k < chunks; ++k)
    minimum[k] = chunkMinimum(k, min_terms, taken, window, &finite);
  while (taken.size() < count)
  {
    // The first chunk holding the smallest distance holds the first column with it.
    size_t best = chunks;
    for (size_t k = 0; k < chunks; ++k)
      if (std::isfinite(minimum[k]) && (best == chunks || minimum[k] < minimum[best]))
        best = k;
    if (best == chunks)
      break;
    const auto masked = [&](size_t c)
    { return std::any_of(taken.begin(), taken.end(), [&](size_t t) { return c + window >= t && c <= t + window; }); };
    size_t column = best * kChunk;
    while (masked(column) || normalized(column, nullptr, min_terms) != minimum[best])
      ++column;
    taken.push_back(column);
    // The chunks its window covers lose those columns.
    const size_t from = column > window ? column - window : 0;
    const size_t to = std::min(columns() - 1, column + window);
    for (size_t k = from / kChunk; k <= to / kChunk; ++k)
      minimum[k] = chunkMinimum(k, min_terms, taken, window, nullptr);
  }
  return finite;
}

}  // namespace openable
