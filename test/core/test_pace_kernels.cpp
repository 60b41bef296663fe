// PaceMatcher's 16-bit fixed point: every kernel the CPU runs (portable, AVX2, AVX-512BW) against the same
// recurrence written the plain way (whole rows, one place and pace at a time, no chunks, no padding, no in-place
// update), to the last bit; across chunks of columns, a growing and an evicting reference, both directions and
// every tolerance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>

#include "bit_oracle.h"  // randomWords
#include "matching/pace_kernels.h"
#include "openable/matching/pace_matcher.h"

using namespace openable;

namespace
{
constexpr int32_t kOne = 32767;

DescriptorLayout binaryLayout(int bits)
{
  DescriptorLayout layout;
  layout.binary = true;
  layout.cell_length = bits;
  layout.cell_words = (bits + 63) / 64;
  layout.cells = 1;
  layout.blocks = 1;
  return layout;
}

int16_t saturated(int32_t x)
{
  return static_cast<int16_t>(std::min(32767, std::max(-32768, x)));
}

/// The quantised recurrence of PaceMatcher (pace_matcher.h), place by place.
class NaiveFixedPace
{
public:
  NaiveFixedPace(const DescriptorLayout& layout, int L, std::vector<std::pair<int, int>> paces, float penalty,
                 int tolerance, float slip)
    : metric_(layout),
      keep_(1.0f - 1.0f / static_cast<float>(L)),
      paces_(std::move(paces)),
      penalty_(penalty),
      tolerance_(tolerance),
      slip_(slip)
  {
  }

  void match(const uint64_t* query, const PlaceDatabase& reference, size_t n)
  {
    // Evicted places leave the front of the row.
    const size_t gone = std::min<size_t>(reference.firstId() - first_id_, costs_.size());
    costs_.erase(costs_.begin(), costs_.begin() + static_cast<long>(gone));
    best_.erase(best_.begin(), best_.begin() + static_cast<long>(gone));
    first_id_ = reference.firstId();
    const bool first = t_ == 0;
    const double max_distance = static_cast<double>(metric_.layout().maxFrameDistance());
    std::vector<uint32_t> raw(n), nearest(n);
    for (size_t j = 0; j < n; ++j)
      raw[j] = metric_.distance(query, reference.descriptor(j));
    for (size_t j = 0; j < n; ++j)
    {
      nearest[j] = raw[j];
      for (int k = 1; k <= tolerance_; ++k)
      {
        if (j >= size_t(k))
          nearest[j] = std::min(nearest[j], raw[j - k]);
        if (j + k < n)
          nearest[j] = std::min(nearest[j], raw[j + k]);
      }
    }
    const float keep = first ? 0.0f : keep_;
    const float change = keep > 0.0f ? penalty_ * spread_ * std::sqrt((1.0f - keep) / (1.0f + keep)) : 0.0f;
    const int32_t a = std::min<int32_t>(32767, static_cast<int32_t>(std::lround(double(keep) * 32768.0)));
    const float scale = static_cast<float>((32768.0 - a) / 32768.0 * kOne / max_distance);
    const int32_t change_fixed = static_cast<int32_t>(std::min<double>(kOne, std::round(double(change) * kOne)));
    // A slip costs slip_ of a change of pace, divided by the square root of the line's pace above 1x.
    const auto slipFixed = [&](int p, int q)
    {
      const double pace = std::max(1.0, double(std::abs(p)) / q);
      return slip_ > 0.0f ? static_cast<int32_t>(std::min<double>(
                                kOne, std::round(double(slip_) * double(change) * kOne / std::sqrt(pace))))
                          : -1;
    };
    const auto entry = [scale](uint32_t r)
    { return static_cast<int32_t>(std::nearbyint(std::min(float(int32_t(r)) * scale, float(kOne)))); };
    const auto oldCost = [&](long j, size_t v)
    { return j >= 0 && j < long(costs_.size()) ? costs_[size_t(j)][v] : prior_; };
    const auto oldBest = [&](long j) { return j >= 0 && j < long(best_.size()) ? best_[size_t(j)] : prior_; };
    std::vector<std::vector<int16_t>> costs(n, std::vector<int16_t>(paces_.size()));
    std::vector<int16_t> best(n);
    for (size_t j = 0; j < n; ++j)
    {
      int16_t smallest = kOne;
      for (size_t v = 0; v < paces_.size(); ++v)
      {
        const int p = paces_[v].first, q = paces_[v].second;
        const long step = long((t_ + 1) * std::abs(p) / q) - long(t_ * std::abs(p) / q);
        const long from = long(j) - (p > 0 ? step : -step);
        int32_t path = std::min<int32_t>(oldCost(from, v), saturated(oldBest(from) + change_fixed));
        const int32_t slip_fixed = slipFixed(p, q);
        if (slip_fixed >= 0)
        {
          // One place further along the line (behind forward, ahead reverse) or, where it advances, one fewer.
          const long further = p > 0 ? -1 : 1;
          int32_t off = oldCost(from + further, v);
          if (step != 0)
            off = std::min<int32_t>(off, oldCost(from - further, v));
          path = std::min<int32_t>(path, saturated(off + slip_fixed));
        }
        costs[j][v] = saturated(entry(nearest[j]) + ((path * a + 16384) >> 15));
        smallest = std::min(smallest, costs[j][v]);
      }
      best[j] = saturated(smallest + entry(raw[j]) - entry(nearest[j]));
    }
    // While searching: the smallest cost plus its pace's prior, and M's own-distance term, saturated at 65535.
    searched_.assign(n, 0);
    for (size_t j = 0; j < n && prior_fraction_ > 0.0f && a > 0; ++j)
    {
      int32_t priced = INT32_MAX;
      for (size_t v = 0; v < paces_.size(); ++v)
      {
        const double pace = double(std::abs(paces_[v].first)) / paces_[v].second;
        const double away = std::min(1.0, std::fabs(std::log(pace)) / std::log(1.3));
        priced = std::min<int32_t>(priced, costs[j][v] + std::lround(double(prior_fraction_) * change_fixed * away));
      }
      searched_[j] = std::min<int32_t>(65535, priced + entry(raw[j]) - entry(nearest[j]));
    }
    costs_ = costs;
    best_ = best;
    uint64_t sum = 0, squares = 0;
    for (uint32_t r : raw)
    {
      sum += r;
      squares += uint64_t(r) * r;
    }
    const double mean = double(sum) / double(n) / max_distance;
    prior_ = static_cast<int16_t>(std::lround(std::min(1.0, mean) * kOne));
    spread_ = static_cast<float>(
        std::sqrt(std::max(0.0, double(squares) / double(n) / (max_distance * max_distance) - mean * mean)));
    ++t_;
  }
  float best(size_t j) const
  {
    return static_cast<float>(best_[j]) / static_cast<float>(kOne);
  }
  /// best() with the pace prior, for a frame matched after search() with a prior.
  float searched(size_t j) const
  {
    return static_cast<float>(searched_[j]) / static_cast<float>(kOne);
  }
  /// The next frames search with this fraction of a change of pace as the prior (0: they do not search).
  void search(float prior_fraction)
  {
    prior_fraction_ = prior_fraction;
  }
  /// The first pace with the smallest cost of place j.
  size_t pace(size_t j) const
  {
    return size_t(std::min_element(costs_[j].begin(), costs_[j].end()) - costs_[j].begin());
  }

private:
  FrameMetric metric_;
  float keep_;
  std::vector<std::pair<int, int>> paces_;
  float penalty_;
  int tolerance_;
  float slip_;
  std::vector<std::vector<int16_t>> costs_;
  std::vector<int16_t> best_;
  std::vector<uint16_t> searched_;
  float prior_fraction_ = 0.0f;
  int16_t prior_ = 0;
  float spread_ = 0.0f;
  uint64_t t_ = 0;
  uint64_t first_id_ = 0;
};

/// The query: a stored place now and then (so some paths are far better than the rest), noise otherwise.
std::vector<uint64_t> queryAt(std::mt19937_64& rng, const PlaceDatabase& reference, int t)
{
  std::vector<uint64_t> q = openable_test::randomWords(rng, 2);
  if (t % 3 != 0 && reference.size() > 40)
  {
    const uint64_t* place = reference.descriptor(reference.size() - 40 + size_t(t % 17));
    q.assign(place, place + 2);
    q[0] ^= rng() & rng() & rng();  // a few bits off
  }
  return q;
}
}  // namespace

TEST(PaceKernels, EveryKernelEqualsTheFixedPointRecurrence)
{
  const DescriptorLayout layout = binaryLayout(128);
  ASSERT_FALSE(supportedPaceKernels().empty());
  for (PaceKernel kernel : supportedPaceKernels())
    for (bool bidirectional : {false, true})
      for (int tolerance : {0, 1, 2})
        for (size_t capacity : {size_t(0), size_t(3000)})
          for (float slip : {0.0f, 0.35f, 3.0f})
          {
            const std::string what = paceKernelName(kernel) + (bidirectional ? " bidirectional" : " forward") +
                                     " tolerance " + std::to_string(tolerance) + " capacity " +
                                     std::to_string(capacity) + " slip " + std::to_string(slip);
            std::mt19937_64 rng(17 + tolerance);
            PlaceDatabase reference(layout, capacity);
            PaceOptions options;
            options.kernel = kernel;
            options.tolerance = tolerance;
            options.max_pace = tolerance == 2 ? 2 : 3;
            options.slip = slip;
            PaceMatcher matcher(layout, 7, bidirectional, options);
            NaiveFixedPace naive(layout, 7, matcher.paces(), options.penalty, tolerance, slip);
            for (int t = 0; t < 45; ++t)
            {
              // 101 places a frame: rows cross the chunks of 2048 columns (twice), new places join every row, and
              // past 3000 the oldest leave. Five stay out of the row (the exclusion window).
              for (int k = 0; k < 101; ++k)
                reference.add(openable_test::randomWords(rng, 2), FrameInfo());
              const auto query = queryAt(rng, reference, t);
              const size_t candidates = reference.size() - 5;
              matcher.match(query.data(), reference, candidates);
              naive.match(query.data(), reference, candidates);
              ASSERT_EQ(matcher.columns(), candidates) << what;
              for (size_t j = 0; j < candidates; ++j)
              {
                ASSERT_EQ(matcher.normalized(j), naive.best(j)) << what << ", frame " << t << ", column " << j;
                const auto& slope = matcher.paces()[naive.pace(j)];
                ASSERT_EQ(matcher.pace(j), float(std::abs(slope.first)) / float(slope.second))
                    << what << ", frame " << t << ", column " << j;
              }
            }
          }
}

TEST(PaceKernels, AKernelTheCpuLacksIsRefused)
{
  const auto supported = supportedPaceKernels();
  EXPECT_EQ(supported.front(), PaceKernel::kPortable);
  for (PaceKernel kernel : {PaceKernel::kAvx2, PaceKernel::kAvx512})
    if (std::find(supported.begin(), supported.end(), kernel) == supported.end())
    {
      PaceOptions options;
      options.kernel = kernel;
      EXPECT_THROW(PaceMatcher(binaryLayout(128), 7, false, options), std::exception) << paceKernelName(kernel);
    }
}

// The AVX-512 kernel reads the places behind a block from it and the block before (31 at most): a faster
// max_pace runs another kernel with the same integers, and asking for AVX-512 there is refused.
TEST(PaceKernels, PacesBeyondTheAvx512ReachRunAnotherKernelWithTheSameResults)
{
  const DescriptorLayout layout = binaryLayout(128);
  for (int max_pace : {31, 40})  // 31: the widest AVX-512 reach (a slip reads 32 places behind); 40: beyond it
  {
    PaceOptions fastest;
    fastest.max_pace = max_pace;
    fastest.slip = 0.35f;
    PaceOptions portable = fastest;
    portable.kernel = PaceKernel::kPortable;
    PaceMatcher best(layout, 7, false, fastest), plain(layout, 7, false, portable);
    std::mt19937_64 rng(3);
    PlaceDatabase reference(layout);
    for (int t = 0; t < 20; ++t)
    {
      for (int k = 0; k < 150; ++k)
        reference.add(openable_test::randomWords(rng, 2), FrameInfo());
      const auto query = queryAt(rng, reference, t);
      best.match(query.data(), reference, reference.size());
      plain.match(query.data(), reference, reference.size());
      for (size_t j = 0; j < reference.size(); ++j)
        ASSERT_EQ(best.normalized(j), plain.normalized(j))
            << "max_pace " << max_pace << ", frame " << t << ", column " << j;
    }
  }
  const auto supported = supportedPaceKernels();
  if (std::find(supported.begin(), supported.end(), PaceKernel::kAvx512) != supported.end())
  {
    PaceOptions wide;
    wide.kernel = PaceKernel::kAvx512;
    wide.max_pace = 32;
    EXPECT_THROW(PaceMatcher(layout, 7, false, wide), std::exception);
    wide.max_pace = 31;
    EXPECT_NO_THROW(PaceMatcher(layout, 7, false, wide));
  }
}

// While searching, each kernel keeps every place's cost with its pace's prior as it writes the costs (equal to the
// plain recurrence's, to the bit), and each chunk's minimum with the prior comes from it; the place
// smallestDistinct() finds must be the smallest of the plain scan, across chunks and tails.
TEST(PaceKernels, EveryKernelsChunkMinimaCarryThePriorExactly)
{
  const DescriptorLayout layout = binaryLayout(128);
  for (PaceKernel kernel : supportedPaceKernels())
    for (bool bidirectional : {false, true})
      for (int tolerance : {0, 1})
        for (float slip : {0.0f, 0.35f})
        {
          const std::string what = paceKernelName(kernel) + (bidirectional ? " bidirectional" : " forward") +
                                   " tolerance " + std::to_string(tolerance) + " slip " + std::to_string(slip);
          PaceOptions options;
          options.kernel = kernel;
          options.tolerance = tolerance;
          options.slip = slip;
          options.prior = 0.24f;
          PaceMatcher matcher(layout, 7, bidirectional, options);
          NaiveFixedPace naive(layout, 7, matcher.paces(), options.penalty, tolerance, slip);
          std::mt19937_64 rng(29 + tolerance);
          PlaceDatabase reference(layout);
          std::vector<size_t> taken;
          for (int t = 0; t < 50; ++t)
          {
            for (int k = 0; k < 101; ++k)  // 5,050 places at the end: two whole chunks and a tail of any length
              reference.add(openable_test::randomWords(rng, 2), FrameInfo());
            matcher.setSearching(t % 5 != 2);
            naive.search(t % 5 != 2 ? options.prior : 0.0f);
            const auto query = queryAt(rng, reference, t);
            const size_t candidates = reference.size() - 5;
            matcher.match(query.data(), reference, candidates);
            naive.match(query.data(), reference, candidates);
            float lowest = 2.0f;
            for (size_t j = 0; j < candidates; ++j)
            {
              const float expected = t % 5 != 2 && t > 0 ? std::min(naive.searched(j), 1.0f) : naive.best(j);
              ASSERT_EQ(matcher.normalized(j), expected) << what << ", frame " << t << ", column " << j;
              lowest = std::min(lowest, matcher.normalized(j));
            }
            if (std::isnan(lowest) || t == 0)
              continue;
            matcher.smallestDistinct(1, 10, 1, taken);
            ASSERT_EQ(taken.size(), 1u) << what << ", frame " << t;
            ASSERT_EQ(matcher.normalized(taken[0]), lowest) << what << ", frame " << t;
          }
        }
}

// The screen of a large row (pace_kernels::ScreenChunk): every version against its definition written plainly, the
// smallest screen cost of the places a path comes from in one frame (0 to reach places behind, and ahead with
// bidirectional), a times it rounded, plus the entry of the place's own distance, saturated; the distances' sums and
// the chunk's smallest cost. Chunks of every length (the vector loops' tails), reaches 1 to 4, both directions,
// costs up to 1.0 and distances up to the largest.
TEST(PaceKernels, EveryScreenComputesTheScreenAsDefined)
{
  std::mt19937_64 rng(71);
  for (PaceKernel kernel : supportedPaceKernels())
    for (bool bidirectional : {false, true})
      for (long reach : {1L, 3L, 4L})
        for (size_t m : {size_t(1), size_t(7), size_t(16), size_t(33), size_t(2048)})
        {
          const long pad = 8;
          const size_t begin = 40;  // a chunk further along the row: old_screen is read by place
          std::vector<int16_t> old_screen(begin + m + 2 * pad), screen(old_screen.size(), -1);
          std::vector<uint32_t> raw(m);
          std::uniform_int_distribution<int> cost(0, kOne), distance(0, 384);
          for (auto& c : old_screen)
            c = static_cast<int16_t>(cost(rng));
          for (auto& r : raw)
            r = static_cast<uint32_t>(distance(rng));
          raw[0] = 384;  // the largest distance: an entry of at least 1.0 at the first row's scale
          pace_kernels::ScreenChunk c;
          c.raw = raw.data();
          c.begin = begin;
          c.m = m;
          c.reach = reach;
          c.bidirectional = bidirectional;
          c.entry_scale = m == 1 ? float(kOne) / 384.0f : 0.9f * float(kOne) / 384.0f / 30.0f;
          c.keep = m == 1 ? 0 : 31744;
          c.old_screen = old_screen.data() + pad;
          c.screen = screen.data() + pad;
          const pace_kernels::ScreenSums sums = pace_kernels::screenFor(kernel)(c);
          uint64_t sum = 0, squares = 0;
          int16_t smallest = kOne;
          for (size_t i = 0; i < m; ++i)
          {
            const long j = static_cast<long>(begin + i);
            int32_t path = old_screen[pad + j];
            for (long s = 1; s <= reach; ++s)
            {
              path = std::min<int32_t>(path, old_screen[pad + j - s]);
              if (bidirectional)
                path = std::min<int32_t>(path, old_screen[pad + j + s]);
            }
            const float entry = std::nearbyint(std::min(float(raw[i]) * c.entry_scale, float(kOne)));
            const int16_t expected = saturated(int32_t(entry) + ((path * c.keep + 16384) >> 15));
            ASSERT_EQ(screen[pad + j], expected) << paceKernelName(kernel) << " m " << m << " place " << i;
            sum += raw[i];
            squares += uint64_t(raw[i]) * raw[i];
            smallest = std::min(smallest, expected);
          }
          EXPECT_EQ(screen[pad + begin - 1], -1) << "wrote before the chunk";
          EXPECT_EQ(screen[pad + begin + m], -1) << "wrote after the chunk";
          EXPECT_EQ(sums.sum, sum);
          EXPECT_EQ(sums.squares, squares);
          EXPECT_EQ(sums.minimum, smallest);
        }
}
