#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "openable/description/frame_describer.h"
#include "openable/error.h"
#include "openable/detection/loop_detector.h"
#include "acceptance_gate.h"
#include "test_util.h"

using namespace openable;

namespace
{
/// A stream of random LDB-sized descriptors that revisits frames 10..29 at frames 60..79.
std::vector<FrameDescriptor> revisitingStream()
{
  std::mt19937_64 rng(21);
  std::vector<FrameDescriptor> frames;
  for (int i = 0; i < 90; ++i)
  {
    if (i >= 60 && i < 80)
    {
      FrameDescriptor d = frames[i - 50];
      d[0] ^= rng() & 0xFF;  // a few bits of noise: nearly the same place
      frames.push_back(d);
    }
    else
      frames.push_back(openable_test::randomWords(rng, 22));
  }
  return frames;
}

/// A route of `places` random LDB-sized places, then its first `revisited` places again, each with a few bits of noise.
std::vector<FrameDescriptor> routeWalkedAgain(uint64_t seed, int places, int revisited)
{
  std::mt19937_64 rng(seed);
  std::vector<FrameDescriptor> frames;
  for (int i = 0; i < places; ++i)
    frames.push_back(openable_test::randomWords(rng, 22));
  for (int i = 0; i < revisited; ++i)
  {
    frames.push_back(frames[i]);
    frames.back()[0] ^= rng() & 0xFF;  // a few bits of noise: nearly the same place
  }
  return frames;
}
}  // namespace

TEST(LoopDetector, FindsRevisitsWithSequencesAndAcceptsBelowThreshold)
{
  Config c = Config::paper();
  c.sequence_length = 5;
  c.exclusion_window = 20;
  c.threshold = 0.2;
  LoopDetector detector(c);
  const auto frames = revisitingStream();
  int accepted = 0;
  for (int i = 0; i < 90; ++i)
  {
    const Detection d = detector.process(frames[i]);
    const bool passes = openable_test::passesAcceptanceGate(c, d);
    EXPECT_EQ(d.query_id, uint64_t(i));
    // Loop-closure mode compares full sequences only: the first is complete L - 1 frames after the window.
    EXPECT_EQ(d.has_candidates, i > c.exclusion_window + c.sequence_length - 1);
    if (i >= 64 && i < 80)  // full sequences inside the revisit
    {
      EXPECT_TRUE(passes) << i;
      EXPECT_EQ(d.best.id, uint64_t(i - 50));
      EXPECT_LT(d.best.distance, 0.02f);
      EXPECT_EQ(d.best.sequence_length, 5);
      EXPECT_GT(d.uniqueness, 0.9f);
      EXPECT_EQ(d.best.direction, 1);
    }
    if (i < 60)
    {
      EXPECT_FALSE(passes) << i;  // random descriptors are ~0.5 apart
    }
    accepted += passes;
  }
  EXPECT_GE(accepted, 16);
  EXPECT_LE(accepted, 22);
}

// min_loop_sequence_length: in loop-closure mode a sequence is a candidate once it has that many frames (at most
// L), both for the paper's sequences and for sequences at any pace; 0 waits for all L.
TEST(LoopDetector, LoopSequencesAreCandidatesFromMinLoopSequenceLengthFrames)
{
  const auto frames = revisitingStream();
  for (int max_pace : {1, 3})
    for (int least : {0, 1, 3, 5, 9})
    {
      Config c = Config::paper();
      c.sequence_length = 5;
      c.exclusion_window = 20;
      c.max_pace = max_pace;
      c.min_loop_sequence_length = least;
      const int frames_needed = least == 0 ? 5 : std::min(least, 5);
      LoopDetector detector(c);
      for (int i = 0; i < 40; ++i)
        EXPECT_EQ(detector.process(frames[i]).has_candidates, i > c.exclusion_window + frames_needed - 1)
            << "max_pace " << max_pace << ", min_loop_sequence_length " << least << ", frame " << i;
    }
}

// short_map_exclusion: while the stream's own map holds at most 2 x exclusion_window + L frames, a second matcher
// leaves out only its last short_map_exclusion frames, so a route of 15 places walked again at once (sooner than
// exclusion_window 20) is found. Once the map is longer, every detection is exactly the one of the detector without
// the short window: the session's own matcher went on behind it as if it were not there.
TEST(LoopDetector, AShortMapIsComparedBeyondItsShortWindowAndALongerMapAsWithoutIt)
{
  std::mt19937_64 rng(33);
  std::vector<FrameDescriptor> frames;
  for (int i = 0; i < 120; ++i)
  {
    const int revisits = i >= 15 && i < 30 ? i - 15 : (i >= 80 && i < 100 ? i - 40 : -1);
    frames.push_back(revisits >= 0 ? frames[revisits] : openable_test::randomWords(rng, 22));
    if (revisits >= 0)
      frames.back()[0] ^= rng() & 0xFF;  // a few bits of noise: nearly the same place
  }
  Config off = Config::paper();
  off.sequence_length = 5;
  off.exclusion_window = 20;
  off.threshold = 0.2;
  ASSERT_EQ(off.short_map_exclusion, -1);
  Config on = off;
  on.short_map_exclusion = 8;  // short while the map holds at most 2 x 20 + 5 = 45 frames
  LoopDetector with(on), without(off);
  for (int i = 0; i < 120; ++i)
  {
    const Detection a = with.process(frames[i]), b = without.process(frames[i]);
    if (i >= 5 && i < 40)
    {
      EXPECT_TRUE(a.short_map) << i;
    }
    if (i > 50)
    {
      EXPECT_FALSE(a.short_map) << i;
    }
    EXPECT_FALSE(b.short_map) << i;
    if (i >= 19 && i < 30)  // full sequences of the revisit, 15 to 4 frames after its place
    {
      EXPECT_TRUE(openable_test::passesAcceptanceGate(on, a)) << i;
      EXPECT_EQ(a.best.id, uint64_t(i - 15)) << i;
      EXPECT_FALSE(openable_test::passesAcceptanceGate(off, b)) << i;  // its place is inside the window
    }
    if (i >= 84 && i < 100)
    {
      EXPECT_EQ(a.best.id, uint64_t(i - 40)) << i;
    }
    if (i > 50)
    {
      EXPECT_EQ(a.has_candidates, b.has_candidates) << i;
      EXPECT_EQ(a.candidates, b.candidates) << i;
      EXPECT_EQ(a.best.id, b.best.id) << i;
      EXPECT_EQ(a.best.distance, b.best.distance) << i;
      EXPECT_EQ(a.uniqueness, b.uniqueness) << i;
      EXPECT_EQ(a.exclusion_edge_id, b.exclusion_edge_id) << i;
    }
    if (a.short_map && b.has_exclusion_edge && a.has_exclusion_edge)
    {
      EXPECT_EQ(a.exclusion_edge_id, b.exclusion_edge_id + 12) << i;  // the short window's edge, 20 - 8 newer
    }
  }
}

// A short map says when its best match is the session's first place (Detection::best_at_session_start): a
// partial sequence ending there has no past (LoopDecision starts no run from it).
TEST(LoopDetector, AShortMapSaysWhenItsBestMatchIsTheSessionsFirstPlace)
{
  const std::vector<FrameDescriptor> frames = routeWalkedAgain(34, 15, 2);
  Config c = Config::paper();
  c.sequence_length = 5;
  c.exclusion_window = 20;
  c.short_map_exclusion = 8;
  c.min_loop_sequence_length = 1;
  LoopDetector detector(c);
  for (int i = 0; i < 15; ++i)
  {
    const Detection d = detector.process(frames[i]);  // (the first frames compared have place 0 nearly alone)
    EXPECT_EQ(d.best_at_session_start, d.has_candidates && d.best.id == 0) << i;
  }
  const Detection first = detector.process(frames[15]);
  EXPECT_TRUE(first.short_map);
  EXPECT_EQ(first.best.id, 0u);
  EXPECT_TRUE(first.best_at_session_start);
  const Detection second = detector.process(frames[16]);
  EXPECT_EQ(second.best.id, 1u);
  EXPECT_FALSE(second.best_at_session_start);
  // A live change of the matcher's kind drops the short map's matcher with the others': the last row is unknown.
  Config live = c;
  live.max_pace = 3;
  detector.updateMatching(live);
  std::vector<float> row;
  detector.lastRow(row);
  ASSERT_EQ(row.size(), 17u);
  EXPECT_TRUE(std::all_of(row.begin(), row.end(), [](float d) { return std::isnan(d); }));
  EXPECT_TRUE(detector.process(frames[2]).short_map);
}

// A short map revisited before its matcher holds a full sequence: the revisit's first frames count no candidate (too
// early) but name their best paths, however short (MapMatcher::earlyPicks), for a run to reach back to. The places they
// name are the ones revisited; without the short window (a long map's rule) those frames have no candidate at all.
TEST(LoopDetector, AShortMapsRevisitNamesItsBestPlacesBeforeItsSequencesAreFull)
{
  const std::vector<FrameDescriptor> frames = routeWalkedAgain(35, 12, 8);
  Config c = Config::paper();
  c.sequence_length = 10;  // full sequences only (min_loop_sequence_length 0)
  c.exclusion_window = 20;
  c.short_map_exclusion = 8;  // places compared from frame 9 on: ten frames of evidence from frame 18
  Config off = c;
  off.short_map_exclusion = -1;
  LoopDetector detector(c), without(off);
  int named = 0;
  for (int i = 0; i < 20; ++i)
  {
    const Detection d = detector.process(frames[i]);
    EXPECT_FALSE(without.process(frames[i]).has_candidates) << i;
    if (i <= 8)
    {
      EXPECT_FALSE(d.has_candidates) << i;  // nothing beyond the short window yet
      continue;
    }
    EXPECT_TRUE(d.short_map) << i;
    ASSERT_TRUE(d.has_candidates) << i;
    if (i >= 12 && i < 17)  // the revisit's early frames: their own places, no candidate counted
    {
      EXPECT_EQ(d.candidates, 0u) << i;
      EXPECT_EQ(d.best.id, uint64_t(i - 12)) << i;
      ++named;
    }
    if (i == 19)
    {
      EXPECT_GT(d.candidates, 0u);  // ten frames matched: full sequences, counted
    }
  }
  EXPECT_EQ(named, 5);
}

TEST(LoopDetector, TopKAreDistinctPlacesBestFirst)
{
  Config c = Config::paper();
  c.top_k = 4;
  c.uniqueness_window = 3;
  c.exclusion_window = 0;
  LoopDetector detector(c);
  std::mt19937_64 rng(4);
  for (int i = 0; i < 40; ++i)
    detector.process(openable_test::randomWords(rng, 22));
  const Detection d = detector.process(openable_test::randomWords(rng, 22));
  ASSERT_EQ(d.top.size(), 4u);
  for (size_t i = 1; i < d.top.size(); ++i)
  {
    EXPECT_LE(d.top[i - 1].distance, d.top[i].distance);
    for (size_t j = 0; j < i; ++j)
      EXPECT_GT(std::labs(long(d.top[i].id) - long(d.top[j].id)), 3);
  }
  EXPECT_EQ(d.best.id, d.top[0].id);
}

TEST(LoopDetector, LastRowHasNaNForExcludedFramesAndItself)
{
  Config c = Config::paper();
  c.exclusion_window = 3;
  LoopDetector detector(c);
  std::mt19937_64 rng(8);
  std::vector<float> row;
  for (int i = 0; i < 10; ++i)
    detector.process(openable_test::randomWords(rng, 22));
  detector.lastRow(row);
  ASSERT_EQ(row.size(), 10u);
  for (size_t j = 0; j < 10; ++j)
    EXPECT_EQ(std::isnan(row[j]), j >= 6) << j;  // frame 9 vs 0..5 compared; 6, 7, 8 excluded; 9 itself
}

TEST(LoopDetector, LocalisationModeMatchesAgainstAFixedMap)
{
  Config c = Config::paper();
  c.sequence_length = 3;
  std::mt19937_64 rng(6);
  PlaceDatabase map(descriptorLayout(c));
  std::vector<FrameDescriptor> places;
  for (int i = 0; i < 30; ++i)
  {
    places.push_back(openable_test::randomWords(rng, 22));
    map.add(places.back());
  }
  LoopDetector detector(c, map);
  EXPECT_TRUE(detector.localisationMode());
  for (int i = 5; i < 15; ++i)
  {
    const Detection d = detector.process(places[i]);
    EXPECT_EQ(d.best.id, uint64_t(i));
    EXPECT_FLOAT_EQ(d.best.distance, 0.0f);
  }
  EXPECT_EQ(detector.map().frameCount(), 30u);  // nothing added to the map

  Config other = c;
  other.descriptor = "ORB";
  EXPECT_THROW(LoopDetector(other, map), Error);
}

TEST(LoopDetector, UpdateMatchingChangesLiveKeysAndRefusesDescriptorKeys)
{
  Config c = Config::paper();
  LoopDetector detector(c);
  Config live = c;
  live.threshold = 0.3;
  live.sequence_length = 8;
  live.exclusion_window = 2;
  detector.updateMatching(live);
  EXPECT_EQ(detector.sequenceLength(), 8);
  EXPECT_DOUBLE_EQ(detector.config().threshold, 0.3);
  Config bad = live;
  bad.patch_size = 32;
  EXPECT_THROW(detector.updateMatching(bad), Error);
  Config invalid = live;
  invalid.sequence_length = 0;
  EXPECT_THROW(detector.updateMatching(invalid), Error);
  EXPECT_EQ(detector.sequenceLength(), 8);  // unchanged after a refusal
}

TEST(LoopDetector, ResetForgetsHistoryButKeepsIdsIncreasing)
{
  LoopDetector detector{Config::paper()};
  std::mt19937_64 rng(10);
  for (int i = 0; i < 5; ++i)
    detector.process(openable_test::randomWords(rng, 22));
  detector.reset();
  EXPECT_EQ(detector.map().frameCount(), 0u);
  const Detection d = detector.process(openable_test::randomWords(rng, 22));
  EXPECT_EQ(d.query_id, 5u);
  EXPECT_FALSE(d.has_candidates);
}

TEST(LoopDetector, WrongDescriptorSizeIsAClearError)
{
  LoopDetector detector{Config::paper()};
  EXPECT_THROW(detector.process(FrameDescriptor(3)), Error);
  // Shifted views (lateral_shift) are whole descriptors of the layout, one after another: a part of one is refused
  // before anything is stored.
  const size_t words = descriptorLayout(Config::paper()).frameWords();
  try
  {
    detector.process(FrameDescriptor(words), FrameInfo(), FrameDescriptor(words + 1));
    FAIL() << "accepted a shifted view of " << words + 1 << " words";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("whole descriptors"), std::string::npos) << e.what();
  }
  EXPECT_EQ(detector.map().frameCount(), 0u);
}

TEST(LoopDetector, MinSequenceLengthLeavesPartialSequencesOut)
{
  Config c = Config::paper();
  c.sequence_length = 4;
  c.min_sequence_length = 0;  // only full sequences
  std::mt19937_64 rng(30);
  PlaceDatabase map(descriptorLayout(c));
  std::vector<FrameDescriptor> places;
  for (int i = 0; i < 20; ++i)
  {
    places.push_back(openable_test::randomWords(rng, 22));
    map.add(places.back());
  }
  LoopDetector detector(c, map);
  std::vector<float> row;
  for (int i = 0; i < 3; ++i)  // the first L - 1 queries have no full sequence anywhere
  {
    EXPECT_FALSE(detector.process(places[i]).has_candidates) << i;
    detector.lastRow(row);
    for (float v : row)
      EXPECT_TRUE(std::isnan(v));
  }
  const Detection d = detector.process(places[3]);
  ASSERT_TRUE(d.has_candidates);
  EXPECT_EQ(d.best.id, 3u);
  EXPECT_EQ(d.best.sequence_length, 4);
  detector.lastRow(row);
  for (int j = 0; j < 3; ++j)  // reference columns 0..2 cannot hold 4 terms
    EXPECT_TRUE(std::isnan(row[j])) << j;
  EXPECT_FALSE(std::isnan(row[3]));
}

// Shifted views (lateral_shift): each candidate says which of the query's views is nearest its place (Candidate::shift:
// -1 the left edge, +1 the right edge, 0 the centre, also where no view is nearer than the centre), so a backend knows
// the match faces a view's shift away. Known answers on random descriptors: a map of 12 places, queries whose one view
// is a stored place.
TEST(LoopDetector, EachCandidateSaysWhichShiftedViewIsNearestItsPlace)
{
  Config c = Config::paper();
  c.sequence_length = 1;
  c.max_pace = 3;  // the matcher at any pace compares views (max_pace 1, the paper's sums, compares centres)
  std::mt19937_64 rng(44);
  PlaceDatabase map(descriptorLayout(c));
  std::vector<FrameDescriptor> places;
  for (int i = 0; i < 12; ++i)
  {
    places.push_back(openable_test::randomWords(rng, 22));
    map.add(places.back());
  }
  const auto viewsOf = [](const FrameDescriptor& left, const FrameDescriptor& right)
  {
    FrameDescriptor views(left);
    views.insert(views.end(), right.begin(), right.end());
    return views;
  };
  const FrameDescriptor noise = openable_test::randomWords(rng, 22);
  struct Case
  {
    FrameDescriptor centre, left, right;
    uint64_t place;
    int shift;
  };
  const std::vector<Case> cases = {
      {noise, places[4], openable_test::randomWords(rng, 22), 4, -1},  // the left edge sees place 4
      {noise, openable_test::randomWords(rng, 22), places[9], 9, 1},   // the right edge sees place 9
      {places[7], places[7], places[7], 7, 0},                         // a tie keeps the centre
      {places[2], noise, noise, 2, 0},                                 // the centre sees place 2
  };
  for (const Case& k : cases)
  {
    LoopDetector detector(c, map);
    const Detection d = detector.process(k.centre, FrameInfo(), viewsOf(k.left, k.right));
    ASSERT_TRUE(d.has_candidates);
    EXPECT_EQ(d.best.id, k.place);
    EXPECT_EQ(d.best.shift, k.shift) << "place " << k.place;
    for (const Candidate& other : d.top)
      EXPECT_TRUE(other.shift >= -1 && other.shift <= 1);
  }
  // Without views every candidate's shift is 0.
  LoopDetector plain(c, map);
  for (const Candidate& other : plain.process(places[5]).top)
    EXPECT_EQ(other.shift, 0);
}

TEST(LoopDetector, AcceptanceNeedsAtLeastOneGateAndEverySetGate)
{
  const auto frames = revisitingStream();
  auto acceptedAt70 = [&frames](double threshold, double min_uniqueness)
  {
    Config c = Config::paper();
    c.sequence_length = 5;
    c.exclusion_window = 20;
    c.threshold = threshold;
    c.min_uniqueness = min_uniqueness;
    LoopDetector detector(c);
    Detection d;
    for (int i = 0; i <= 70; ++i)
      d = detector.process(frames[i]);
    return openable_test::passesAcceptanceGate(c, d);
  };
  EXPECT_FALSE(acceptedAt70(-1, 0.0));     // no gate: nothing is accepted
  EXPECT_TRUE(acceptedAt70(0.2, 0.0));     // distance gate only
  EXPECT_TRUE(acceptedAt70(-1, 0.5));      // uniqueness gate only (a revisit is very unique)
  EXPECT_FALSE(acceptedAt70(0.001, 0.5));  // both set: the distance gate fails
  EXPECT_FALSE(acceptedAt70(-1, 0.999));   // uniqueness gate fails
}
