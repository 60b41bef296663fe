// Issue 12: a map of several sessions, continued as a new session, merged, saved and loaded.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/detection/loop_detector.h"
#include "openable/detection/map_matcher.h"
#include "openable/map/session_map.h"
#include "acceptance_gate.h"
#include "test_util.h"

using namespace openable;

namespace
{
constexpr size_t kWords = 22;  // LDB on a 64-pixel patch

Config ldbConfig()
{
  // The paper's sequences (max_pace 1: only full sequences of L are candidates), which these tests were
  // written for; PaceSequencesDoNotRunAcrossTheEndOfOneSessionIntoTheNext runs the PaceMatcher.
  Config c = Config::paper();
  c.descriptor = "LDB";
  c.patch_size = 64;
  c.sequence_length = 5;
  c.exclusion_window = 10;
  c.min_uniqueness = 0.1;
  return c;
}

DescriptorLayout layoutOf(const Config& c)
{
  return FrameDescriber(c).layout();
}

/// Random places, one per frame.
std::vector<FrameDescriptor> route(std::mt19937_64& rng, int frames)
{
  std::vector<FrameDescriptor> out;
  for (int i = 0; i < frames; ++i)
    out.push_back(openable_test::randomWords(rng, layoutOf(ldbConfig()).frameWords()));
  return out;
}

/// The same places seen again with a few bits of noise.
FrameDescriptor revisit(const FrameDescriptor& place, std::mt19937_64& rng)
{
  FrameDescriptor d = place;
  d[0] ^= rng() & 0xF;
  return d;
}

std::string tempPath(const std::string& name)
{
  return testing::TempDir() + "/sessions_" + name;
}

std::string errorOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "";
}

/// Every detection of `frames` through `detector`, as (session, id, distance) of the best match.
std::vector<std::tuple<uint32_t, uint64_t, float>> bestMatches(LoopDetector& detector,
                                                               const std::vector<FrameDescriptor>& frames)
{
  std::vector<std::tuple<uint32_t, uint64_t, float>> out;
  for (const auto& f : frames)
  {
    const Detection d = detector.process(f);
    out.emplace_back(d.best.session, d.has_candidates ? d.best.id : UINT64_MAX, d.best.distance);
  }
  return out;
}
}  // namespace

TEST(SessionMap, SessionsHaveUniqueNamesAndIdsThatContinue)
{
  const Config c = ldbConfig();
  SessionMap map(layoutOf(c), c.toYaml());
  std::mt19937_64 rng(1);
  const uint32_t a = map.addSession({"day", "robot1", 0.0});
  for (int i = 0; i < 5; ++i)
  {
    FrameInfo info;
    info.stamp = 100.0 + i;
    EXPECT_EQ(map.add(a, openable_test::randomWords(rng, kWords), info), uint64_t(i));
  }
  EXPECT_EQ(map.session(a).start_stamp, 100.0);
  const uint32_t b = map.addSession({"night", "robot1", 0.0});
  EXPECT_EQ(map.add(b, openable_test::randomWords(rng, kWords)), 5u);  // ids go on after the first session
  EXPECT_EQ(map.frames(b).info(0).session, b);
  EXPECT_EQ(map.frameCount(), 6u);
  EXPECT_EQ(map.findSession("night"), 1);
  EXPECT_EQ(map.findSession("dusk"), -1);
  EXPECT_NE(errorOf([&] { map.addSession({"day", "", 0.0}); }).find("'day' is already in the map"), std::string::npos);
  EXPECT_NE(errorOf([&] { map.addSession({"", "", 0.0}); }).find("needs a name"), std::string::npos);
  EXPECT_EQ(map.sessionCount(), 2u);  // nothing added by the refusals
}

TEST(SessionMap, SavedAndLoadedWithEverySessionAndFrame)
{
  const Config c = ldbConfig();
  SessionMap map(layoutOf(c), c.toYaml());
  std::mt19937_64 rng(2);
  for (const char* name : {"first", "second", "third"})
  {
    const uint32_t s = map.addSession({name, std::string("robot_") + name, 0.0});
    for (int i = 0; i < 4 + static_cast<int>(s); ++i)
    {
      FrameInfo info;
      info.stamp = 10.0 * s + i;
      info.source = std::string(name) + std::to_string(i);
      info.has_pose = i % 2 == 0;
      info.pose[0] = i;
      map.add(s, openable_test::randomWords(rng, kWords), info);
    }
  }
  const std::string path = tempPath("three.map");
  map.save(path);
  const SessionMap back = SessionMap::load(path);
  ASSERT_EQ(back.sessionCount(), 3u);
  EXPECT_EQ(back.configYaml(), map.configYaml());
  for (uint32_t s = 0; s < 3; ++s)
  {
    EXPECT_EQ(back.session(s).name, map.session(s).name);
    EXPECT_EQ(back.session(s).robot, map.session(s).robot);
    EXPECT_EQ(back.session(s).start_stamp, map.session(s).start_stamp);
    ASSERT_EQ(back.frames(s).size(), map.frames(s).size());
    EXPECT_EQ(back.frames(s).firstId(), map.frames(s).firstId());
    for (size_t i = 0; i < map.frames(s).size(); ++i)
    {
      const FrameInfo x = map.frames(s).info(i), y = back.frames(s).info(i);
      EXPECT_EQ(y.id, x.id);
      EXPECT_EQ(y.session, s);
      EXPECT_EQ(y.source, x.source);
      EXPECT_EQ(y.has_pose, x.has_pose);
      EXPECT_EQ(y.pose, x.pose);
      EXPECT_EQ(std::vector<uint64_t>(back.frames(s).descriptor(i), back.frames(s).descriptor(i) + kWords),
                std::vector<uint64_t>(map.frames(s).descriptor(i), map.frames(s).descriptor(i) + kWords));
    }
  }
  // A map of several sessions is not one database.
  EXPECT_NE(errorOf([&] { PlaceDatabase::load(path); }).find("holds 3 sessions"), std::string::npos);
}

TEST(SessionMap, MergeRenumbersAndRefusesOtherConfigurationsAndRepeatedNames)
{
  const Config c = ldbConfig();
  std::mt19937_64 rng(3);
  SessionMap a(layoutOf(c), c.toYaml()), b(layoutOf(c), c.toYaml());
  a.addSession({"day", "", 0.0});
  b.addSession({"night", "", 0.0});
  for (int i = 0; i < 7; ++i)
    a.add(0, openable_test::randomWords(rng, kWords));
  for (int i = 0; i < 3; ++i)
    b.add(0, openable_test::randomWords(rng, kWords));
  const SessionMap merged = SessionMap::merge(a, b);
  ASSERT_EQ(merged.sessionCount(), 2u);
  EXPECT_EQ(merged.frames(1).firstId(), 7u);  // as if night had been recorded after day
  EXPECT_EQ(merged.frames(1).info(2).session, 1u);
  EXPECT_EQ(merged.frames(1).descriptor(2)[1], b.frames(0).descriptor(2)[1]);

  EXPECT_NE(errorOf([&] { SessionMap::merge(a, a); }).find("session name 'day' is in both maps"), std::string::npos);
  Config other = c;
  other.patch_size = 32;
  SessionMap small(layoutOf(other), other.toYaml());
  const std::string refusal = errorOf([&] { SessionMap::merge(a, small); });
  EXPECT_NE(refusal.find("different configurations: patch_size '64' (other '32')"), std::string::npos) << refusal;
}

TEST(LoopDetector, ContinuedSessionFindsLoopsWithTheMapAndWithinItself)
{
  const Config c = ldbConfig();
  std::mt19937_64 rng(4);
  const std::vector<FrameDescriptor> day = route(rng, 60);

  LoopDetector recording(c, SessionInfo{"day", "", 0.0});
  for (const auto& f : day)
    recording.process(f);
  const std::string path = tempPath("day.map");
  recording.map().save(path);

  // Night: day's places 10..39, then new places, then its own frames 60..79 of the night again.
  std::vector<FrameDescriptor> night;
  for (int i = 10; i < 40; ++i)
    night.push_back(revisit(day[i], rng));
  const std::vector<FrameDescriptor> fresh = route(rng, 30);
  night.insert(night.end(), fresh.begin(), fresh.end());
  for (int i = 0; i < 20; ++i)
    night.push_back(revisit(fresh[i], rng));

  LoopDetector detector(c, SessionMap::load(path), MapMode::Continue, SessionInfo{"night", "", 0.0});
  EXPECT_EQ(detector.ownSession(), 1);
  int with_day = 0, within_night = 0;
  for (size_t t = 0; t < night.size(); ++t)
  {
    const Detection d = detector.process(night[t]);
    EXPECT_EQ(d.query_id, 60 + t);  // the new session's ids follow the map's
    if (t >= 4 && t < 30)  // full sequences on day's route
    {
      ASSERT_TRUE(d.has_candidates) << t;
      EXPECT_EQ(d.best.session, 0u) << t;
      EXPECT_EQ(d.best.id, 10 + t) << t;
      with_day += openable_test::passesAcceptanceGate(c, d);
    }
    if (t >= 64)  // full sequences on the night's own earlier frames
    {
      EXPECT_EQ(d.best.session, 1u) << t;
      EXPECT_EQ(d.best.id, 60 + 30 + (t - 60)) << t;
      within_night += openable_test::passesAcceptanceGate(c, d);
    }
    // A sequence never spans two sessions: no match has more terms than its session had frames before it.
    if (d.has_candidates && d.best.session == 1)
    {
      EXPECT_LE(d.best.id - 60 + 1, t);
    }
  }
  EXPECT_GE(with_day, 24);
  EXPECT_GE(within_night, 14);
  EXPECT_EQ(detector.map().sessionCount(), 2u);
  EXPECT_EQ(detector.map().frames(0).size(), 60u);  // the loaded session is not touched
  EXPECT_EQ(detector.map().frames(1).size(), night.size());

  // Localising against the same map stores nothing and finds day's places.
  LoopDetector localiser(c, SessionMap::load(path), MapMode::Localise);
  EXPECT_TRUE(localiser.localisationMode());
  for (int i = 0; i < 10; ++i)
    localiser.process(night[static_cast<size_t>(i)]);
  EXPECT_EQ(localiser.map().frameCount(), 60u);

  EXPECT_NE(errorOf([&] { LoopDetector(c, SessionMap::load(path), MapMode::Continue, SessionInfo{"day", "", 0.0}); })
                .find("'day' is already in the map"),
            std::string::npos);
}

TEST(LoopDetector, SequencesDoNotRunAcrossTheEndOfOneSessionIntoTheNext)
{
  // Session two starts where session one ended: the map's frame after "one"'s last is "two"'s first, but a
  // query that retraces one's last frames then two's first must not find a sequence spanning both.
  Config c = ldbConfig();
  c.exclusion_window = 0;
  std::mt19937_64 rng(5);
  const std::vector<FrameDescriptor> one = route(rng, 20), two = route(rng, 20);
  SessionMap map(layoutOf(c), c.toYaml());
  for (const auto& [name, frames] : {std::make_pair("one", &one), std::make_pair("two", &two)})
  {
    const uint32_t s = map.addSession({name, "", 0.0});
    for (const auto& f : *frames)
      map.add(s, f);
  }
  // Continued (loop-closure rules: full sequences of L only; localising would accept partial ones).
  LoopDetector detector(c, map, MapMode::Continue, SessionInfo{"three", "", 0.0});
  for (int i = 15; i < 20; ++i)
    detector.process(revisit(one[static_cast<size_t>(i)], rng));
  for (int i = 0; i < 3; ++i)
  {
    const Detection d = detector.process(revisit(two[static_cast<size_t>(i)], rng));
    ASSERT_TRUE(d.has_candidates);
    // Stored as one run, one[15+i..19] + two[0..i] would be a perfect full sequence ending at two[i]. Kept
    // apart, two has only i + 1 frames of that chain (fewer than L = 5): no near-perfect match exists.
    EXPECT_FALSE(d.best.session == 1 && d.best.id == 20u + static_cast<uint64_t>(i)) << i;
    EXPECT_GT(d.best.distance, 0.2f) << i;
  }
}

TEST(LoopDetector, PaceSequencesDoNotRunAcrossTheEndOfOneSessionIntoTheNext)
{
  // With sequences at any pace every place is a candidate from its first frame, so the rule differs from the
  // paper's: a path into session two's first place must start there (from the row's prior), never continue
  // from session one's last place. The same query frames against session two alone give the same distances;
  // the same places stored as ONE session (the path may run through) give a closer match.
  Config c = ldbConfig();
  c.max_pace = 3;
  c.exclusion_window = 0;
  std::mt19937_64 rng(5);
  const std::vector<FrameDescriptor> one = route(rng, 20), two = route(rng, 20);
  std::vector<FrameDescriptor> queries;
  for (int i = 15; i < 20; ++i)
    queries.push_back(revisit(one[static_cast<size_t>(i)], rng));
  for (int i = 0; i < 3; ++i)
    queries.push_back(revisit(two[static_cast<size_t>(i)], rng));
  // The distance of the query frame 5 + i (two[i] seen again) to two[i], for each stored layout.
  const auto distancesToTwo = [&](const std::vector<std::vector<FrameDescriptor>>& sessions, uint64_t first_of_two)
  {
    SessionMap map(layoutOf(c), c.toYaml());
    for (size_t s = 0; s < sessions.size(); ++s)
    {
      const uint32_t id = map.addSession({"s" + std::to_string(s), "", 0.0});
      for (const auto& f : sessions[s])
        map.add(id, f);
    }
    LoopDetector detector(c, map, MapMode::Continue, SessionInfo{"query", "", 0.0});
    std::vector<float> out;
    for (size_t q = 0; q < queries.size(); ++q)
    {
      detector.process(queries[q]);
      std::vector<float> row;
      detector.lastRow(row);
      if (q >= 5)
        out.push_back(row[first_of_two + (q - 5)]);
    }
    return out;
  };
  std::vector<FrameDescriptor> joined = one;
  joined.insert(joined.end(), two.begin(), two.end());
  const std::vector<float> apart = distancesToTwo({one, two}, 20);
  const std::vector<float> alone = distancesToTwo({two}, 0);
  const std::vector<float> through = distancesToTwo({joined}, 20);
  for (size_t i = 0; i < apart.size(); ++i)
  {
    EXPECT_FLOAT_EQ(apart[i], alone[i]) << i;
    EXPECT_LT(through[i], apart[i]) << i << ": the joined route should have given the path a head start";
  }
}

TEST(LoopDetector, MergeThenContinueEqualsOneContinuedRun)
{
  const Config c = ldbConfig();
  std::mt19937_64 rng(6);
  const std::vector<FrameDescriptor> day = route(rng, 40);
  std::vector<FrameDescriptor> night, dusk;
  for (int i = 0; i < 40; ++i)
    night.push_back(revisit(day[static_cast<size_t>(i)], rng));
  for (int i = 5; i < 35; ++i)
    dusk.push_back(revisit(day[static_cast<size_t>(i)], rng));

  // One run: day, then night continued into it, then dusk.
  LoopDetector day_run(c, SessionInfo{"day", "", 0.0});
  bestMatches(day_run, day);
  LoopDetector night_run(c, day_run.map(), MapMode::Continue, SessionInfo{"night", "", 0.0});
  bestMatches(night_run, night);
  LoopDetector dusk_after_one(c, night_run.map(), MapMode::Continue, SessionInfo{"dusk", "", 0.0});
  const auto one = bestMatches(dusk_after_one, dusk);

  // Two maps recorded apart, merged, then dusk.
  LoopDetector night_alone(c, SessionInfo{"night", "", 0.0});
  bestMatches(night_alone, night);
  LoopDetector dusk_after_merge(c, SessionMap::merge(day_run.map(), night_alone.map()), MapMode::Continue,
                                SessionInfo{"dusk", "", 0.0});
  const auto merged = bestMatches(dusk_after_merge, dusk);
  EXPECT_EQ(merged, one);
  size_t found = 0;
  for (const auto& [session, id, distance] : one)
    found += id != UINT64_MAX && distance < 0.05f;
  EXPECT_GE(found, 20u);  // and they are real loops, not two identical failures
}

TEST(SessionMap, DescriptorHashFollowsOnlyTheDescriptorKeys)
{
  const Config c = ldbConfig();
  Config live = c;
  live.threshold = 0.3;  // a matching key: the descriptors stay comparable
  Config other = c;
  other.patch_size = 32;
  EXPECT_EQ(descriptorHash(live), descriptorHash(c));
  EXPECT_NE(descriptorHash(other), descriptorHash(c));
  EXPECT_EQ(descriptorHash(c), descriptorHash(Config::fromYamlString(c.toYaml())));
}

TEST(MapMatcher, CandidatesOfSeveralSessionsAreThoseOfOneScanOverAllRows)
{
  // Reference: the greedy scan over every session's row side by side (MapMatcher::lastRow), windows
  // clipped to their session; MapMatcher picks per session and merges. Same places, same order.
  Config c = ldbConfig();
  c.top_k = 5;
  c.uniqueness_window = 3;
  c.exclusion_window = 4;
  std::mt19937_64 rng(7);
  const std::vector<FrameDescriptor> places = route(rng, 30);
  SessionMap map(layoutOf(c), c.toYaml());
  for (int s = 0; s < 3; ++s)
  {
    const uint32_t session = map.addSession({"s" + std::to_string(s), "", 0.0});
    for (int i = 0; i < 25 + 5 * s; ++i)
      map.add(session, revisit(places[static_cast<size_t>((i + 7 * s) % 30)], rng));
  }
  const uint32_t own = map.addSession({"own", "", 0.0});
  MapMatcher matcher(c, map.layout(), false);
  std::vector<float> row;
  for (int t = 0; t < 40; ++t)
  {
    const FrameDescriptor query = revisit(places[static_cast<size_t>(t % 30)], rng);
    const Detection d = matcher.match(query, map, static_cast<int>(own), 0.0);
    matcher.lastRow(map, row);
    std::vector<size_t> starts;
    for (uint32_t s = 0, at = 0; s < map.sessionCount(); at += map.frames(s).size(), ++s)
      starts.push_back(at);
    starts.push_back(row.size());
    std::vector<std::pair<uint32_t, size_t>> expected;  // (session, position)
    size_t finite = 0;
    for (float v : row)
      finite += std::isfinite(v);
    while (expected.size() < static_cast<size_t>(c.top_k))
    {
      size_t best = row.size();
      for (size_t i = 0; i < row.size(); ++i)
        if (std::isfinite(row[i]) && (best == row.size() || row[i] < row[best]))
          best = i;
      if (best == row.size())
        break;
      const auto s = static_cast<uint32_t>(std::upper_bound(starts.begin(), starts.end(), best) - starts.begin() - 1);
      expected.emplace_back(s, best - starts[s]);
      for (size_t i = std::max(starts[s], best >= 3 ? best - 3 : 0); i <= best + 3 && i < starts[s + 1]; ++i)
        row[i] = std::nanf("");
    }
    EXPECT_EQ(d.candidates, finite) << t;
    ASSERT_EQ(d.top.size(), expected.size()) << t;
    for (size_t k = 0; k < expected.size(); ++k)
    {
      EXPECT_EQ(d.top[k].session, expected[k].first) << t << " #" << k;
      EXPECT_EQ(d.top[k].position, expected[k].second) << t << " #" << k;
    }
    map.add(own, query);
  }
}

namespace
{
/// Single frames matched at any pace (the PaceMatcher keeps the row's spread), every frame a candidate at once.
Config reliefConfig(int uniqueness_window)
{
  Config c = ldbConfig();
  c.max_pace = 3;
  c.sequence_length = 1;
  c.exclusion_window = 0;
  c.uniqueness_window = uniqueness_window;
  return c;
}

/// A map of `places` (session 0) and an empty session 1 the queries are stored in.
SessionMap mapOfRoute(const Config& c, const std::vector<FrameDescriptor>& places)
{
  SessionMap map(layoutOf(c), c.toYaml());
  const uint32_t stored = map.addSession({"first", "", 0.0});
  for (const FrameDescriptor& f : places)
    map.add(stored, f);
  map.addSession({"own", "", 0.0});
  return map;
}
constexpr uint32_t kRoute = 0, kOwn = 1;  // mapOfRoute's sessions
}  // namespace

TEST(MapMatcher, ReliefIsTheSpreadOfTheMatchsNeighboursInStandardDeviationsOfTheRow)
{
  // Reference: the query's frame distances to every place compared (a plain loop over the row), their population
  // standard deviation, and the largest minus the smallest within uniqueness_window of the best match.
  const Config c = reliefConfig(4);
  std::mt19937_64 rng(11);
  const std::vector<FrameDescriptor> places = route(rng, 60);
  const SessionMap map = mapOfRoute(c, places);
  MapMatcher matcher(c, map.layout(), false);
  const FrameMetric metric(map.layout());
  const double scale = static_cast<double>(map.layout().maxFrameDistance());
  for (int t = 0; t < 25; ++t)
  {
    const FrameDescriptor query = revisit(places[static_cast<size_t>(2 * t + 3)], rng);
    const Detection d = matcher.match(query, map, static_cast<int>(kOwn), 0.0);
    ASSERT_TRUE(d.has_candidates);
    std::vector<double> row;
    for (size_t j = 0; j < places.size(); ++j)
      row.push_back(metric.distance(query.data(), map.frames(kRoute).descriptor(j)) / scale);
    double mean = 0.0, squares = 0.0;
    for (double v : row)
      mean += v / static_cast<double>(row.size());
    for (double v : row)
      squares += (v - mean) * (v - mean) / static_cast<double>(row.size());
    const size_t best = static_cast<size_t>(d.best.id);
    const size_t low = best >= 4 ? best - 4 : 0, high = std::min(best + 4, places.size() - 1);
    const auto [smallest, largest] =
        std::minmax_element(row.begin() + static_cast<long>(low), row.begin() + static_cast<long>(high) + 1);
    EXPECT_NEAR(d.relief, (*largest - *smallest) / std::sqrt(squares), 1e-3) << t;
    EXPECT_GT(d.relief, 1.0f) << t << ": random places around a revisited one do not look alike";
  }
}

TEST(MapMatcher, ReliefIsNearZeroAmongLookAlikePlacesAndUnknownWithoutTheRowsSpread)
{
  const Config c = reliefConfig(5);
  std::mt19937_64 rng(12);
  std::vector<FrameDescriptor> places = route(rng, 50);
  for (size_t j = 15; j < 40; ++j)  // a snowfield: places that differ from place 27 by a bit or two
  {
    places[j] = places[27];
    if (j != 27)
      places[j][j % places[j].size()] ^= (j % 2 ? 1u : 3u);
  }
  const SessionMap map = mapOfRoute(c, places);
  MapMatcher pace(c, map.layout(), false);
  const Detection flat = pace.match(places[27], map, static_cast<int>(kOwn), 0.0);
  ASSERT_TRUE(flat.has_candidates);
  EXPECT_EQ(flat.best.id, 27u);
  EXPECT_LT(flat.relief, 0.1f);  // 2 bits of 256 among neighbours, against a row spread of about a quarter

  Config paper = c;
  paper.max_pace = 1;  // the paper's SequenceMatcher keeps no spread of the row
  MapMatcher diagonal(paper, map.layout(), false);
  EXPECT_TRUE(std::isnan(diagonal.match(places[27], map, static_cast<int>(kOwn), 0.0).relief));
}
