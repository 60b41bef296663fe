#include "openable/matching/pace_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "openable/error.h"
#include "openable/parabola.h"
#include "pace_chunks.h"
#include "pace_kernels.h"

namespace openable
{
using pace_chunks::kChunk;

namespace
{
/// The cost of a path that does not exist (before the first place): never the minimum, never overflows.
constexpr float kNoPath = 1e30f;

/// The paces of max_pace as fractions p / 60 (places per frame), slowest first: from 1 / max_pace to max_pace
/// in steps of a factor kPaceStep, 1 exactly among them. Between two neighbours a straight line drifts by one
/// place in about 1 / (pace * (kPaceStep - 1)) frames.
constexpr double kPaceStep = 1.15;
/// The pace prior's full price from this pace (1.3x, 1 / 1.3x) on: the two paces followed next to 1x pay part of it.
constexpr double kPriorPace = 1.3;
/// refinedColumn() from this pace (1.65x, 1 / 1.65x) on, where two neighbouring lines are a quarter of a place a
/// frame apart, and how far from the best path's end it looks for a neighbouring pace's smallest cost (places).
constexpr double kRefinedPace = 1.65;
constexpr long kRefineReach = 4;
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

/// What a slip off a line of `pace` places a frame costs in the kernels' fixed point: `slip_penalty` of a change of
/// pace, divided by the square root of the pace above 1x. A revisit between two of the paces followed drifts off
/// the nearer line by about pace x 0.07 places a frame, so a fast one needs a slip every few frames (2.2x: about
/// every 7) and, at one price for all, pays for them over its whole memory as much as a rival's noise. Measured on
/// 62 steady paces from 1.0x to 2.9x (scripts/pace_sweep.py): summed recall 40.35 -> 42.69 at 272 -> 274 wrong
/// loops; dividing by the pace itself, 43.04 at 295 (doc/results.md "Slips cheaper at fast paces").
int16_t slipCost(float slip_penalty, float change_cost, double pace)
{
  const double cost = double(slip_penalty) * double(change_cost) * pace_kernels::kOne / std::sqrt(std::max(1.0, pace));
  return static_cast<int16_t>(std::min<double>(pace_kernels::kOne, std::round(cost)));
}

/// A cost of the kernels (M, or a cost with the pace prior: pace_kernels::searchedCost) as a normalised distance.
float costOf(int32_t cost)
{
  return static_cast<float>(cost) / static_cast<float>(pace_kernels::kOne);
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
    slip_penalty_(options.slip),
    tolerance_(options.tolerance),
    prior_fraction_(options.prior),
    kernel_(pace_kernels::kernelFor(options.kernel, long(options.max_pace) + 1)),  // throws now, not at a frame
    screen_chunks_(options.screen_chunks),
    refined_limit_(std::max<size_t>(1, options.screen_chunks / 4)),
    screen_kernel_(pace_kernels::screenFor(options.kernel))
{
  if (max_pace_ < 1 || max_pace_ > 64)
    throw Error("max_pace " + std::to_string(max_pace_) + " is out of range; expected 1..64 places per frame");
  if (!std::isfinite(step_penalty_) || step_penalty_ < 0.0f)
    throw Error("pace_penalty must be finite and >= 0");
  if (!std::isfinite(slip_penalty_) || slip_penalty_ < 0.0f)
    throw Error("slip_penalty must be finite and >= 0 (a fraction of pace_penalty; 0 = off)");
  if (!std::isfinite(prior_fraction_) || prior_fraction_ < 0.0f)
    throw Error("pace_prior must be finite and >= 0 (a fraction of pace_penalty; 0 = off)");
  if (tolerance_ < 0 || tolerance_ > 2)
    throw Error("pace_tolerance " + std::to_string(tolerance_) + " is out of range; expected 0..2 places");
  setSequenceLength(sequence_length);
  raw_.resize(kChunk + 2 * static_cast<size_t>(tolerance_));
  entry_.resize(kChunk);
  extra_.resize(kChunk);
  smallest_.resize(kChunk);
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
  pad_ = static_cast<size_t>(max_pace_) + 1;
  margin_ = (pad_ + 31) / 32 * 32;
  segment_ = kChunk + 2 * margin_;
  queries_ = 0;
  searching_ = true;
  prior_active_ = false;
  evidence_ = 0;
  columns_ = 0;
  costs_.clear();
  reverse_.clear();
  flipped_ = false;
  best_.clear();
  old_best_.clear();
  searched_.clear();
  chunk_minimum_.clear();
  screen_.clear();
  old_screen_.clear();
  screen_minimum_.clear();
  refined_.clear();
  stale_.clear();
  screen_offset_ = 0;
  slot_.clear();
  pooled_ = false;
  free_slots_.clear();
  pool_slots_ = 0;
}

AlignedCosts& PaceMatcher::current(size_t pace)
{
  return slopes_[pace].first < 0 && flipped_ ? reverse_ : costs_;
}

const AlignedCosts& PaceMatcher::current(size_t pace) const
{
  return slopes_[pace].first < 0 && flipped_ ? reverse_ : costs_;
}

void PaceMatcher::resizeCosts(AlignedCosts& costs, size_t front, size_t size)
{
  // Places j of chunk j / kChunk at j % kChunk of each pace's segment: the rows of every pace over a chunk are
  // one run of memory, which the kernel reads and writes in one go (17 rows of their own, each 512 bytes at a
  // time, read and write at half the speed: the memory's row buffers and the prefetchers lose track).
  const size_t paces = slopes_.size();
  const size_t kept = std::min(size, columns_ - std::min(front, columns_));
  const size_t chunks = chunksOf(size);
  // One slot a chunk, in order, for the old layout and the new (resizeAll trims slot_ after).
  for (size_t k = slot_.size(); k < std::max(chunks, chunksOf(columns_)); ++k)
    slot_.push_back(static_cast<int32_t>(k));
  if (front > 0 && kept > 0)
  {
    // Evicted places leave: every place moves, in runs within a chunk of both the old and the new layout.
    AlignedCosts moved(chunks * paces * segment_, prior_);
    for (size_t v = 0; v < paces; ++v)
      for (size_t j = 0; j < kept;)
      {
        const size_t from = j + front;
        const size_t run = std::min({kept - j, kChunk - j % kChunk, kChunk - from % kChunk});
        std::copy_n(segment(costs, from / kChunk, v) + from % kChunk, run, segment(moved, j / kChunk, v) + j % kChunk);
        j += run;
      }
    costs.swap(moved);
    return;
  }
  costs.resize(chunks * paces * segment_, prior_);
  // Places that join start as typical (the last chunk's places past the old end hold padding).
  for (size_t v = 0; v < paces; ++v)
    for (size_t j = kept; j < size;)
    {
      const size_t run = std::min(size - j, kChunk - j % kChunk);
      std::fill_n(segment(costs, j / kChunk, v) + j % kChunk, run, prior_);
      j += run;
    }
}

void PaceMatcher::align(const PlaceDatabase& reference, size_t candidates)
{
  candidates = std::min(candidates, reference.size());
  // M keeps pad_ typical places on each side: forward paces read behind, reverse ones ahead, with no edge
  // cases in the kernels. Places that stay keep their costs; new ones and the padding start at the previous
  // row's mean.
  const auto resize = [this](std::vector<int16_t>& row, size_t front, size_t size)
  {
    if (row.size() < 2 * pad_)
      row.assign(2 * pad_, prior_);
    const size_t kept = std::min(size, columns_ - std::min(front, columns_));
    row.erase(row.begin() + static_cast<long>(pad_), row.begin() + static_cast<long>(pad_ + std::min(front, columns_)));
    row.resize(pad_ + kept);
    row.resize(pad_ + size + pad_, prior_);
    std::fill(row.begin(), row.begin() + static_cast<long>(pad_), prior_);
  };
  const auto resizeAll = [&](size_t front, size_t size)
  {
    // A place's costs are the last frame's where it came from a chunk whose costs were (places that join start at
    // `prior`, as a path that has seen nothing). Evicted places move every place: a chunk's first part comes from
    // one chunk of the last frame, the rest from the next, so what is stale is one end of it or all of it.
    const size_t kept = std::min(size, columns_ - std::min(front, columns_));
    const auto wasValid = [this](size_t old_chunk) { return old_chunk >= stale_.size() || stale_[old_chunk].empty(); };
    std::vector<Stale> stale(chunksOf(size));
    for (size_t k = 0; k < stale.size() && k * kChunk < kept; ++k)
    {
      const size_t from = k * kChunk + front;       // where the chunk's first place was
      const size_t split = kChunk - from % kChunk;  // its places before `split` were in chunk from / kChunk
      const size_t old_places = std::min(kept - k * kChunk, kChunk);  // the rest joined the row
      const bool head = wasValid(from / kChunk), tail = split >= old_places || wasValid(from / kChunk + 1);
      if (!head && !tail)
        stale[k] = Stale{0, old_places};
      else if (!head)
        stale[k] = Stale{0, std::min(split, old_places)};
      else if (!tail)
        stale[k] = Stale{split, old_places};
    }
    stale_.swap(stale);
    resize(screen_, front, size);
    if (!pooled_ && columns_ == 0 && screen_chunks_ > 0 && stale_.size() > screen_chunks_)
    {
      // A first row that will be screened (a large map loaded): a pool with every chunk screened out, not a slot
      // for every chunk first (340 MB at 1e7 places).
      refined_.assign(stale_.size(), 0);
      slot_.assign(stale_.size(), -1);
      costs_.clear();
      reverse_.clear();
      pool();
    }
    if (pooled_)
      rekeyPool(front, size);
    else
    {
      resizeCosts(costs_, front, size);
      if (bidirectional_)
        resizeCosts(reverse_, front, size);
      slot_.resize(chunksOf(size));
    }
    resize(best_, front, size);
  };
  if (reference.firstId() < first_id_ || (columns_ == 0 && reference.firstId() != first_id_))
  {
    // The reference restarted (or this is the first row): nothing of the old row applies.
    resizeAll(columns_, 0);
    columns_ = 0;
    first_id_ = reference.firstId();
  }
  // Places evicted from the reference leave the row; places that join it (the reference grew, or the
  // exclusion let them in) start as typical; places the exclusion took back are dropped.
  const size_t gone = static_cast<size_t>(std::min<uint64_t>(reference.firstId() - first_id_, columns_));
  first_id_ = reference.firstId();
  resizeAll(gone, candidates);
  columns_ = candidates;
}

void PaceMatcher::distances(const PlaceDatabase& reference, size_t begin, size_t m)
{
  // raw_[tolerance + i] is the distance of place begin + i; neighbours past either end of the row never win
  // the nearest distance.
  const size_t n = columns_;
  const size_t tolerance = static_cast<size_t>(tolerance_);
  const size_t low = begin > tolerance ? begin - tolerance : 0;
  const size_t high = std::min(n, begin + m + tolerance);
  const uint32_t far = static_cast<uint32_t>(std::numeric_limits<int32_t>::max());
  const size_t first = tolerance - (begin - low);
  std::fill(raw_.begin(), raw_.begin() + static_cast<long>(first), far);
  std::fill(raw_.begin() + static_cast<long>(first + (high - low)), raw_.begin() + static_cast<long>(m + 2 * tolerance),
            far);
  // The frame and its shifted views against each place in one pass: a view costs its popcounts, not another read
  // of the map.
  metric_.rowNearest(query_views_.data(), query_views_.size(), reference.descriptor(low), high - low,
                     raw_.data() + first);
}

void PaceMatcher::matchShifted(const uint64_t* query, const uint64_t* shifted, size_t views,
                               const PlaceDatabase& reference, size_t candidates)
{
  const bool first_row = columns_ == 0;
  // The frame, then its shifted views: every chunk's distances take the smallest (distances()).
  const size_t words = metric_.layout().frameWords();
  query_views_.resize(1 + views);
  query_views_[0] = query;
  for (size_t v = 0; v < views; ++v)
    query_views_[1 + v] = shifted + v * words;
  align(reference, candidates);
  const size_t n = columns_;
  const size_t chunks = chunksOf(n);
  chunk_minimum_.assign(chunks, kNoPath);
  const bool screening = chooseRefined(chunks);
  placeRefinedChunks(screening);
  if (n == 0)
    return;
  const uint64_t t = queries_++;
  ++evidence_;
  const size_t paces = slopes_.size();
  // A row's first frame has no path behind it: every place starts from its own distance.
  const float keep = first_row ? 0.0f : keep_;
  const float fresh = 1.0f - keep;
  // Changing pace costs `step_penalty_` standard deviations of a path's cost under noise: the frame distances
  // of the previous row spread by spread_, their weighted mean over the path by spread_ * sqrt(fresh / (1 + keep)).
  // So a path changes pace for a real change of the revisit, not to chase the noise of one frame, whatever the
  // data, the descriptor and L are.
  const float change_cost = keep > 0.0f ? step_penalty_ * spread_ * std::sqrt(fresh / (1.0f + keep)) : 0.0f;
  // The fixed point: a in 1/32768 (at most 32767, L up to 65535), the entry weight 1 - a exactly, so that a path
  // of equal distances d keeps the cost d.
  pace_kernels::Chunk chunk;
  const int32_t keep_fixed = std::min<int32_t>(32767, static_cast<int32_t>(std::lround(double(keep) * 32768.0)));
  const double max_distance = static_cast<double>(std::max<uint64_t>(1, metric_.layout().maxFrameDistance()));
  chunk.keep = static_cast<int16_t>(keep_fixed);
  chunk.entry_scale = static_cast<float>((32768.0 - keep_fixed) / 32768.0 * pace_kernels::kOne / max_distance);
  pace_kernels::ScreenChunk screen;
  screen.raw = raw_.data() + tolerance_;
  screen.reach = max_pace_;
  screen.bidirectional = bidirectional_;
  screen.entry_scale = chunk.entry_scale;
  screen.keep = chunk.keep;
  chunk.change =
      static_cast<int16_t>(std::min<double>(pace_kernels::kOne, std::round(double(change_cost) * pace_kernels::kOne)));
  // While the stream looks for a loop, a place is judged by its paths near the first pass's pace first: of the 17
  // paces' noisy paths at a place the revisit does not pass, the smallest is lower than any one of them, so a
  // wrong place gains more from the other paces than the right one, whose path has one pace; and at the start of a
  // revisit a path's first frames fit any pace (a lead of 3 or 4 places on a 1.5x path, a creeping 0.33x one). A
  // pace pays prior x change x min(1, |ln pace| / ln 1.3) to be its place's best (each pace's own cost and the
  // recurrence unchanged): GP day_right then day_left 1x 0.735 -> 0.865, its 60-frame short route 0.200 -> 0.700.
  // Once a loop is published the run's place is followed at whatever pace it goes (always on: a revisit at 1.25x
  // lost 0.925 -> 0.662, and Nordland's changing paces gained wrong loops; doc/results.md "A pace prior while
  // searching").
  prior_active_ = searching_ && prior_fraction_ > 0.0f && keep > 0.0f;
  if (prior_active_)
  {
    pace_prior_.resize(slopes_.size());
    for (size_t v = 0; v < slopes_.size(); ++v)
    {
      const double away = std::min(1.0, std::fabs(std::log(placesPerFrame(slopes_[v]))) / std::log(kPriorPace));
      pace_prior_[v] = static_cast<uint16_t>(std::lround(double(prior_fraction_) * double(chunk.change) * away));
    }
  }
  // A slip costs a fraction of a change of pace (slip_penalty 0: paths never leave their line; the kernels skip the
  // term).
  chunk.slips = slip_penalty_ > 0.0f;
  chunk.tolerance = tolerance_;
  chunk.raw = raw_.data();
  chunk.entry = entry_.data();
  chunk.extra = extra_.data();
  // The places each pace advances this frame: a path comes from j - step (forward) or j + step (reverse). A
  // forward row is updated in place (a kernel never overwrites a place before reading what reads it); a reverse
  // one goes to the other buffer.
  std::vector<pace_kernels::PaceRow> rows(paces);
  std::vector<long> offsets;
  std::vector<uint8_t> slot(paces);
  for (size_t v = 0; v < paces; ++v)
  {
    const int p = slopes_[v].first;
    const long step = stepAt(t, std::abs(p), slopes_[v].second);
    rows[v].offset = p > 0 ? -step : step;
    rows[v].slip = chunk.slips ? slipCost(slip_penalty_, change_cost, placesPerFrame(slopes_[v])) : int16_t(-1);
    const auto found = std::find(offsets.begin(), offsets.end(), rows[v].offset);
    slot[v] = static_cast<uint8_t>(found - offsets.begin());
    if (found == offsets.end())
      offsets.push_back(rows[v].offset);
  }
  chunk.rows = rows.data();
  chunk.paces = paces;
  chunk.offsets = offsets.data();
  chunk.distinct = offsets.size();
  chunk.slot = slot.data();
  with_change_.resize(offsets.size() * kChunk);
  chunk.with_change = with_change_.data();
  chunk.stride = kChunk;
  chunk.smallest = smallest_.data();
  chunk.prior = prior_active_ ? pace_prior_.data() : nullptr;
  if (prior_active_)
    searched_.resize(n);
  chunk.searched = prior_active_ ? searched_.data() : nullptr;
  // M_{t-1} is read while M_t is written: both keep pad_ typical places on each side.
  std::swap(best_, old_best_);
  best_.resize(old_best_.size());
  chunk.old_best = old_best_.data() + pad_;
  chunk.best = best_.data() + pad_;
  std::swap(screen_, old_screen_);
  screen_.resize(old_screen_.size());
  screen.old_screen = old_screen_.data() + pad_;
  screen.screen = screen_.data() + pad_;
  uint64_t distance_sum = 0, square_sum = 0;
  int64_t above_screen = 0;
  size_t refined_places = 0;
  // Chunk by chunk in the order of memory (the prefetchers follow it; backwards, a frame took twice as long).
  for (size_t k = 0; k < chunks; ++k)
  {
    chunk.begin = k * kChunk;
    chunk.m = std::min(kChunk, n - chunk.begin);
    if (refined_[k])
      prepareChunk(k, chunks, chunk.m, rows);
    distances(reference, chunk.begin, chunk.m);
    screen.begin = chunk.begin;
    screen.m = chunk.m;
    const pace_kernels::ScreenSums screened_sums = screen_kernel_(screen);
    screen_minimum_[k] = screened_sums.minimum;
    distance_sum += screened_sums.sum;
    square_sum += screened_sums.squares;
    if (refined_[k])
    {
      const pace_kernels::ChunkSums sums = kernel_(chunk);
      chunk_minimum_[k] = prior_active_ ? costOf(sums.searched_minimum) : costOf(sums.minimum);
      if (screening)
        for (size_t i = 0; i < chunk.m; ++i)
          above_screen += int64_t(best_[pad_ + chunk.begin + i]) - int64_t(screen_[pad_ + chunk.begin + i]);
      refined_places += chunk.m;
    }
  }
  // How far a refined place's cost lies above its screen cost, on average (the screen's paths may zig-zag, so they
  // are lower, most of all where nothing matches): a chunk refined next frame starts that much above its screen,
  // typical for its rank rather than better than every path already followed.
  if (screening && refined_places > 0)
    screen_offset_ =
        static_cast<int16_t>(std::clamp<int64_t>(above_screen / int64_t(refined_places), 0, pace_kernels::kOne));
  // A chunk left out this frame keeps costs of an older one.
  for (size_t k = 0; k < chunks; ++k)
    stale_[k] = refined_[k] ? Stale{} : Stale{0, kChunk};
  flipped_ = bidirectional_ && !flipped_;
  const double mean = static_cast<double>(distance_sum) / static_cast<double>(n) / max_distance;
  const double squares = static_cast<double>(square_sum) / static_cast<double>(n) / (max_distance * max_distance);
  prior_ = static_cast<int16_t>(std::lround(std::min(1.0, mean) * pace_kernels::kOne));
  spread_ = static_cast<float>(std::sqrt(std::max(0.0, squares - mean * mean)));
}

size_t PaceMatcher::chunksOf(size_t places)
{
  return (places + kChunk - 1) / kChunk;
}

int16_t PaceMatcher::costAt(size_t column, size_t pace) const
{
  return current(pace)[(size_t(slot_[column / kChunk]) * slopes_.size() + pace) * segment_ + margin_ + column % kChunk];
}

size_t PaceMatcher::refinedColumn(size_t column) const
{
  // A revisit between two of the fast paces followed (2.2x lies between 2.02x and 2.32x) drifts from either line by
  // 0.15 places a frame, and where neighbouring places look alike the best line goes on drifting: its end was 3
  // places ahead of GP day_right then day_left at 2.2x for 20 frames, published as wrong loops (tolerance 2), while
  // the slower neighbour's line ended as far behind. As a sub-pixel peak is found, a parabola through the three
  // paces' costs (each neighbour's smallest within kRefineReach places) places the revisit's pace between them, and
  // the end moves that fraction (at most half) of the way to the neighbour's end. Measured (doc/results.md, "The
  // end of a fast path placed between the paces followed"): 90 pace streams 45.53 -> 46.59 summed recall at 271 ->
  // 253 wrong, every steady pace 1.0x to 2.9x 43.15 -> 44.01 at 185 -> 165, 35 streams not tuned on 18.84 -> 18.98
  // at 223 -> 226.
  // From 1.65x only: from 1.22x, a borderline match before a stop moved one place and was repeated through it (119
  // wrong loops on one stream not tuned on, 7 before), and at 1.5x, on a line, the parabola's noise broke runs.
  if (column >= columns_)
    return column;
  const size_t v = paceIndex(column);
  const bool has_neighbours = slopes_[v].first > 0 && v > 0 && v + 1 < slopes_.size() && slopes_[v + 1].first > 0;
  if (!has_neighbours || std::fabs(std::log(placesPerFrame(slopes_[v]))) < std::log(kRefinedPace))
    return column;
  const auto smallestNear = [&](size_t pace, long* at)
  {
    int32_t smallest = INT32_MAX;
    const long first = std::max(0L, static_cast<long>(column) - kRefineReach);
    const long last = std::min(static_cast<long>(columns_) - 1, static_cast<long>(column) + kRefineReach);
    for (long j = first; j <= last; ++j)
    {
      if (!isRefined(static_cast<size_t>(j)))
        continue;  // a screened chunk's costs are older
      const int32_t cost = costAt(static_cast<size_t>(j), pace);
      const bool nearer = std::labs(j - static_cast<long>(column)) < std::labs(*at - static_cast<long>(column));
      if (cost < smallest || (cost == smallest && nearer))
      {
        smallest = cost;
        *at = j;
      }
    }
    return static_cast<double>(smallest);
  };
  long slower_end = static_cast<long>(column), faster_end = static_cast<long>(column);
  const double slower = smallestNear(v - 1, &slower_end), faster = smallestNear(v + 1, &faster_end);
  // In paces, + faster; 0 (the line's own end) where the three costs have no minimum between the neighbours.
  const double offset = std::clamp(parabolaMinimum(slower, costAt(column, v), faster), -0.5, 0.5);
  const long toward = offset > 0.0 ? faster_end : slower_end;
  const double place =
      static_cast<double>(column) + std::fabs(offset) * static_cast<double>(toward - static_cast<long>(column));
  return static_cast<size_t>(std::max(0L, std::lround(place)));
}

size_t PaceMatcher::paceIndex(size_t column) const
{
  const auto cost = [&](size_t v) { return int32_t(costAt(column, v)) + (prior_active_ ? pace_prior_[v] : 0); };
  size_t index = 0;
  for (size_t v = 1; v < slopes_.size(); ++v)
    if (cost(v) < cost(index))
      index = v;
  return index;
}

float PaceMatcher::value(size_t column, int* direction) const
{
  if (direction)
    *direction = slopes_[paceIndex(column)].first > 0 ? 1 : -1;
  return prior_active_ ? costOf(searched_[column]) : costOf(best_[pad_ + column]);
}

bool PaceMatcher::enoughEvidence(int min_terms) const
{
  return evidence_ >= static_cast<uint64_t>(std::min(std::max(1, min_terms), sequence_length_));
}

float PaceMatcher::normalized(size_t column, int* direction, int min_terms) const
{
  if (!isRefined(column))
    return std::nanf("");  // screened out this frame: no path of every pace to judge it by
  const float best = value(column, direction);
  if (!enoughEvidence(min_terms) || !(best < kNoPath))
    return std::nanf("");
  return std::min(best, 1.0f);
}

uint16_t PaceMatcher::terms(size_t, int) const
{
  return static_cast<uint16_t>(std::min<uint64_t>(evidence_, static_cast<uint64_t>(sequence_length_)));
}

float PaceMatcher::chunkMinimum(size_t chunk, const std::vector<size_t>& taken, size_t window) const
{
  if (!refined_[chunk])
    return kNoPath;
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
  if (columns() == 0 || !enoughEvidence(min_terms))
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
