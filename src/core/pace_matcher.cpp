#include "openable/pace_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "openable/error.h"

namespace openable
{
namespace
{
/// Columns processed together: one chunk of distances stays in L1, and each chunk gets one minimum for
/// smallestDistinct().
constexpr size_t kChunk = 256;
/// The cost of a path that does not exist (before the first place): never the minimum, never overflows.
constexpr float kNoPath = 1e30f;

/// The paces of max_pace as fractions p / 60 (places per frame), slowest first: from 1 / max_pace to max_pace
/// in steps of a factor kPaceStep, 1 exactly among them. Between two neighbours a straight line drifts by one
/// place in about 1 / (pace * (kPaceStep - 1)) frames.
constexpr double kPaceStep = 1.15;
std::vector<std::pair<int, int>> slopesFor(int max_pace)
{
  const int steps = static_cast<int>(std::ceil(std::log(static_cast<double>(max_pace)) / std::log(kPaceStep)));
  std::vector<std::pair<int, int>> slopes;
  const auto add = [&slopes](double pace)
  {
    const int p = std::max(1, static_cast<int>(std::lround(pace * 60.0)));
    if (slopes.empty() || slopes.back().first != p)
      slopes.emplace_back(p, 60);
  };
  for (int k = -steps; k <= steps; ++k)
    add(std::min<double>(max_pace, std::max(1.0 / max_pace, std::pow(kPaceStep, k))));
  return slopes;
}

/// Places a pace of p / q advances at frame t: the straight line's position floor(t p / q), differenced.
int stepAt(uint64_t t, int p, int q)
{
  return static_cast<int>((t + 1) * static_cast<uint64_t>(p) / static_cast<uint64_t>(q) -
                          t * static_cast<uint64_t>(p) / static_cast<uint64_t>(q));
}
}  // namespace

PaceMatcher::PaceMatcher(const DescriptorLayout& layout, int sequence_length, bool bidirectional,
                         const PaceOptions& options)
  : metric_(layout),
    sequence_length_(1),
    max_pace_(options.max_pace),
    bidirectional_(bidirectional),
    step_penalty_(options.penalty),
    tolerance_(options.tolerance),
    inverse_max_distance_(1.0f / static_cast<float>(std::max<uint64_t>(1, layout.maxFrameDistance())))
{
  if (max_pace_ < 1 || max_pace_ > 64)
    throw Error("max_pace " + std::to_string(max_pace_) + " is out of range; expected 1..64 places per frame");
  if (!std::isfinite(step_penalty_) || step_penalty_ < 0.0f)
    throw Error("pace_penalty must be finite and >= 0");
  if (tolerance_ < 0 || tolerance_ > 2)
    throw Error("pace_tolerance " + std::to_string(tolerance_) + " is out of range; expected 0..2 places");
  setSequenceLength(sequence_length);
  raw_.resize(kChunk + 2 * static_cast<size_t>(tolerance_));
  distances_.resize(kChunk);
}

void PaceMatcher::setSequenceLength(int sequence_length)
{
  if (sequence_length < 1 || sequence_length > std::numeric_limits<uint16_t>::max())
    throw Error("sequence_length " + std::to_string(sequence_length) + " is out of range; expected 1..65535");
  sequence_length_ = sequence_length;
  keep_ = 1.0f - 1.0f / static_cast<float>(sequence_length);
  reset();
}

void PaceMatcher::setBidirectional(bool bidirectional)
{
  bidirectional_ = bidirectional;
  reset();
}

void PaceMatcher::reset()
{
  slopes_ = slopesFor(max_pace_);
  if (bidirectional_)
  {
    const size_t forward = slopes_.size();
    for (size_t v = 0; v < forward; ++v)
      slopes_.emplace_back(-slopes_[v].first, slopes_[v].second);
  }
  const size_t slopes = slopes_.size();
  one_ = static_cast<uint8_t>(std::find(slopes_.begin(), slopes_.end(), std::make_pair(60, 60)) - slopes_.begin());
  reach_ = 1;
  for (const auto& slope : slopes_)
    reach_ = std::max(reach_, static_cast<size_t>((std::abs(slope.first) + slope.second - 1) / slope.second));
  const size_t reach = reach_;
  old_costs_.assign((kChunk + 2 * reach) * slopes, kNoPath);
  old_best_.assign(kChunk + 2 * reach, kNoPath);
  queries_ = 0;
  evidence_ = 0;
  columns_ = 0;
  costs_.clear();
  best_.clear();
  pace_.clear();
  chunk_minimum_.clear();
}

void PaceMatcher::align(const PlaceDatabase& reference, size_t candidates)
{
  const size_t slopes = slopes_.size();
  candidates = std::min(candidates, reference.size());
  if (reference.firstId() < first_id_ || (columns_ == 0 && reference.firstId() != first_id_))
  {
    // The reference restarted (or this is the first row): nothing of the old row applies.
    columns_ = 0;
    costs_.clear();
    best_.clear();
    pace_.clear();
    first_id_ = reference.firstId();
  }
  if (reference.firstId() > first_id_)
  {
    const size_t gone = static_cast<size_t>(std::min<uint64_t>(reference.firstId() - first_id_, columns_));
    costs_.erase(costs_.begin(), costs_.begin() + static_cast<long>(gone * slopes));
    best_.erase(best_.begin(), best_.begin() + static_cast<long>(gone));
    pace_.erase(pace_.begin(), pace_.begin() + static_cast<long>(gone));
    columns_ -= gone;
    first_id_ = reference.firstId();
  }
  // Places that join the row start as typical; places that left it (the exclusion grew) are dropped.
  columns_ = candidates;
  costs_.resize(candidates * slopes, prior_);
  best_.resize(candidates, prior_);
  pace_.resize(candidates, one_);
}

void PaceMatcher::match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates)
{
  const bool first_row = columns_ == 0;
  align(reference, candidates);
  const size_t n = columns_;
  chunk_minimum_.assign((n + kChunk - 1) / kChunk, kNoPath);
  if (n == 0)
    return;
  const uint64_t t = queries_++;
  ++evidence_;
  const size_t slopes = slopes_.size();
  const size_t reach = reach_;
  // Where each pace's path came from this frame, as an offset into the chunk's copy of the previous row.
  std::vector<long> source(slopes);
  for (size_t v = 0; v < slopes; ++v)
  {
    const int p = slopes_[v].first;
    const int step = stepAt(t, std::abs(p), slopes_[v].second);
    source[v] = static_cast<long>(reach) - (p > 0 ? step : -step);
  }
  // A row's first frame has no path behind it: every place starts from its own distance.
  const float keep = first_row ? 0.0f : keep_;
  const float fresh = 1.0f - keep;
  // Changing pace costs `step_penalty_` standard deviations of a path's cost under noise: the frame distances
  // of the previous row spread by spread_, their weighted mean over the path by spread_ * sqrt(fresh / (1 + keep)).
  // So a path changes pace for a real change of the revisit, not to chase the noise of one frame, whatever the
  // data, the descriptor and L are.
  const float change_cost = keep > 0.0f ? step_penalty_ * spread_ * std::sqrt(fresh / (1.0f + keep)) : 0.0f;
  // The previous frame's costs of the `reach` places before the chunk (already overwritten in place). Before
  // the first place and after the last, a path starts afresh: typical, as a place that joins the row.
  std::fill(old_costs_.begin(), old_costs_.begin() + static_cast<long>(reach * slopes), prior_);
  std::fill(old_best_.begin(), old_best_.begin() + static_cast<long>(reach), prior_);
  double distance_sum = 0.0, square_sum = 0.0;
  for (size_t begin = 0, chunk = 0; begin < n; begin += kChunk, ++chunk)
  {
    const size_t m = std::min(kChunk, n - begin);
    // The chunk's distances and `tolerance` places on each side.
    const size_t tolerance = static_cast<size_t>(tolerance_);
    const size_t low = begin > tolerance ? begin - tolerance : 0;
    const size_t high = std::min(n, begin + m + tolerance);
    metric_.row(query, reference.descriptor(low), high - low, raw_.data());
    const uint32_t* own = raw_.data() + (begin - low);
    // The previous frame's costs of this chunk and of the `reach` places after it, not yet overwritten.
    const size_t after = std::min(n, begin + m + reach) - begin;
    std::copy(costs_.begin() + static_cast<long>(begin * slopes),
              costs_.begin() + static_cast<long>((begin + after) * slopes),
              old_costs_.begin() + static_cast<long>(reach * slopes));
    std::fill(old_costs_.begin() + static_cast<long>((reach + after) * slopes), old_costs_.end(), prior_);
    std::copy(best_.begin() + static_cast<long>(begin), best_.begin() + static_cast<long>(begin + after),
              old_best_.begin() + static_cast<long>(reach));
    std::fill(old_best_.begin() + static_cast<long>(reach + after), old_best_.end(), prior_);

    float minimum = kNoPath;
    for (size_t i = 0; i < m; ++i)
    {
      // A path may be off its line by `tolerance` places (a pace between two of the slopes): each frame counts
      // the nearest of the place and its neighbours within it.
      const size_t j = begin + i;
      uint32_t nearest = own[i];
      for (size_t k = 1; k <= tolerance; ++k)
      {
        if (j >= k)
          nearest = std::min(nearest, own[static_cast<long>(i) - static_cast<long>(k)]);
        if (j + k < n)
          nearest = std::min(nearest, own[i + k]);
      }
      const float exact = static_cast<float>(own[i]) * inverse_max_distance_;
      distance_sum += exact;
      square_sum += double(exact) * exact;
      const float d = static_cast<float>(nearest) * inverse_max_distance_;
      float best = kNoPath;
      uint8_t pace = one_;
      float* costs = costs_.data() + (begin + i) * slopes;
      for (size_t v = 0; v < slopes; ++v)
      {
        const size_t from = static_cast<size_t>(static_cast<long>(i) + source[v]);
        // Keep the pace, or take the place's best path at any pace for the penalty (the robot sped up or slowed down).
        const float* before = old_costs_.data() + from * slopes;
        const float changed = old_best_[from];
        const float path = std::min(before[v], changed + change_cost);
        costs[v] = fresh * d + keep * path;
        if (costs[v] < best)
        {
          best = costs[v];
          pace = static_cast<uint8_t>(v);
        }
      }
      // The place itself is judged by its own distance this frame: the tolerance is for the path behind it.
      best += fresh * (exact - d);
      best_[begin + i] = best;
      pace_[begin + i] = pace;
      minimum = std::min(minimum, best);
    }
    chunk_minimum_[chunk] = minimum;
    // The next chunk's "before" places: this chunk's last `reach` ones, as they were.
    std::copy(old_costs_.begin() + static_cast<long>(m * slopes),
              old_costs_.begin() + static_cast<long>((m + reach) * slopes), old_costs_.begin());
    std::copy(old_best_.begin() + static_cast<long>(m), old_best_.begin() + static_cast<long>(m + reach),
              old_best_.begin());
  }
  prior_ = static_cast<float>(distance_sum / static_cast<double>(n));
  spread_ = static_cast<float>(std::sqrt(std::max(0.0, square_sum / static_cast<double>(n) - double(prior_) * prior_)));
}

float PaceMatcher::value(size_t column, int* direction) const
{
  if (direction)
    *direction = slopes_[pace_[column]].first > 0 ? 1 : -1;
  return best_[column];
}

float PaceMatcher::normalized(size_t column, int* direction, int min_terms) const
{
  const float best = value(column, direction);
  if (evidence_ < static_cast<uint64_t>(std::min(std::max(1, min_terms), sequence_length_)) || !(best < kNoPath))
    return std::nanf("");
  return std::min(best, 1.0f);
}

uint16_t PaceMatcher::terms(size_t, int) const
{
  return static_cast<uint16_t>(std::min<uint64_t>(evidence_, static_cast<uint64_t>(sequence_length_)));
}

float PaceMatcher::chunkMinimum(size_t chunk, const std::vector<size_t>& taken, size_t window) const
{
  const size_t begin = chunk * kChunk;
  const size_t end = std::min(columns(), begin + kChunk);
  const auto near_taken = [&](size_t begin_or_end_column)
  {
    for (size_t t : taken)
      if ((begin_or_end_column > t ? begin_or_end_column - t : t - begin_or_end_column) <= window)
        return true;
    return false;
  };
  bool touched = false;
  for (size_t t : taken)
    touched = touched || (t + window >= begin && t <= end - 1 + window);
  if (!touched)
    return chunk_minimum_[chunk];
  float minimum = kNoPath;
  for (size_t c = begin; c < end; ++c)
    if (!near_taken(c))
      minimum = std::min(minimum, value(c, nullptr));
  return minimum;
}

size_t PaceMatcher::smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& taken) const
{
  taken.clear();
  if (columns() == 0 || std::isnan(normalized(0, nullptr, min_terms)))
    return 0;
  const size_t chunks = chunk_minimum_.size();
  std::vector<float> minimum(chunk_minimum_);
  while (taken.size() < count)
  {
    size_t best = chunks;
    for (size_t k = 0; k < chunks; ++k)
      if (minimum[k] < kNoPath && (best == chunks || minimum[k] < minimum[best]))
        best = k;
    if (best == chunks)
      break;
    // The first column of that chunk with its minimum, outside every taken window.
    const size_t begin = best * kChunk;
    const size_t end = std::min(columns(), begin + kChunk);
    size_t pick = end;
    for (size_t c = begin; c < end && pick == end; ++c)
    {
      bool masked = false;
      for (size_t t : taken)
        masked = masked || (c > t ? c - t : t - c) <= window;
      if (!masked && value(c, nullptr) == minimum[best])
        pick = c;
    }
    if (pick == end)
    {
      minimum[best] = kNoPath;  // cannot happen: the minimum was computed over the same unmasked columns
      continue;
    }
    taken.push_back(pick);
    const size_t low = pick > window ? (pick - window) / kChunk : 0;
    const size_t high = std::min(chunks - 1, (pick + window) / kChunk);
    for (size_t k = low; k <= high; ++k)
      minimum[k] = chunkMinimum(k, taken, window);
  }
  return columns();
}

}  // namespace openable
