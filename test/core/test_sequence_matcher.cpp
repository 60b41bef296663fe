// SequenceMatcher against a brute-force O(N * L) reference on random descriptors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <utility>
#include <vector>

#include "openable/error.h"
#include "openable/matching/frame_metric.h"
#include "openable/hamming/hamming.h"
#include "openable/matching/sequence_matcher.h"
#include "test_util.h"

using namespace openable;

namespace
{
DescriptorLayout binaryLayout(int words, int blocks = 1)
{
  DescriptorLayout layout;
  layout.binary = true;
  layout.cell_length = words * 64;
  layout.cell_words = words;
  layout.cells = blocks;
  layout.blocks = blocks;
  return layout;
}

/// The documented definition, computed directly: the sum of d(t - k, j -/+ k) over the terms k < L for which
/// the pair was comparable when query t - k arrived (the chain stops at the first pair that was not), and
/// not before query `start` (a restart).
struct BruteForce
{
  const FrameMetric& metric;
  std::vector<std::vector<uint64_t>> queries;
  std::vector<std::vector<uint64_t>> reference;  // by id
  std::function<bool(long query, long id)> comparable;

  std::pair<uint64_t, int> sum(long t, long j, int L, int direction, long start) const  // direction +1 or -1
  {
    uint64_t s = 0;
    int n = 0;
    for (long k = 0; k < L; ++k)
    {
      const long q = t - k, r = j - direction * k;  // forward: j - k; reverse: j + k
      if (q < start || r < 0 || r >= long(reference.size()) || !comparable(q, r))
        break;
      s += metric.distance(queries[q].data(), reference[r].data());
      ++n;
    }
    return {s, n};
  }
};

void expectRowMatches(const SequenceMatcher& m, const BruteForce& bf, long t, int L, bool bidirectional, long start,
                      size_t first_checked_column = 0)
{
  for (size_t c = first_checked_column; c < m.columns(); ++c)
  {
    const long j = long(m.firstId() + c);
    const auto fwd = bf.sum(t, j, L, +1, start);
    ASSERT_EQ(m.forwardSum(c), fwd.first) << "t=" << t << " j=" << j << " L=" << L;
    ASSERT_EQ(m.forwardCount(c), fwd.second) << "t=" << t << " j=" << j << " L=" << L;
    if (bidirectional)
    {
      const auto rev = bf.sum(t, j, L, -1, start);
      ASSERT_EQ(m.reverseSum(c), rev.first) << "reverse t=" << t << " j=" << j << " L=" << L;
      ASSERT_EQ(m.reverseCount(c), rev.second) << "reverse t=" << t << " j=" << j << " L=" << L;
    }
  }
}
}  // namespace

TEST(SequenceMatcher, LoopClosureModeEqualsBruteForce)
{
  std::mt19937_64 rng(3);
  for (int L : {1, 2, 3, 7, 20})
    for (int exclusion : {0, 1, 5, 13})
      for (bool bidirectional : {false, true})
      {
        const auto layout = binaryLayout(3);
        const FrameMetric metric(layout);
        PlaceDatabase db(layout);
        SequenceMatcher m(layout, L, bidirectional);
        BruteForce bf{metric, {}, {}, [exclusion](long q, long r) { return r <= q - 1 - exclusion; }};
        for (long t = 0; t < 60; ++t)
        {
          // Repeated descriptors make ties and zero distances, the cases where mistakes hide.
          auto d = (t % 9 == 4 && t > 20) ? bf.queries[t - 17] : openable_test::randomWords(rng, 3);
          bf.queries.push_back(d);
          const size_t candidates = db.size() > size_t(exclusion) ? db.size() - exclusion : 0;
          m.match(d.data(), db, candidates);
          ASSERT_EQ(m.columns(), candidates);
          expectRowMatches(m, bf, t, L, bidirectional, 0);
          db.add(d);
          bf.reference.push_back(d);
        }
      }
}

TEST(SequenceMatcher, LocalisationModeEqualsBruteForce)
{
  std::mt19937_64 rng(5);
  for (int L : {1, 4, 10, 45})
    for (bool bidirectional : {false, true})
    {
      const auto layout = binaryLayout(2);
      const FrameMetric metric(layout);
      PlaceDatabase map(layout);
      BruteForce bf{metric, {}, {}, [](long, long) { return true; }};
      for (int i = 0; i < 40; ++i)
      {
        bf.reference.push_back(openable_test::randomWords(rng, 2));
        map.add(bf.reference.back());
      }
      SequenceMatcher m(layout, L, bidirectional);
      for (long t = 0; t < 50; ++t)
      {
        bf.queries.push_back(t % 3 == 0 ? bf.reference[(t * 7) % 40] : openable_test::randomWords(rng, 2));
        m.match(bf.queries.back().data(), map, map.size());
        expectRowMatches(m, bf, t, L, bidirectional, 0);
      }
    }
}

TEST(SequenceMatcher, PanoramicShiftedMetricEqualsBruteForce)
{
  std::mt19937_64 rng(9);
  const auto layout = binaryLayout(1, 4);  // four sub-panoramas of one word
  const FrameMetric metric(layout);
  PlaceDatabase db(layout);
  SequenceMatcher m(layout, 5, true);
  BruteForce bf{metric, {}, {}, [](long q, long r) { return r <= q - 1 - 2; }};
  for (long t = 0; t < 30; ++t)
  {
    bf.queries.push_back(openable_test::randomWords(rng, 4));
    m.match(bf.queries.back().data(), db, db.size() > 2 ? db.size() - 2 : 0);
    expectRowMatches(m, bf, t, 5, true, 0);
    db.add(bf.queries.back());
    bf.reference.push_back(bf.queries.back());
  }
}

TEST(SequenceMatcher, ChangingLengthRestartsSequences)
{
  std::mt19937_64 rng(13);
  const auto layout = binaryLayout(2);
  const FrameMetric metric(layout);
  PlaceDatabase db(layout);
  SequenceMatcher m(layout, 6, true);
  BruteForce bf{metric, {}, {}, [](long q, long r) { return r <= q - 1; }};
  long start = 0;
  int L = 6;
  for (long t = 0; t < 70; ++t)
  {
    if (t == 25 || t == 47)
    {
      L = (t == 25) ? 3 : 11;
      m.setSequenceLength(L);
      start = t;
    }
    bf.queries.push_back(openable_test::randomWords(rng, 2));
    m.match(bf.queries.back().data(), db, db.size());
    expectRowMatches(m, bf, t, L, true, start);
    db.add(bf.queries.back());
    bf.reference.push_back(bf.queries.back());
  }
}

TEST(SequenceMatcher, BoundedHistoryKeepsFullSequencesExact)
{
  std::mt19937_64 rng(17);
  const auto layout = binaryLayout(2);
  const FrameMetric metric(layout);
  const int L = 4, exclusion = 3;
  PlaceDatabase db(layout, 32);  // evicts 2 frames at a time when full
  SequenceMatcher m(layout, L, false);
  BruteForce bf{metric, {}, {}, [](long q, long r) { return r <= q - 1 - exclusion; }};
  size_t evictions = 0;
  for (long t = 0; t < 200; ++t)
  {
    bf.queries.push_back(openable_test::randomWords(rng, 2));
    const uint64_t first_before = db.firstId();
    m.match(bf.queries.back().data(), db, db.size() > exclusion ? db.size() - exclusion : 0);
    ASSERT_EQ(m.firstId(), db.firstId());
    // A full sequence is exact; the oldest columns, whose sequences ran into evicted frames, restart
    // their chains and are full (and exact) again L frames later.
    size_t full = 0;
    for (size_t c = 0; c < m.columns(); ++c)
    {
      const long j = long(m.firstId() + c);
      if (m.forwardCount(c) != L)
        continue;
      ++full;
      ASSERT_EQ(m.forwardSum(c), bf.sum(t, j, L, +1, 0).first) << "t=" << t << " j=" << j;
    }
    if (t > 40)
    {
      ASSERT_GE(full + 2 * L, m.columns());  // restarted chains are full again L frames later
    }
    db.add(bf.queries.back());
    bf.reference.push_back(bf.queries.back());
    evictions += db.firstId() != first_before;
    ASSERT_LE(db.size(), 32u);
  }
  EXPECT_GT(evictions, 50u);
  EXPECT_GE(db.size(), 30u);  // 15/16 of the capacity at least
}

// Hundreds of columns: the in-place update crosses chunk boundaries (256 columns), and the candidate range
// shrinks and grows from frame to frame, so chains start, stop and restart inside and across chunks. Both
// widths of sums: 16-bit while L times the largest frame distance fits (HOG-B's 6 words, 384 bits, and 22
// words with L = 20: 28,160), 32-bit beyond (22 words, 1,408 bits, with L = 47: 66,176). L = 300 is longer
// than a chunk: the leaving terms a chunk hands to the next reach back past the chunk before.
TEST(SequenceMatcher, ManyColumnsWithChangingCandidatesEqualBruteForce)
{
  std::mt19937_64 rng(23);
  for (const auto& [words, L] : std::vector<std::pair<int, int>>{{6, 1}, {6, 2}, {6, 20}, {6, 300}, {22, 20}, {22, 47}})
    for (bool bidirectional : {false, true})
    {
      const auto layout = binaryLayout(words);  // 6: HOG-B, the fused AVX-512 kernel; 22: LDB's size
      const FrameMetric metric(layout);
      PlaceDatabase map(layout);
      const size_t places = L > 256 ? 1300 : 700;  // several steady chunks past the first L columns
      std::vector<size_t> candidates_of;           // by query
      BruteForce bf{metric, {}, {}, [&candidates_of](long q, long r) { return size_t(r) < candidates_of[q]; }};
      for (size_t i = 0; i < places; ++i)
      {
        // Few distinct descriptors: many equal sums.
        bf.reference.push_back(i % 5 == 0 && i > 0 ? bf.reference[i / 2] : openable_test::randomWords(rng, words));
        map.add(bf.reference.back());
      }
      SequenceMatcher m(layout, L, bidirectional);
      for (long t = 0; t < L + 25; ++t)  // full chains for the last 25 frames at least
      {
        // Mostly everything, sometimes a few columns fewer or far fewer (across a chunk boundary; not for
        // L = 300, whose chains would never be full again within the test).
        const size_t roll = rng() % 8;
        candidates_of.push_back(roll == 0 ? places - rng() % 3 : roll == 1 && L <= 256 ? 200 + rng() % 120 : places);
        bf.queries.push_back(t % 4 == 0 ? bf.reference[(t * 37) % places] : openable_test::randomWords(rng, words));
        m.match(bf.queries.back().data(), map, candidates_of.back());
        ASSERT_EQ(m.columns(), candidates_of.back());
        expectRowMatches(m, bf, t, L, bidirectional, 0);
      }
    }
}

// smallestDistinct() against the selection it replaces: normalizedRow(), then repeatedly the first smallest
// finite value with the windows of those taken blanked out.
TEST(SequenceMatcher, SmallestDistinctEqualsScanningTheRow)
{
  std::mt19937_64 rng(29);
  const auto naive =
      [](const SequenceMatcher& m, size_t count, size_t window, int min_terms, std::vector<size_t>& taken)
  {
    std::vector<float> row;
    m.normalizedRow(row, nullptr, min_terms);
    taken.clear();
    size_t finite = 0;
    for (float d : row)
      finite += std::isfinite(d);
    while (taken.size() < count)
    {
      size_t best = row.size();
      for (size_t c = 0; c < row.size(); ++c)
        if (std::isfinite(row[c]) && (best == row.size() || row[c] < row[best]))
          best = c;
      if (best == row.size())
        break;
      taken.push_back(best);
      for (size_t c = best > window ? best - window : 0; c <= best + window && c < row.size(); ++c)
        row[c] = std::nanf("");
    }
    return finite;
  };
  for (int L : {1, 3, 10})
    for (bool bidirectional : {false, true})
    {
      const auto layout = binaryLayout(1);
      PlaceDatabase db(layout);
      SequenceMatcher m(layout, L, bidirectional);
      for (long t = 0; t < 900; ++t)
      {
        // Descriptors of a few bits: ties everywhere, and stretches of exact repeats (distance 0).
        const uint64_t d = (t > 500 && t % 50 < 20) ? *db.descriptor(size_t(t - 400)) : rng() & 0x1F;
        const size_t exclusion = 30;
        m.match(&d, db, db.size() > exclusion ? db.size() - exclusion : 0);
        if (t % 7 == 0 || t > 880)
          for (size_t count : {1u, 5u})
            for (size_t window : {0u, 10u, 300u})
              for (int min_terms : {1, L})
              {
                std::vector<size_t> expected, got;
                const size_t expected_finite = naive(m, count, window, min_terms, expected);
                ASSERT_EQ(m.smallestDistinct(count, window, min_terms, got), expected_finite) << "t=" << t;
                ASSERT_EQ(got, expected) << "t=" << t << " L=" << L << " window=" << window;
              }
        db.add(&d, 1);
      }
    }
}

TEST(SequenceMatcher, NormalizedDistanceIsMeanTermOverMaximum)
{
  const auto layout = binaryLayout(1);
  PlaceDatabase db(layout);
  SequenceMatcher m(layout, 2, false);
  const uint64_t zeros = 0, ones = ~uint64_t(0), half = 0xFFFFFFFFull;
  db.add(&zeros, 1);
  db.add(&zeros, 1);
  m.match(&ones, db, 2);  // d = 64 to both
  EXPECT_FLOAT_EQ(m.normalized(0), 1.0f);
  m.match(&half, db, 2);  // column 1: (64 + 32) / 2 / 64
  EXPECT_FLOAT_EQ(m.normalized(1), 0.75f);
  EXPECT_FLOAT_EQ(m.normalized(0), 0.5f);  // chain restarted (column -1 does not exist): 32 / 64
}

TEST(SequenceMatcher, BadInput)
{
  const auto layout = binaryLayout(1);
  EXPECT_THROW(SequenceMatcher(layout, 0, false), Error);
  EXPECT_THROW(SequenceMatcher(layout, 70000, false), Error);
  SequenceMatcher m(layout, 2, false);
  PlaceDatabase other(binaryLayout(2));
  const uint64_t q[2] = {0, 0};
  EXPECT_THROW(m.match(q, other, 0), Error);
}

// A frame and its shifted views against a row (PaceMatcher's views): each row's smallest distance to any query,
// for plain binary rows (the Hamming kernels), sub-panoramas (the shifted metric) and unit float vectors.
TEST(FrameMetric, RowNearestIsEachRowsSmallestDistanceToAnyQuery)
{
  std::mt19937_64 rng(13);
  DescriptorLayout floats;
  floats.binary = false;
  floats.cell_length = 4;
  floats.cell_words = 2;
  for (const DescriptorLayout& layout : {binaryLayout(2), binaryLayout(1, 4), floats})
  {
    const FrameMetric metric(layout);
    const size_t words = layout.frameWords();
    const size_t count = 21, nq = 3;
    std::vector<uint64_t> rows, query_words;
    const auto randomFrame = [&] {
      if (layout.binary)
        return openable_test::randomWords(rng, words);
      std::normal_distribution<float> normal;
      std::vector<float> v(layout.cell_length);
      float norm = 0.0f;
      for (float& x : v)
      {
        x = normal(rng);
        norm += x * x;
      }
      for (float& x : v)
        x /= std::sqrt(norm);
      std::vector<uint64_t> frame(words);
      std::memcpy(frame.data(), v.data(), v.size() * sizeof(float));
      return frame;
    };
    for (size_t i = 0; i < count + nq; ++i)
    {
      const auto frame = randomFrame();
      (i < count ? rows : query_words).insert((i < count ? rows : query_words).end(), frame.begin(), frame.end());
    }
    std::vector<const uint64_t*> queries;
    for (size_t q = 0; q < nq; ++q)
      queries.push_back(query_words.data() + q * words);
    std::vector<uint32_t> out(count);
    metric.rowNearest(queries.data(), nq, rows.data(), count, out.data());
    size_t won[3] = {0, 0, 0};
    for (size_t i = 0; i < count; ++i)
    {
      uint32_t nearest = UINT32_MAX;
      size_t which = 0;
      for (size_t q = 0; q < nq; ++q)
      {
        const uint32_t d = metric.distance(queries[q], rows.data() + i * words);
        if (d < nearest)
          nearest = d, which = q;
      }
      ASSERT_EQ(out[i], nearest) << "row " << i << (layout.binary ? " binary" : " float");
      ++won[which];
    }
    EXPECT_GT(won[1] + won[2], 0u) << "a view never the nearest: the test would not see it ignored";
    EXPECT_THROW(metric.rowNearest(queries.data(), 0, rows.data(), count, out.data()), Error);
  }
}
