#include "openable/sequence_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "openable/error.h"

namespace openable
{
namespace
{
/// Columns processed together: their descriptors (and those L frames earlier) stay in cache between the
/// two distance computations of the recurrence.
constexpr size_t kChunk = 256;

/// True when every count equals `full`: the chains of a chunk are all complete (the steady state).
bool allFull(const uint16_t* counts, size_t n, uint16_t full)
{
  bool all = true;
  for (size_t i = 0; i < n; ++i)
    all &= counts[i] == full;  // no early exit: the loop vectorises
  return all;
}

/// The steady-state recurrence, branch-free so that it vectorises: next = previous + entering - leaving.
void addAndDrop(const uint32_t* __restrict previous, const uint32_t* __restrict entering,
                const uint32_t* __restrict leaving, size_t n, uint32_t* __restrict next)
{
  for (size_t i = 0; i < n; ++i)
    next[i] = previous[i] + entering[i] - leaving[i];
}
}  // namespace

SequenceMatcher::SequenceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional)
  : metric_(layout), sequence_length_(1), bidirectional_(bidirectional)
{
  setSequenceLength(sequence_length);
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
  std::fill(forward_.sum.begin(), forward_.sum.end(), 0u);
  std::fill(forward_.count.begin(), forward_.count.end(), uint16_t(0));
  std::fill(reverse_.sum.begin(), reverse_.sum.end(), 0u);
  std::fill(reverse_.count.begin(), reverse_.count.end(), uint16_t(0));
  // Chains restart: the ring no longer holds the frames that would leave them. Count queries from here.
  queries_ = 0;
}

void SequenceMatcher::setBidirectional(bool bidirectional)
{
  if (bidirectional && !bidirectional_)
  {
    reverse_.sum.assign(forward_.sum.size(), 0u);
    reverse_.count.assign(forward_.count.size(), 0);
  }
  bidirectional_ = bidirectional;
}

void SequenceMatcher::reset()
{
  queries_ = 0;
  first_id_ = 0;
  forward_ = Chains();
  reverse_ = Chains();
}

const uint64_t* SequenceMatcher::recentQuery(size_t age) const
{
  const size_t slots = sequence_length_ + 1;
  const uint64_t index = queries_ - 1 - age;  // queries_ - 1 is the current query
  return recent_.data() + (index % slots) * metric_.layout().frameWords();
}

void SequenceMatcher::match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates)
{
  if (reference.layout() != metric_.layout())
    throw Error("SequenceMatcher: reference database descriptors do not match the query descriptors");
  candidates = std::min(candidates, reference.size());
  const size_t words = metric_.layout().frameWords();
  std::memcpy(recent_.data() + (queries_ % (sequence_length_ + 1)) * words, query, sizeof(uint64_t) * words);
  ++queries_;

  // Frames evicted from the front of the reference take their columns with them.
  const uint64_t new_first = reference.firstId();
  if (new_first != first_id_)
  {
    const size_t gone = static_cast<size_t>(std::min<uint64_t>(new_first - first_id_, forward_.sum.size()));
    for (Chains* chains : {&forward_, &reverse_})
    {
      const size_t n = std::min(gone, chains->sum.size());
      chains->sum.erase(chains->sum.begin(), chains->sum.begin() + static_cast<long>(n));
      chains->count.erase(chains->count.begin(), chains->count.begin() + static_cast<long>(n));
    }
    first_id_ = new_first;
  }
  // The reverse pass reuses this frame's distances; without it they live only chunk by chunk.
  current_distances_.resize(bidirectional_ ? candidates : kChunk);
  advanceForward(reference, candidates);
  if (bidirectional_)
    advanceReverse(reference, candidates);
}

void SequenceMatcher::advanceForward(const PlaceDatabase& reference, size_t columns)
{
  const size_t L = sequence_length_;
  const Chains& old = forward_;  // the previous frame's chains; columns that did not exist have count 0
  Chains& next = next_;
  next.sum.resize(columns);
  next.count.resize(columns);
  // With L = 1 every sequence is the current frame alone: nothing to carry over or drop.
  const bool can_drop = queries_ > L && L > 1;  // the query L frames ago exists
  const uint64_t* query = recentQuery(0);
  const uint64_t* leaving_query = can_drop ? recentQuery(L) : nullptr;
  dropped_distances_.resize(kChunk);

  // Ascending: the descriptors L frames back, needed for the leaving term, were read one or two chunks
  // ago and are still in cache, so the history is streamed from memory only once per frame.
  for (size_t begin = 0; begin < columns; begin += kChunk)
  {
    const size_t end = std::min(columns, begin + kChunk);
    uint32_t* current = current_distances_.data() + (bidirectional_ ? begin : 0);  // current[c - begin]
    metric_.row(query, reference.descriptor(begin), end - begin, current);
    const size_t drop_begin = std::max(begin, L);  // d(t - L, j - L) where j - L is stored
    if (can_drop && drop_begin < end)
      metric_.row(leaving_query, reference.descriptor(drop_begin - L), end - drop_begin,
                  dropped_distances_.data() + (drop_begin - begin));
    if (can_drop && begin >= L && end <= old.count.size() && allFull(old.count.data() + begin - 1, end - begin, L))
    {
      addAndDrop(old.sum.data() + begin - 1, current, dropped_distances_.data(), end - begin, next.sum.data() + begin);
      std::fill(next.count.begin() + long(begin), next.count.begin() + long(end), static_cast<uint16_t>(L));
      continue;
    }
    for (size_t c = begin; c < end; ++c)
    {
      const uint16_t previous_count = (L > 1 && c > 0 && c - 1 < old.count.size()) ? old.count[c - 1] : 0;
      const uint32_t entering = current[c - begin];
      if (previous_count == 0)
      {
        next.sum[c] = entering;
        next.count[c] = 1;
      }
      else if (previous_count < L)
      {
        next.sum[c] = old.sum[c - 1] + entering;
        next.count[c] = previous_count + 1;
      }
      else if (c >= L && can_drop)
      {
        next.sum[c] = old.sum[c - 1] + entering - dropped_distances_[c - begin];
        next.count[c] = static_cast<uint16_t>(L);
      }
      else
      {
        // The frame leaving the sequence was evicted from a bounded history: the chain starts again.
        next.sum[c] = entering;
        next.count[c] = 1;
      }
    }
  }
  std::swap(forward_, next_);
}

void SequenceMatcher::advanceReverse(const PlaceDatabase& reference, size_t columns)
{
  const size_t L = sequence_length_;
  const Chains& old = reverse_;
  Chains& next = next_;
  next.sum.resize(columns);
  next.count.resize(columns);
  const size_t stored = reference.size();
  const bool can_drop = queries_ > L;
  const uint64_t* leaving_query = can_drop ? recentQuery(L) : nullptr;
  const uint32_t* current = current_distances_.data();
  dropped_distances_.resize(kChunk);

  // R_t[j] = R_{t-1}[j + 1] + d(t, j) - d(t - L, j + L). Descending, so that the descriptors L frames
  // ahead were read one or two chunks ago.
  for (size_t end = columns; end > 0;)
  {
    const size_t begin = end > kChunk ? end - kChunk : 0;
    const size_t drop_end = std::min(end, stored > L ? stored - L : 0);
    if (can_drop && begin < drop_end)
      metric_.row(leaving_query, reference.descriptor(begin + L), drop_end - begin, dropped_distances_.data());
    if (can_drop && end <= drop_end && end < old.count.size() && allFull(old.count.data() + begin + 1, end - begin, L))
    {
      addAndDrop(old.sum.data() + begin + 1, current + begin, dropped_distances_.data(), end - begin,
                 next.sum.data() + begin);
      std::fill(next.count.begin() + long(begin), next.count.begin() + long(end), static_cast<uint16_t>(L));
      end = begin;
      continue;
    }
    for (size_t c = begin; c < end; ++c)
    {
      const uint16_t previous_count = c + 1 < old.count.size() ? old.count[c + 1] : 0;
      if (previous_count == 0)
      {
        next.sum[c] = current[c];
        next.count[c] = 1;
      }
      else if (previous_count < L)
      {
        next.sum[c] = old.sum[c + 1] + current[c];
        next.count[c] = previous_count + 1;
      }
      else if (c < drop_end && can_drop)
      {
        next.sum[c] = old.sum[c + 1] + current[c] - dropped_distances_[c - begin];
        next.count[c] = static_cast<uint16_t>(L);
      }
      else
      {
        next.sum[c] = current[c];
        next.count[c] = 1;
      }
    }
    end = begin;
  }
  std::swap(reverse_, next_);
}

float SequenceMatcher::normalized(size_t column, int* direction, int min_terms) const
{
  const double max_distance = double(metric_.layout().maxFrameDistance());
  const int needed = std::max(1, min_terms);
  const uint16_t n = forward_.count[column];
  float best = n >= needed ? static_cast<float>(forward_.sum[column] / (n * max_distance)) : std::nanf("");
  int dir = 1;
  if (bidirectional_)
  {
    const uint16_t r = reverse_.count[column];
    if (r >= needed)
    {
      const float reverse = static_cast<float>(reverse_.sum[column] / (r * max_distance));
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

}  // namespace openable
