// PaceMatcher on a large row (pace_matcher.h): which chunks keep every pace's costs this frame (the screen ranks
// them), the pool of slots that holds those costs, and each refined chunk's preparation before the kernel runs.
#include "openable/matching/pace_matcher.h"

#include <algorithm>
#include <vector>

#include "pace_chunks.h"
#include "pace_kernels.h"

namespace openable
{
using pace_chunks::kChunk;

void PaceMatcher::prepareChunk(size_t k, size_t chunks, size_t m, std::vector<pace_kernels::PaceRow>& rows)
{
  if (!stale_[k].empty())
    startFromScreen(k);
  // A place's screen cost of the last frame as a path's (screenedCost), where a chunk's costs are not the last frame's.
  const auto screened = [&](size_t place) { return screenedCost(old_screen_[pad_ + place]); };
  // A segment's padding holds the previous costs of the places a pace reads beyond the chunk. Forward, the last places
  // of the chunk before: a refined chunk copies its own into the next one's padding before it is updated in place
  // (here), and a chunk screened out has none, so its screen costs stand in. Reverse, the first places of the chunk
  // after, in the buffer that is only read (or their screen costs).
  const bool before = k > 0 && refined_[k - 1], after = k + 1 < chunks && refined_[k + 1];
  for (size_t v = 0; v < slopes_.size(); ++v)
  {
    AlignedCosts& from = current(v);
    int16_t* own = segment(from, k, v);
    const bool forward = slopes_[v].first > 0;
    for (size_t q = 1; q <= pad_; ++q)
      if (forward)
      {
        if (k == 0 || !before)
          own[-static_cast<long>(q)] = k == 0 ? prior_ : screened(k * kChunk - q);
        if (after)
          segment(from, k + 1, v)[-static_cast<long>(q)] = own[kChunk - q];  // (stale_[k] is empty by now)
      }
      else
        own[m + q - 1] = k + 1 == chunks                        ? prior_
                         : after && !stale_[k + 1].holds(q - 1) ? segment(from, k + 1, v)[q - 1]
                                                                : screened((k + 1) * kChunk + q - 1);
    rows[v].from = own;
    rows[v].to = forward ? own : segment(&from == &costs_ ? reverse_ : costs_, k, v);
  }
  // M of the last frame of the places a path comes from beyond the chunk, where it was screened out: its screen cost
  // as a path's.
  for (size_t q = 1; q <= pad_; ++q)
  {
    if (k > 0 && stale_[k - 1].holds(kChunk - q))
      old_best_[pad_ + k * kChunk - q] = screened(k * kChunk - q);
    if (k + 1 < chunks && stale_[k + 1].holds(q - 1))
      old_best_[pad_ + (k + 1) * kChunk + q - 1] = screened((k + 1) * kChunk + q - 1);
  }
}

bool PaceMatcher::chooseRefined(size_t chunks)
{
  refined_.assign(chunks, 1);
  screen_minimum_.resize(chunks, INT16_MAX);  // a chunk that joined the row has no screen cost yet
  if (screen_chunks_ == 0 || chunks <= screen_chunks_)
    return false;
  // The chunks with the smallest screen costs of the last frame and the chunk after each (a forward path goes on into
  // it; the one before too with bidirectional), and those refined the frame before that still rank among twice as
  // many: a chunk near the limit does not start again from its screen costs every other frame. At most a quarter of
  // the limit start again in a frame (the best ranked first): each start writes every pace's costs of a chunk, and
  // where nothing matches the ranking is noise that changes every frame (random queries at L = 10 took 3.5x today's
  // matcher at 1e6 places, starting a dozen chunks a frame).
  std::fill(refined_.begin(), refined_.end(), 0);
  std::vector<size_t> order(chunks);
  for (size_t k = 0; k < chunks; ++k)
    order[k] = k;
  const auto smaller = [this](size_t a, size_t b)
  { return screen_minimum_[a] < screen_minimum_[b] || (screen_minimum_[a] == screen_minimum_[b] && a < b); };
  const size_t kept = std::min(chunks, 2 * refined_limit_);
  std::partial_sort(order.begin(), order.begin() + static_cast<long>(kept), order.end(), smaller);
  const auto wasRefined = [this](size_t k) { return k < stale_.size() && stale_[k].empty(); };
  size_t starts = std::max<size_t>(1, refined_limit_ / 4);
  const auto refine = [&](size_t k)
  {
    if (refined_[k] || (!wasRefined(k) && starts == 0))
      return;
    starts -= wasRefined(k) ? 0 : 1;
    refined_[k] = 1;
  };
  for (size_t r = 0; r < kept; ++r)
  {
    const size_t k = order[r];
    if (screen_minimum_[k] == INT16_MAX)
      continue;
    if (r < refined_limit_)
    {
      refine(k);
      if (k + 1 < chunks)
        refine(k + 1);
      if (bidirectional_ && k > 0)
        refine(k - 1);
    }
    else if (wasRefined(k))
      refined_[k] = 1;
  }
  return true;
}

void PaceMatcher::startFromScreen(size_t chunk)
{
  // Every pace of a place starts from its screen cost: the best of its paths at any pace, as a change of pace
  // would take M (a little lower than M would be: the screen's path may zig-zag).
  const Stale& stale = stale_[chunk];
  const size_t end = std::min(stale.end, columns_ - chunk * kChunk);
  const int16_t* screened = old_screen_.data() + pad_ + chunk * kChunk;
  // The same start for every pace, computed once (a chunk that starts again writes all 17 paces' costs).
  int16_t* start = old_best_.data() + pad_ + chunk * kChunk;  // M of the last frame: the smallest of those
  for (size_t i = stale.begin; i < end; ++i)
    start[i] = screenedCost(screened[i]);
  for (size_t v = 0; v < slopes_.size(); ++v)
    std::copy(start + stale.begin, start + end, segment(current(v), chunk, v) + stale.begin);
  stale_[chunk] = Stale{};
}

int16_t PaceMatcher::screenedCost(int16_t screen) const
{
  return pace_kernels::addSaturated(screen, screen_offset_);
}

bool PaceMatcher::isRefined(size_t column) const
{
  return column / kChunk < refined_.size() && refined_[column / kChunk];
}

void PaceMatcher::placeRefinedChunks(bool screening)
{
  if (!screening)
  {
    if (pooled_)
      unpool();
    return;
  }
  if (!pooled_)
    pool();
  // A chunk left out gives its slot back (its costs would be an older frame's); a chunk refined without one takes
  // one and starts from its screen costs.
  for (size_t k = 0; k < refined_.size(); ++k)
    if (!refined_[k] && slot_[k] >= 0)
    {
      free_slots_.push_back(slot_[k]);
      slot_[k] = -1;
      stale_[k] = Stale{0, kChunk};
    }
  for (size_t k = 0; k < refined_.size(); ++k)
    if (refined_[k] && slot_[k] < 0)
    {
      if (free_slots_.empty())  // cannot happen: chooseRefined refines at most as many chunks as the pool holds
      {
        refined_[k] = 0;
        continue;
      }
      slot_[k] = free_slots_.back();
      free_slots_.pop_back();
      stale_[k] = Stale{0, kChunk};
    }
}

void PaceMatcher::pool()
{
  // chooseRefined refines at most the limit's chunks, the one after each (and before, both ways) and as many again
  // that were refined: a slot for each, where a row refined whole kept a slot for every chunk (340 MB at 1e7 places).
  pool_slots_ = (bidirectional_ ? 4 : 3) * refined_limit_ + 1;
  const size_t entries = pool_slots_ * slopes_.size() * segment_;  // int16 costs: every pace's segment of every slot
  AlignedCosts costs(entries, prior_), reverse(bidirectional_ ? entries : 0, prior_);
  free_slots_.clear();
  for (size_t s = pool_slots_; s-- > 0;)
    free_slots_.push_back(static_cast<int32_t>(s));
  const size_t run = slopes_.size() * segment_;  // a slot: every pace's segment
  for (size_t k = 0; k < refined_.size(); ++k)
  {
    if (!refined_[k] || !stale_[k].empty())
    {
      slot_[k] = -1;
      stale_[k] = Stale{0, kChunk};
      continue;
    }
    const int32_t s = free_slots_.back();
    free_slots_.pop_back();
    std::copy_n(costs_.begin() + static_cast<long>(k * run), run, costs.begin() + static_cast<long>(size_t(s) * run));
    if (bidirectional_)
      std::copy_n(reverse_.begin() + static_cast<long>(k * run), run,
                  reverse.begin() + static_cast<long>(size_t(s) * run));
    slot_[k] = s;
  }
  costs_.swap(costs);
  reverse_.swap(reverse);
  pooled_ = true;
}

void PaceMatcher::unpool()
{
  const size_t chunks = refined_.size(), run = slopes_.size() * segment_;
  AlignedCosts costs(chunks * run, prior_), reverse(bidirectional_ ? chunks * run : 0, prior_);
  for (size_t k = 0; k < chunks; ++k)
  {
    if (slot_[k] >= 0)
    {
      std::copy_n(costs_.begin() + static_cast<long>(size_t(slot_[k]) * run), run,
                  costs.begin() + static_cast<long>(k * run));
      if (bidirectional_)
        std::copy_n(reverse_.begin() + static_cast<long>(size_t(slot_[k]) * run), run,
                    reverse.begin() + static_cast<long>(k * run));
    }
    else
      stale_[k] = Stale{0, kChunk};
    slot_[k] = static_cast<int32_t>(k);
  }
  costs_.swap(costs);
  reverse_.swap(reverse);
  free_slots_.clear();
  pooled_ = false;
  pool_slots_ = 0;
}

void PaceMatcher::rekeyPool(size_t front, size_t size)
{
  // New chunk k's places were places [off, kChunk) of old chunk a and then the first of old chunk a + 1: it takes a's
  // slot, moved down by off, and the rest from a + 1's slot before that one moves in turn (chunks in order).
  const size_t kept = std::min(size, columns_ - std::min(front, columns_));
  const size_t chunks = chunksOf(size), old_chunks = slot_.size();
  std::vector<int32_t> slots(chunks, -1);
  for (size_t k = 0; k < chunks && k * kChunk < kept; ++k)
  {
    const size_t from = k * kChunk + front, a = from / kChunk, off = from % kChunk;
    if (a >= old_chunks || slot_[a] < 0)
      continue;
    const int32_t s = slot_[a];
    slots[k] = s;
    const size_t old_places = std::min(kept - k * kChunk, kChunk);
    const size_t joined = std::min(kChunk, size - k * kChunk);
    for (AlignedCosts* buffer : {&costs_, &reverse_})
    {
      if (buffer->empty())
        continue;
      for (size_t v = 0; v < slopes_.size(); ++v)
      {
        int16_t* own = slotSegment(*buffer, size_t(s), v);
        std::copy(own + off, own + kChunk, own);
        if (kChunk - off < old_places && a + 1 < old_chunks && slot_[a + 1] >= 0)
          std::copy_n(slotSegment(*buffer, size_t(slot_[a + 1]), v), old_places - (kChunk - off), own + kChunk - off);
        std::fill(own + old_places, own + std::max(old_places, joined), prior_);
      }
    }
  }
  // Every slot no chunk took is free again; a chunk without one is screened out (stale).
  std::vector<uint8_t> taken(pool_slots_, 0);
  for (int32_t s : slots)
    if (s >= 0)
      taken[size_t(s)] = 1;
  free_slots_.clear();
  for (size_t s = pool_slots_; s-- > 0;)
    if (!taken[s])
      free_slots_.push_back(static_cast<int32_t>(s));
  slot_.swap(slots);
  for (size_t k = 0; k < chunks; ++k)
    if (slot_[k] < 0)
      stale_[k] = Stale{0, kChunk};
}

}  // namespace openable
