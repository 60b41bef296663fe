#include "openable/matching/pace_matcher.h"

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
  exact_.resize(kChunk);
  near_.resize(kChunk);
  pace_chunk_.resize(kChunk);
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
  one_ = static_cast<uint8_t>(std::find(slopes_.begin(), slopes_.end(), std::make_pair(60, 60)) - slopes_.begin());
  pad_ = static_cast<size_t>(max_pace_) + 1;
  old_.resize(kChunk + 2 * pad_);
  queries_ = 0;
  evidence_ = 0;
  columns_ = 0;
  rows_.assign(slopes_.size(), std::vector<float>());
  best_.clear();
  old_best_.clear();
  pace_.clear();
  chunk_minimum_.clear();
}

void PaceMatcher::align(const PlaceDatabase& reference, size_t candidates)
{
  candidates = std::min(candidates, reference.size());
  // Rows keep pad_ typical places after the last (reverse paces read ahead), the M buffers pad_ on each side
  // (forward paces read behind): no edge cases in the loops.
  const auto resize = [this](size_t front, size_t size)
  {
    for (auto& row : rows_)
    {
      row.erase(row.begin(), row.begin() + static_cast<long>(std::min(front, row.size())));
      row.resize(size);  // keeps the old typical padding as the first new places
      row.resize(size + pad_, prior_);
      std::fill(row.begin() + static_cast<long>(std::min(size, columns_ - std::min(front, columns_))), row.end(),
                prior_);
    }
    best_.erase(best_.begin() + static_cast<long>(pad_),
                best_.begin() + static_cast<long>(pad_ + std::min(front, columns_)));
    best_.resize(pad_ + size);
    std::fill(best_.begin() + static_cast<long>(pad_ + std::min(size, columns_ - std::min(front, columns_))),
              best_.end(), prior_);
    best_.resize(pad_ + size + pad_, prior_);
    std::fill(best_.begin(), best_.begin() + static_cast<long>(pad_), prior_);
    std::fill(best_.end() - static_cast<long>(pad_), best_.end(), prior_);
    pace_.erase(pace_.begin(), pace_.begin() + static_cast<long>(std::min(front, pace_.size())));
    pace_.resize(size, one_);
  };
  if (best_.size() < 2 * pad_)
    best_.assign(2 * pad_, prior_);
  if (reference.firstId() < first_id_ || (columns_ == 0 && reference.firstId() != first_id_))
  {
    // The reference restarted (or this is the first row): nothing of the old row applies.
    resize(columns_, 0);
    columns_ = 0;
    first_id_ = reference.firstId();
  }
  // Places evicted from the reference leave the row; places that join it (the reference grew, or the
  // exclusion let them in) start as typical; places the exclusion took back are dropped.
  const size_t gone = static_cast<size_t>(std::min<uint64_t>(reference.firstId() - first_id_, columns_));
  first_id_ = reference.firstId();
  resize(gone, candidates);
  columns_ = candidates;
}

void PaceMatcher::prepareChunk(const uint64_t* query, const PlaceDatabase& reference, size_t begin, size_t m)
{
  // The chunk's distances and `tolerance` places on each side.
  const size_t n = columns_;
  const size_t tolerance = static_cast<size_t>(tolerance_);
  const size_t low = begin > tolerance ? begin - tolerance : 0;
  const size_t high = std::min(n, begin + m + tolerance);
  metric_.row(query, reference.descriptor(low), high - low, raw_.data());
  const uint32_t* own = raw_.data() + (begin - low);
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
    exact_[i] = static_cast<float>(own[i]) * inverse_max_distance_;
    near_[i] = static_cast<float>(nearest) * inverse_max_distance_;
  }
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
  // The places each pace advances this frame: a path comes from j - step (forward) or j + step (reverse).
  std::vector<long>& steps = steps_;
  steps.resize(slopes);
  for (size_t v = 0; v < slopes; ++v)
  {
    const int p = slopes_[v].first;
    const long step = stepAt(t, std::abs(p), slopes_[v].second);
    steps[v] = p > 0 ? step : -step;
  }
  // A row's first frame has no path behind it: every place starts from its own distance.
  const float keep = first_row ? 0.0f : keep_;
  const float fresh = 1.0f - keep;
  // Changing pace costs `step_penalty_` standard deviations of a path's cost under noise: the frame distances
  // of the previous row spread by spread_, their weighted mean over the path by spread_ * sqrt(fresh / (1 + keep)).
  // So a path changes pace for a real change of the revisit, not to chase the noise of one frame, whatever the
  // data, the descriptor and L are.
  const float change_cost = keep > 0.0f ? step_penalty_ * spread_ * std::sqrt(fresh / (1.0f + keep)) : 0.0f;
  // M_{t-1} is read while M_t is written; both keep pad_ typical places on each side.
  std::swap(best_, old_best_);
  best_.assign(old_best_.size(), prior_);
  // A forward pace reads up to pad_ places before its own, already overwritten by the chunk before: the
  // previous frame's costs of those places are carried from chunk to chunk.
  carry_.assign(slopes * pad_, prior_);
  double distance_sum = 0.0, square_sum = 0.0;
  for (size_t begin = 0, chunk = 0; begin < n; begin += kChunk, ++chunk)
  {
    const size_t m = std::min(kChunk, n - begin);
    prepareChunk(query, reference, begin, m);
    float* best = best_.data() + pad_ + begin;
    uint8_t* pace = pace_.data() + begin;
    for (size_t i = 0; i < m; ++i)
    {
      distance_sum += exact_[i];
      square_sum += double(exact_[i]) * exact_[i];
      best[i] = kNoPath;
      pace_chunk_[i] = one_;
    }
    const float* old_best = old_best_.data() + pad_ + begin;
    for (size_t v = 0; v < slopes; ++v)
    {
      float* row = rows_[v].data() + begin;
      const long step = steps[v];
      // old[i - step] is the previous frame's cost of place begin + i - step.
      const float* old = row;
      if (step >= 0)
      {
        float* scratch = old_.data();
        std::copy(carry_.begin() + static_cast<long>(v * pad_), carry_.begin() + static_cast<long>((v + 1) * pad_),
                  scratch);
        std::copy(row, row + m, scratch + pad_);
        std::copy(scratch + m, scratch + m + pad_, carry_.begin() + static_cast<long>(v * pad_));
        old = scratch + pad_;
      }
      else if (step < 0)
      {
        std::copy(row, row + m - step, old_.data());  // the places after the chunk are in the row (or its padding)
        old = old_.data();
      }
      const float* __restrict from = old - step;
      const float* __restrict from_best = old_best - step;
      const float* __restrict d = near_.data();
      float* __restrict out = row;
      for (size_t i = 0; i < m; ++i)
        out[i] = fresh * d[i] + keep * std::min(from[i], from_best[i] + change_cost);
      // The best pace so far, in 32-bit lanes beside the float costs so that the loop vectorises.
      float* __restrict best_chunk = best;
      int32_t* __restrict pace_chunk = pace_chunk_.data();
      const int32_t index = static_cast<int32_t>(v);
      for (size_t i = 0; i < m; ++i)
      {
        const int32_t better = -static_cast<int32_t>(out[i] < best_chunk[i]);  // all ones where this pace wins
        best_chunk[i] = std::min(out[i], best_chunk[i]);
        pace_chunk[i] = (pace_chunk[i] & ~better) | (index & better);
      }
    }
    for (size_t i = 0; i < m; ++i)
      pace[i] = static_cast<uint8_t>(pace_chunk_[i]);
    // The place itself is judged by its own distance this frame: the tolerance is for the path behind it.
    float minimum = kNoPath;
    for (size_t i = 0; i < m; ++i)
    {
      best[i] += fresh * (exact_[i] - near_[i]);
      minimum = std::min(minimum, best[i]);
    }
    chunk_minimum_[chunk] = minimum;
  }
  prior_ = static_cast<float>(distance_sum / static_cast<double>(n));
  spread_ = static_cast<float>(std::sqrt(std::max(0.0, square_sum / static_cast<double>(n) - double(prior_) * prior_)));
}

float PaceMatcher::value(size_t column, int* direction) const
{
  if (direction)
    *direction = slopes_[pace_[column]].first > 0 ? 1 : -1;
  return best_[pad_ + column];
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
