// OnlineDetector on real images: what it publishes in loop-closure mode (one stream revisiting itself),
// streams that must publish nothing, keyframes, time jumps, verification policy and map refusal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <tuple>
#include <opencv2/imgcodecs.hpp>

#include "openable/error.h"
#include "openable/detection/online_detector.h"
#include "openable/io/image_source.h"
#include "openable/verification/camera_calibration.h"
#include "test_util.h"

using namespace openable;

namespace
{
Config shipped(const std::string& name)
{
  return Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/" + name + ".yaml");
}

/// `config` without its view channel: the rules of one channel, measured on it alone.
Config wholeImageOnly(Config config)
{
  config.view_channel_shift = 0.0;
  return config;
}

cv::Mat nordland(const std::string& season, int index)
{
  char name[48];
  std::snprintf(name, sizeof(name), "nordland/%s/images-%05d.png", season.c_str(), (index + 1) * 10);
  return cv::imread(openable_test::sharedData(name), cv::IMREAD_COLOR);
}

/// Frames of one traversal after another, loaded once per test binary.
const std::vector<cv::Mat>& gardensPointStream(const std::string& first, const std::string& second)
{
  static std::map<std::string, std::vector<cv::Mat>> cache;
  std::vector<cv::Mat>& frames = cache[first + "+" + second];
  if (frames.empty())
    for (const std::string& traversal : {first, second})
      for (int i = 0; i < 200 && !traversal.empty(); ++i)
        frames.push_back(openable_test::gardensPoint(traversal, i));
  return frames;
}

/// A short route walked again: frames start .. start + places - 1 of `first`, then the same places of `second`.
std::vector<cv::Mat> gardensPointRoute(const std::string& first, const std::string& second, int start, int places)
{
  const std::vector<cv::Mat>& whole = gardensPointStream(first, second);
  std::vector<cv::Mat> frames(whole.begin() + start, whole.begin() + start + places);
  frames.insert(frames.end(), whole.begin() + 200 + start, whole.begin() + 200 + start + places);
  return frames;
}

std::vector<FrameOutcome> runStream(const std::vector<cv::Mat>& frames, const Config& config,
                                    const OnlineOptions& options = OnlineOptions(),
                                    const PinholeCamera* camera = nullptr)
{
  OnlineDetector detector(config, options);
  if (camera)
    detector.setCamera(*camera);
  std::vector<FrameOutcome> outcomes;
  for (size_t i = 0; i < frames.size(); ++i)
  {
    FrameInput input;
    input.image = frames[i];
    input.stamp = 1.0 + double(i);
    outcomes.push_back(detector.process(input));
  }
  return settled(std::move(outcomes));  // each frame with its final status, as decisions.csv has it
}

struct Scored
{
  int published = 0;
  int wrong = 0;
  double precision = 1.0;
  double recall = 0.0;
};

/// Joined stream: frame `half + i` is the place of frame i (within `tolerance`); earlier frames have no loop.
Scored score(const std::vector<FrameOutcome>& outcomes, size_t half, long tolerance)
{
  Scored s;
  int correct = 0;
  for (size_t t = 0; t < outcomes.size(); ++t)
  {
    if (!outcomes[t].published())
      continue;
    ++s.published;
    const long match = static_cast<long>(outcomes[t].detection.best.id);
    const bool right = t >= half && std::labs(match - static_cast<long>(t - half)) <= tolerance;
    correct += right ? 1 : 0;
    s.wrong += right ? 0 : 1;
  }
  s.precision = s.published ? double(correct) / s.published : 1.0;
  s.recall = double(correct) / double(outcomes.size() - half);
  return s;
}

/// The stream frame each stored frame's id stands for (frames standing still are not stored: Nordland's stations).
std::vector<long> framesOfIds(const std::vector<FrameOutcome>& outcomes)
{
  std::vector<long> frame_of;
  for (size_t t = 0; t < outcomes.size(); ++t)
    if (outcomes[t].stored)
    {
      frame_of.resize(std::max<size_t>(frame_of.size(), outcomes[t].query.id + 1), -1);
      frame_of[outcomes[t].query.id] = static_cast<long>(t);
    }
  return frame_of;
}

/// score(), with each match read as the stream frame it was stored from.
Scored scoreByFrame(std::vector<FrameOutcome> outcomes, size_t half, long tolerance)
{
  const std::vector<long> frame_of = framesOfIds(outcomes);
  for (FrameOutcome& o : outcomes)
    if (o.published())
      o.detection.best.id = static_cast<uint64_t>(frame_of.at(o.detection.best.id));
  return score(outcomes, half, tolerance);
}

/// A rule that adds loops on a joined stream (`half` frames with no loop, then their revisit): the stream with the
/// rule (`with`) and without it, both recalls recorded (`name` + `with_tag`, `name` + `without_tag`); no wrong loop,
/// at least `gain` more recall, nothing published in the first traversal. Returns the score with the rule.
Scored expectMoreLoopsAndNoWrongOne(const std::vector<cv::Mat>& frames, size_t half, const Config& with,
                                    const Config& without, double gain, const std::string& name,
                                    const std::string& with_tag, const std::string& without_tag)
{
  const auto outcomes = runStream(frames, with);
  const Scored added = score(outcomes, half, 2), before = score(runStream(frames, without), half, 2);
  ::testing::Test::RecordProperty(name + with_tag, std::to_string(added.recall));
  ::testing::Test::RecordProperty(name + without_tag, std::to_string(before.recall));
  EXPECT_EQ(added.wrong, 0) << name << ": " << added.published << " published";
  EXPECT_GE(added.recall, before.recall + gain) << name;
  for (size_t t = 0; t < half; ++t)
    EXPECT_FALSE(outcomes[t].published()) << name << ": frame " << t << " of the first traversal has no loop";
  return added;
}
}  // namespace

// A row beyond screen_places is screened (PaceMatcher): one cost a place, every pace only where the screen ranks first.
// Real frames: Nordland summer then winter (1,800 frames each, its own revisit), then Gardens Point day_right then
// night_right, about 3,900 places in two chunks of 2,048. With screen_places 2,048 one chunk (and the one after it)
// keeps every pace; what is published on the Gardens Point revisit is as right and as many as with the whole row.
TEST(OnlineDetector, AScreenedRowPublishesTheRevisitTheWholeRowPublishes)
{
  std::vector<cv::Mat> frames;
  for (const char* season : {"summer", "winter"})
    for (int i = 0; i < 1800; ++i)
      frames.push_back(nordland(season, i));
  const auto& gardens = gardensPointStream("day_right", "night_right");
  frames.insert(frames.end(), gardens.begin(), gardens.end());
  Config screened = shipped("default"), whole = shipped("default");
  ASSERT_EQ(screened.screen_places, 131072);
  screened.screen_places = 2048;
  whole.screen_places = 0;
  const auto a = runStream(frames, screened), b = runStream(frames, whole);
  // The Gardens Point part alone: its first traversal starts at frame 3,600, its places at the id stored there.
  const auto gardensScore = [&](const std::vector<FrameOutcome>& outcomes)
  {
    const std::vector<long> frame_of = framesOfIds(outcomes);
    Scored s;
    int correct = 0;
    for (size_t t = 3800; t < outcomes.size(); ++t)
    {
      if (!outcomes[t].published())
        continue;
      ++s.published;
      const long match = frame_of.at(outcomes[t].detection.best.id);
      const bool right = std::labs(match - static_cast<long>(t - 200)) <= 2;
      correct += right ? 1 : 0;
      s.wrong += right ? 0 : 1;
    }
    s.recall = correct / 200.0;
    return s;
  };
  const Scored with_screen = gardensScore(a), without = gardensScore(b);
  RecordProperty("screened_recall", std::to_string(with_screen.recall));
  RecordProperty("whole_recall", std::to_string(without.recall));
  EXPECT_EQ(with_screen.wrong, 0) << with_screen.published << " published";
  EXPECT_GE(with_screen.recall, without.recall - 0.02);
  EXPECT_GE(with_screen.recall, 0.8);
}

TEST(OnlineDetector, DefaultConfigurationPublishesTrustworthyLoopsDayThenNight)
{
  const auto outcomes = runStream(gardensPointStream("day_right", "night_right"), shipped("default"));
  const Scored s = score(outcomes, 200, 2);
  EXPECT_EQ(s.wrong, 0) << s.published << " published";
  EXPECT_GE(s.precision, 0.99);
  EXPECT_GE(s.recall, 0.3);  // measured 0.875 (issue 21 asks 0.8 of default.yaml here)
  RecordProperty("recall", std::to_string(s.recall));
  for (size_t t = 0; t < 200; ++t)
    EXPECT_FALSE(outcomes[t].published()) << "frame " << t << " of the first traversal has no loop";
}

// A run reaches back (run_start_tolerance): once it is consistent, the frames before it on its line join its loop
// closure. On real streams with a revisit it adds loops and no wrong one, each joined frame a loop with its own
// frame's place, and the first traversal (no revisit) still publishes nothing. Measured, default.yaml without runs
// that resume (run_resume_frames 0, which recovers some of the same frames): day_right -> night_right 0.765 -> 0.885,
// day_right -> day_left 0.335 -> 0.625 (doc/results.md "A run reaches back", "A run reaches further back").
TEST(OnlineDetector, ARunReachesBackToTheFramesOnItsLineAndNoWrongLoop)
{
  Config on = wholeImageOnly(shipped("default"));  // the view channel finds some of them its own way
  on.run_resume_frames = 0;
  Config off = on;
  ASSERT_GE(off.run_start_tolerance, 0);
  off.run_start_tolerance = -1;
  for (const char* second : {"night_right", "day_left"})
    expectMoreLoopsAndNoWrongOne(gardensPointStream("day_right", second), 200, on, off, 0.08,
                                 std::string("day_right_") + second, "_recall_reaching_back", "_recall_before");
}

// A short route (60 places, revisited once): in loop-closure mode a sequence is a candidate from
// min_loop_sequence_length (21) frames and min_candidates (21) places, not only once it has all L = 30 frames and
// 30 places, so the revisit gets candidates from its 12th frame instead of its 21st. Measured, default.yaml:
// day_right 0-59 then night_right 0-59 0.467 -> 0.767, day_left then day_right (not tuned on) 0.617 -> 0.767, 0
// wrong (doc/results.md "A short route"). Measured as then, with the exclusion of 50 frames throughout: the short
// map's own window (short_map_exclusion) compares the revisit's first frames too, the next test.
TEST(OnlineDetector, AShortRouteGetsLoopsFromTheRevisitsFirstFrames)
{
  Config now = shipped("default");
  now.short_map_exclusion = -1;
  Config before = now;
  ASSERT_EQ(before.min_loop_sequence_length, 21);
  before.min_loop_sequence_length = 0;  // only full sequences of L frames
  before.min_candidates = 30;
  for (const auto& [first, second] :
       {std::pair<const char*, const char*>{"day_right", "night_right"}, {"day_left", "day_right"}})
  {
    const std::vector<cv::Mat> frames = gardensPointRoute(first, second, 0, 60);
    const std::string stream = std::string(first) + "_" + second;
    const Scored partial = expectMoreLoopsAndNoWrongOne(frames, 60, now, before, 0.1, stream, "_short_recall",
                                                        "_short_recall_full_sequences");
    EXPECT_GE(partial.recall, 0.7) << stream;
    const Scored shipped_now = score(runStream(frames, shipped("default")), 60, 2);  // with the short map's window
    EXPECT_EQ(shipped_now.wrong, 0) << stream;
    EXPECT_GE(shipped_now.recall, 0.7) << stream;
  }
}

// A route walked again sooner than exclusion_window (50) frames, a corridor or a small room: while the map is short
// (at most 2 x 50 + 30 frames) a matcher of its own leaves out only short_map_exclusion (30) frames and answers for
// the stream's own candidates. Real routes of 40 and 60 Gardens Point places, each walked twice: with it more loops
// and no wrong one, nothing in the first traversal; without it (-1) a route of 40 places gets none.
TEST(OnlineDetector, ARouteShorterThanTheExclusionWindowGetsLoopsFromAShortMapsOwnWindow)
{
  const Config with = shipped("default");
  ASSERT_EQ(with.short_map_exclusion, 30);
  Config without = with;
  without.short_map_exclusion = -1;
  struct Route
  {
    const char* first;
    const char* second;
    int start;
    int places;
    double gain;
  };
  // Measured: 0 -> 0.600 and 0 -> 0.575 on the routes of 40 places, 0.700 -> 0.900 and 0.767 -> 0.950 on those of 60.
  for (const Route& r : {Route{"day_right", "day_left", 50, 40, 0.3}, Route{"day_right", "night_right", 100, 40, 0.3},
                         Route{"day_right", "day_left", 0, 60, 0.1}, Route{"day_left", "day_right", 0, 60, 0.1}})
  {
    const std::vector<cv::Mat> frames = gardensPointRoute(r.first, r.second, r.start, r.places);
    const std::string route = std::string(r.first) + "_" + r.second + "_" + std::to_string(r.start) + "_" +
                              std::to_string(r.places);
    expectMoreLoopsAndNoWrongOne(frames, static_cast<size_t>(r.places), with, without, r.gain, route,
                                 "_recall_short_window", "_recall_without");
  }
}

// A route of 40 places walked again: the revisit's first frames come before the short map holds min_candidates
// places beyond its window (frames 40-50 of the stream), too early for a decision. Their own best paths, short as they
// are, lie on the line of the run that follows, which reaches back to them as to frames not unique: the revisit's
// first frames get loops, late, and none is wrong. Measured (default.yaml): day_left then day_right 0-39 0.650 -> 0.850,
// day_right then night_right 0-39 0.650 -> 0.775; the routes of 40 places of scripts/pace_sets.py 32.76 -> 34.86.
TEST(OnlineDetector, ARevisitsFirstFramesTooEarlyForAShortMapJoinItsRunLate)
{
  const Config config = shipped("default");
  for (const auto& [first, second, least] : {std::make_tuple("day_left", "day_right", 0.8),
                                             std::make_tuple("day_right", "night_right", 0.75)})
  {
    const std::vector<cv::Mat> frames = gardensPointRoute(first, second, 0, 40);
    const std::vector<FrameOutcome> outcomes = runStream(frames, config);
    const Scored s = score(outcomes, 40, 2);
    SCOPED_TRACE(std::string(first) + " then " + second);
    EXPECT_EQ(s.wrong, 0);
    EXPECT_GE(s.recall, least);
    int early = 0;  // the revisit's frames before the short map has a candidate: too early as they came
    for (size_t t = 40; t <= 50; ++t)
      early += outcomes[t].published() ? 1 : 0;
    EXPECT_GE(early, 3);
  }
}

// A run's first frames that passed the gates themselves join it on its line, even where the frames between them and
// the run joined on the best path's line alone (LoopDecision::framesOnLineBefore). GP day_right then day_left 140-199
// walked again: the view channel's revisit frames 11-20 (uniqueness 0.062-0.082, its run 10 of 12 frames when a dip
// broke it) were lost behind frames 21-29; now 15-20 join (14 lies 1.5 places off the line), recall 0.600 -> 0.700
// (doc/results.md "A run's unique first frames").
TEST(OnlineDetector, ARunsUniqueFirstFramesJoinItOnItsLine)
{
  const std::vector<cv::Mat> frames = gardensPointRoute("day_right", "day_left", 140, 60);
  const std::vector<FrameOutcome> outcomes = runStream(frames, shipped("default"));
  const Scored s = score(outcomes, 60, 2);
  EXPECT_EQ(s.wrong, 0);
  EXPECT_GE(s.recall, 0.68);
  int first = 0;  // revisit frames 11-20
  for (size_t t = 71; t <= 80; ++t)
    first += outcomes[t].published() ? 1 : 0;
  EXPECT_GE(first, 5);
}

// lateral_shift: Gardens Point day_left then night_right is the other side of the path at night, the scene a tenth of
// the image or more further sideways. With places described from the centre 76 % of the image and each frame also
// from its left and right edges, the smallest distance counting, most of its loops are found, none wrong (pace
// sets: 53 -> 158 published at 1x, doc/results.md "Views shifted sideways").
TEST(OnlineDetector, ViewsShiftedSidewaysFindTheOtherSideOfThePathAtNight)
{
  Config whole = shipped("default");
  ASSERT_EQ(whole.lateral_shift, 0.0);
  whole.view_channel_shift = 0.0;
  Config shifted = whole;
  shifted.lateral_shift = 0.12;
  const Scored now = expectMoreLoopsAndNoWrongOne(gardensPointStream("day_left", "night_right"), 200, shifted, whole,
                                                  0.4, "day_left_night_right", "_shifted_recall", "_whole_recall");
  EXPECT_GE(now.recall, 0.75);
}

// The view channel (view_channel_shift, default.yaml): the whole image and its shifted views as two channels over
// the same stored frames, a frame's loop the first either publishes. It finds the other side of the path at night
// as lateral_shift does, and keeps what the whole image finds where lateral_shift loses it (day_right then
// night_right at 3x: 0.761 both, lateral_shift alone 0). Measured (doc/results.md "Two channels, built"): day_left
// then night_right 0.265 -> 0.745, day_right then day_left 0.900 -> 0.950, day_right then night_right 0.955 both.
TEST(OnlineDetector, AViewChannelFindsTheOtherSideOfThePathAndKeepsWhatTheWholeImageFinds)
{
  const Config joined = shipped("default");
  ASSERT_GT(joined.view_channel_shift, 0.0);
  Config whole = joined;
  whole.view_channel_shift = 0.0;
  const Scored other_side = expectMoreLoopsAndNoWrongOne(gardensPointStream("day_left", "night_right"), 200, joined,
                                                         whole, 0.4, "day_left_night_right", "_joined_recall",
                                                         "_whole_recall");
  EXPECT_GE(other_side.recall, 0.7);
  for (const char* second : {"night_right", "day_left"})
    expectMoreLoopsAndNoWrongOne(gardensPointStream("day_right", second), 200, joined, whole, 0.0,
                                 std::string("day_right_") + second, "_joined_recall", "_whole_recall");
  // 3x (every third frame of the revisit): the views alone lose it, the join keeps the whole image's loops.
  const auto& stream = gardensPointStream("day_right", "night_right");
  std::vector<cv::Mat> fast(stream.begin(), stream.begin() + 200);
  for (size_t i = 200; i < stream.size(); i += 3)
    fast.push_back(stream[i]);
  const auto outcomes = runStream(fast, joined), alone = runStream(fast, whole);
  int joined_right = 0, whole_right = 0;
  for (size_t t = 200; t < fast.size(); ++t)
  {
    const long place = static_cast<long>(3 * (t - 200));
    const auto right = [&](const FrameOutcome& o)
    { return o.published() && std::labs(static_cast<long>(o.detection.best.id) - place) <= 3; };
    joined_right += right(outcomes[t]) ? 1 : 0;
    whole_right += right(alone[t]) ? 1 : 0;
    EXPECT_TRUE(!outcomes[t].published() || right(outcomes[t])) << "frame " << t;
  }
  RecordProperty("day_right_night_right_3x_joined_right", joined_right);
  EXPECT_GE(joined_right, whole_right);
  EXPECT_GT(whole_right, 30);
}

// Issue 21: config/default.yaml stores at most 64 bytes a place, both channels' descriptors together (the whole
// image's 324 bits of HOG-B in 6 words, 128 of the crop's in 2).
TEST(OnlineDetector, TheDefaultStoresAtMost64BytesAPlaceInBothChannels)
{
  OnlineDetector detector(shipped("default"));
  ASSERT_NE(detector.viewChannel(), nullptr);
  FrameInput input;
  input.image = openable_test::gardensPoint("day_left", 0);
  input.stamp = 1.0;
  ASSERT_TRUE(detector.process(input).stored);
  ASSERT_NE(detector.viewChannel(), nullptr);
  const size_t whole = sizeof(uint64_t) * detector.loopDetector().map().layout().frameWords();
  const size_t views = sizeof(uint64_t) * detector.viewChannel()->detector.map().layout().frameWords();
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 1u);
  EXPECT_EQ(detector.viewChannel()->detector.map().frameCount(), 1u);
  EXPECT_EQ(whole, 48u);
  EXPECT_EQ(views, 16u);
  EXPECT_LE(whole + views, 64u);
  RecordProperty("default_bytes_a_place", static_cast<int>(whole + views));
}

// Both channels may confirm the same frame: it is published once, with the first loop closure that came.
TEST(OnlineDetector, AFrameIsPublishedOnceWhateverChannelsConfirmIt)
{
  OnlineDetector detector(shipped("default"));
  ASSERT_NE(detector.viewChannel(), nullptr);
  std::map<uint64_t, int> published;
  std::map<uint64_t, FrameOutcome> reported;
  int by_views = 0;
  const auto& stream = gardensPointStream("day_right", "day_left");
  for (size_t i = 0; i < stream.size(); ++i)
  {
    FrameInput input;
    input.image = stream[i];
    input.stamp = 1.0 + double(i);
    const FrameOutcome outcome = detector.process(input);
    reported[outcome.frame] = outcome;
    if (outcome.published())
      ++published[outcome.frame];
    for (const FrameOutcome& c : outcome.confirmed)
    {
      EXPECT_TRUE(c.published());
      ++published[c.frame];
      by_views += c.view_channel ? 1 : 0;
      // A frame reported with one channel's decision and confirmed by the other's moves from what was reported.
      const FrameOutcome& then = reported.at(c.frame);
      if (then.view_channel != c.view_channel)
      {
        EXPECT_EQ(c.status_before, then.status) << "frame " << c.frame;
      }
    }
  }
  EXPECT_GT(published.size(), 150u);
  EXPECT_GT(by_views, 0);  // measured: the whole image alone publishes 180 of these frames, both 190
  for (const auto& [frame, times] : published)
    EXPECT_EQ(times, 1) << "frame " << frame;
}

// Where there are no views the channel does not run: a frame too small for them (Nordland's 64x32: a crop would be
// enlarged), a panorama, D-LDB, lateral_shift (the whole image has views of its own), a map's later session.
TEST(OnlineDetector, AViewChannelRunsOnlyWhereThereAreViews)
{
  OnlineDetector small(shipped("default"));
  ASSERT_NE(small.viewChannel(), nullptr);
  FrameInput input;
  input.image = nordland("summer", 0);
  input.stamp = 1.0;
  small.process(input);
  EXPECT_EQ(small.viewChannel(), nullptr);
  small.reset();
  EXPECT_NE(small.viewChannel(), nullptr);
  Config ring = shipped("default");
  ring.camera_type = "panoramic";
  EXPECT_EQ(OnlineDetector(ring).viewChannel(), nullptr);
  Config dldb = shipped("default");
  dldb.camera_type = "stereo";
  dldb.descriptor = "D-LDB";
  EXPECT_EQ(OnlineDetector(dldb).viewChannel(), nullptr);
  Config shifted = shipped("default");
  shifted.lateral_shift = 0.12;
  EXPECT_EQ(OnlineDetector(shifted).viewChannel(), nullptr);
  const Config config = shipped("default");
  SessionMap empty(FrameDescriber(config).layout(), config.toYaml());
  SessionInfo session;
  session.name = "first";
  OnlineDetector first(config, empty, MapMode::Continue, session);
  EXPECT_NE(first.viewChannel(), nullptr);
  input.image = openable_test::gardensPoint("day_left", 0);
  first.process(input);
  SessionMap earlier = first.loopDetector().map();
  SessionInfo later;
  later.name = "later";
  EXPECT_EQ(OnlineDetector(config, earlier, MapMode::Continue, later).viewChannel(), nullptr);
}

// While no loop is published, a place is judged by its paths near the first pass's pace first (pace_prior): the
// revisit's first frames, which fit a lead of 3 or 4 places on a 1.5x path or a creeping 0.33x one as well as the
// truth, are found on their place. Measured, default.yaml: day_right -> day_left 0.735 -> 0.865, its short route
// (frames 0-59 of each) 0.200 -> 0.700, night_right -> day_right (not tuned on) 0.820 -> 0.945, 0 wrong
// (doc/results.md "A pace prior while searching"). The short route as measured then, with the exclusion of 50
// frames: with the short map's window the whole image alone (no view channel) publishes 6 wrong loops there, its
// first run 3 places ahead (doc/results.md "A short map's own window"; default.yaml's two channels publish none).
TEST(OnlineDetector, APacePriorWhileSearchingFindsTheRevisitsFirstFrames)
{
  const Config with = wholeImageOnly(shipped("default"));  // the view channel finds some of them its own way
  Config without = with;
  ASSERT_GT(without.pace_prior, 0.0);
  without.pace_prior = 0.0;
  for (const auto& [first, second, gain] : {std::tuple<const char*, const char*, double>{"day_right", "day_left", 0.1},
                                            {"night_right", "day_right", 0.08}})
    expectMoreLoopsAndNoWrongOne(gardensPointStream(first, second), 200, with, without, gain,
                                 std::string(first) + "_" + second, "_recall_with_prior", "_recall_without_prior");
  const std::vector<cv::Mat> frames = gardensPointRoute("day_right", "day_left", 0, 60);
  Config with_long_window = with, without_long_window = without;
  with_long_window.short_map_exclusion = without_long_window.short_map_exclusion = -1;
  const Scored short_route = expectMoreLoopsAndNoWrongOne(frames, 60, with_long_window, without_long_window, 0.3,
                                                          "short_route", "_recall_with_prior",
                                                          "_recall_without_prior");
  EXPECT_GE(short_route.recall, 0.65);
}

// A published run broken by a dip of uniqueness resumes (run_resume_frames) where the next frames' matches lie on
// its line, extended, at continue_uniqueness: on real streams with a revisit it adds loops and no wrong one, and the
// first traversal still publishes nothing. Measured, default.yaml: day_right -> day_left 0.805 -> 0.865, day_left
// -> day_right (not tuned on) 0.700 -> 0.870, day_right -> night_right 0.955 both (before the pace prior while
// searching: 0.625 -> 0.735, 0.660 -> 0.830 and 0.885 -> 0.875; a stream that does not resume searches again, and
// the prior now finds most of what resuming found) (doc/results.md "A run resumes", "A pace prior while searching").
TEST(OnlineDetector, ABrokenRunResumesOnItsLineAndNoWrongLoop)
{
  const Config with = wholeImageOnly(shipped("default"));  // the view channel finds some of them its own way
  Config off = with;
  ASSERT_GT(off.run_resume_frames, 0);
  off.run_resume_frames = 0;
  // day_right then day_left: 0.835 -> 0.900 when frames before a run joined on the run's line only; since they also
  // join on the line of its path's pace, the run that starts afresh takes most of them (0.910 -> 0.930).
  for (const auto& [first, second, gain] : {std::tuple<const char*, const char*, double>{"day_right", "day_left", 0.015},
                                            {"day_left", "day_right", 0.08},
                                            {"day_right", "night_right", -0.015}})
    expectMoreLoopsAndNoWrongOne(gardensPointStream(first, second), 200, with, off, gain,
                                 std::string(first) + "_" + second, "_recall_resuming", "_recall_not_resuming");
}

TEST(OnlineDetector, GardensPointConfigurationPublishesTrustworthyLoopsDayThenNight)
{
  const Scored s = score(runStream(gardensPointStream("day_right", "night_right"), shipped("gardens_point")), 200, 2);
  EXPECT_GE(s.precision, 0.99) << s.wrong << " wrong of " << s.published;
  EXPECT_GE(s.recall, 0.5);  // measured 0.910
  RecordProperty("recall", std::to_string(s.recall));
}

// Verification that may add recall (verified_min_uniqueness, verification_veto false): where it can confirm a
// place (the same daylight from the other side of the path) a verified frame passes with less uniqueness; where it
// cannot (day to night), appearance decides as without it. Either way it takes no loop away and adds no wrong one.
// Measured: day_left -> day_right recall 0.830 both, day_right -> night_right 0.875 both, 0 wrong (before a run's
// unconfirmed last frames could join a later run: 0.785 -> 0.815 and 0.870 both; before runs resumed: 0.645 ->
// 0.705; before they reached back: 0.480 -> 0.600 and 0.765): the frames it won are now taken by the later run.
// Gardens Point has no calibration: the assumed pinhole.
TEST(OnlineDetector, VerificationAddsRecallWhereItCanConfirmAndNoWrongLoop)
{
  const PinholeCamera camera =
      readCameraCalibration(std::string(OPENABLE_SOURCE_DIR) + "/test/data/calibration/gardens_point_assumed.yaml");
  Config config = shipped("default");
  config.verification_veto = false;
  OnlineOptions verifying;
  verifying.verify = true;
  verifying.verify_required = false;  // appearance decides what verification cannot check (veto false)
  for (const auto& [first, second, same_light] :
       {std::tuple<const char*, const char*, bool>{"day_left", "day_right", true}, {"day_right", "night_right", false}})
  {
    const auto& frames = gardensPointStream(first, second);
    const auto outcomes = runStream(frames, config, verifying, &camera);
    const Scored with = score(outcomes, 200, 2);
    const Scored without = score(runStream(frames, config), 200, 2);
    EXPECT_EQ(with.wrong, 0) << first << " -> " << second << ": " << with.published << " published";
    const std::string stream = std::string(first) + "_" + second;
    RecordProperty(stream + "_recall_without", std::to_string(without.recall));
    RecordProperty(stream + "_recall_with", std::to_string(with.recall));
    RecordProperty(stream + "_wrong_with", with.wrong);
    EXPECT_GE(with.recall, without.recall) << first << " -> " << second;
    int verified = 0;
    for (size_t t = 0; t < outcomes.size(); ++t)
    {
      EXPECT_TRUE(t >= 200 || !outcomes[t].published()) << "frame " << t << " of the first traversal has no loop";
      verified += outcomes[t].published() && outcomes[t].verified ? 1 : 0;
    }
    if (same_light)
    {
      EXPECT_GE(verified, 40) << first << " -> " << second;  // published loops that carry a relative pose
    }
  }
}

TEST(OnlineDetector, StreamsWithoutRevisitPublishNothing)
{
  for (const char* config : {"default", "gardens_point"})
  {
    const auto outcomes = runStream(gardensPointStream("day_left", ""), shipped(config));
    for (size_t t = 0; t < outcomes.size(); ++t)
      EXPECT_FALSE(outcomes[t].published()) << config << ": day_left frame " << t;
  }
  std::vector<cv::Mat> summer;
  for (int i = 0; i < 1800; ++i)
    summer.push_back(nordland("summer", i));
  for (const char* config : {"default", "nordland"})
  {
    const auto outcomes = runStream(summer, shipped(config));
    int published = 0;
    for (const auto& o : outcomes)
      published += o.published() ? 1 : 0;
    EXPECT_EQ(published, 0) << config << ": Nordland summer alone";
  }
}

// No loop among look-alike places (min_relief): Nordland winter 506-546 is a featureless stretch (every summer place
// within 10 of a frame's own is as far from it as that one), where the sequence drifted 2 places behind and was
// published there: every wrong loop of summer then winter at the first pass's pace. With the rule: none, and the
// recall issue 21 asks of this stream (0.85, near-black frames masked; here unmasked). Measured 12 wrong -> 0,
// recall 0.917 -> 0.893 (doc/results.md "No loop among look-alike places").
TEST(OnlineDetector, NoLoopAmongLookAlikePlacesNordlandSummerThenWinter)
{
  std::vector<cv::Mat> frames;
  for (const char* season : {"summer", "winter"})
    for (int i = 0; i < 1800; ++i)
      frames.push_back(nordland(season, i));
  Config without = shipped("default");
  without.min_relief = 0.0;
  const auto before = runStream(frames, without), now = runStream(frames, shipped("default"));
  const Scored loose = scoreByFrame(before, 1800, 1), gated = scoreByFrame(now, 1800, 1);
  RecordProperty("nordland_wrong_without_relief", std::to_string(loose.wrong));
  RecordProperty("nordland_recall_with_relief", std::to_string(gated.recall));
  EXPECT_GT(loose.wrong, 0) << "the stream no longer shows what the rule is for";
  EXPECT_EQ(gated.wrong, 0) << gated.published << " published";
  EXPECT_GE(gated.recall, 0.85);
  const std::vector<long> frame_of = framesOfIds(before);
  for (size_t t = 1800; t < before.size(); ++t)
    if (before[t].published() && std::labs(frame_of[before[t].detection.best.id] - static_cast<long>(t - 1800)) > 1)
    {
      EXPECT_GE(t - 1800, 506u) << "a wrong loop outside the look-alike stretch";
      EXPECT_LE(t - 1800, 546u) << "a wrong loop outside the look-alike stretch";
      EXPECT_FALSE(now[t].published()) << t - 1800;
      if (now[t].stored)  // (a frame standing still repeats the last stored one's decision: standstill)
      {
        EXPECT_EQ(now[t].status, FrameStatus::Featureless) << t - 1800;
      }
    }
}

// A configuration made for larger images on a small camera: gardens_point.yaml's patch of 128 on Nordland's 64x32
// frames. Each frame is described at its own size (Preprocessor: a cell smaller than the patch both ways is not
// enlarged into blocks), so the stream publishes what the same configuration at patch 64 publishes, frame by frame.
// Measured with scripts/pace_eval.py (doc/results.md): 795 published, 31 wrong, recall 0.424 when the frames were
// enlarged to 128; 1,416 published, 8 wrong (precision 0.994), recall 0.782 at their own size.
TEST(OnlineDetector, ASmallCameraIsDescribedAtItsOwnSizeNordlandWithTheGardensPointConfiguration)
{
  std::vector<cv::Mat> frames;
  for (const char* season : {"summer", "winter"})
    for (int i = 0; i < 1800; ++i)
      frames.push_back(nordland(season, i));
  const Config large = shipped("gardens_point");
  ASSERT_EQ(large.patch_size, 128);
  Config own = large;
  own.patch_size = 64;
  const auto at_large = runStream(frames, large), at_own = runStream(frames, own);
  ASSERT_EQ(at_large.size(), at_own.size());
  for (size_t t = 0; t < at_large.size(); ++t)
  {
    ASSERT_EQ(at_large[t].status, at_own[t].status) << t;
    if (at_large[t].published())
    {
      ASSERT_EQ(at_large[t].detection.best.id, at_own[t].detection.best.id) << t;
    }
  }
  const Scored scored = scoreByFrame(at_large, 1800, 1);
  RecordProperty("nordland_gardens_point_published", std::to_string(scored.published));
  RecordProperty("nordland_gardens_point_precision", std::to_string(scored.precision));
  RecordProperty("nordland_gardens_point_recall", std::to_string(scored.recall));
  EXPECT_GE(scored.precision, 0.99) << scored.wrong << " wrong of " << scored.published;
  EXPECT_GE(scored.recall, 0.75);
}

TEST(OnlineDetector, ARobotStandingStillClosesNoLoop)
{
  const std::vector<cv::Mat> still(300, openable_test::gardensPoint("day_right", 10));
  // With standstill detection (the default), the repeated image is one place; without it (neither the exact
  // repeat nor a still camera's noise), the matcher and the decision must still refuse a loop of the stop with
  // itself: every stored place looks like every other (featureless, min_relief).
  Config without = shipped("default");
  without.standstill_distance = 0.0;
  without.stop_distance = 0.0;
  for (const Config& config : {shipped("default"), without})
  {
    const auto outcomes = runStream(still, config);
    for (size_t t = 0; t < outcomes.size(); ++t)
    {
      ASSERT_FALSE(outcomes[t].published()) << t;
      if (t > 150)
      {
        EXPECT_EQ(outcomes[t].status,
                  config.standstill_distance > 0.0 ? FrameStatus::Standstill : FrameStatus::Featureless)
            << t;
      }
    }
  }
}

/// Every image of a folder of the shared data, in order, read as openable_offline reads it.
std::vector<cv::Mat> framesIn(const std::string& folder)
{
  ImageSource source(openable_test::sharedData(folder));
  std::vector<cv::Mat> frames;
  cv::Mat image;
  std::string name;
  while (source.next(image, name))
    frames.push_back(image.clone());
  return frames;
}

size_t storedFrames(const std::vector<FrameOutcome>& outcomes)
{
  return static_cast<size_t>(
      std::count_if(outcomes.begin(), outcomes.end(), [](const FrameOutcome& o) { return o.stored; }));
}

TEST(OnlineDetector, ARealCameraStandingStillStopsAddingPlacesAfterStopFrames)
{
  // The 40 frames of EuRoC V1_01's start (cam0, 20 Hz): the MAV on the ground, a real still camera with its sensor's
  // noise (consecutive frames 2 bits of HOG-B apart, none the same image as the one before).
  const std::vector<cv::Mat> still = framesIn("stereo/euroc_v101_micro/cam0/data");
  ASSERT_EQ(still.size(), 40u);
  // Cycled, the 40 real frames are a stop of 400 frames (20 s): its noise, not one image repeated.
  std::vector<cv::Mat> stop;
  for (int k = 0; k < 10; ++k)
    stop.insert(stop.end(), still.begin(), still.end());
  const Config config = shipped("default");
  ASSERT_GT(config.stop_distance, 0.0);
  const auto outcomes = runStream(stop, config);
  const size_t stored = storedFrames(outcomes);
  RecordProperty("euroc_still_frames", std::to_string(stop.size()));
  RecordProperty("euroc_still_stored", std::to_string(stored));
  // The first frame, stop_frames within its noise, and a frame or two whose noise strays past stop_distance.
  EXPECT_LE(stored, static_cast<size_t>(config.stop_frames) + 3);
  for (size_t t = 0; t < outcomes.size(); ++t)
  {
    EXPECT_FALSE(outcomes[t].published()) << t;
    if (!outcomes[t].stored)
    {
      EXPECT_EQ(outcomes[t].status, FrameStatus::Standstill) << t;
    }
  }
  // Without the rule, only an identical image is a standstill: nearly every noisy frame became a place.
  Config exact_only = config;
  exact_only.stop_distance = 0.0;
  const size_t stored_exact = storedFrames(runStream(stop, exact_only));
  RecordProperty("euroc_still_stored_exact_only", std::to_string(stored_exact));
  EXPECT_GT(stored_exact, stop.size() * 3 / 4);
  // A stop needs at least one stored frame within the noise to be told from a moving camera.
  Config at_once = config;
  at_once.stop_frames = 0;
  EXPECT_THROW(at_once.validateOrThrow(), Error);
}

TEST(OnlineDetector, AMovingCameraIsNeverTakenForAStop)
{
  // Consecutive frames of a moving camera are further apart than a still camera's noise: Gardens Point at a frame a
  // metre, KITTI 07 at 10 Hz (a car). Every frame is stored.
  const std::vector<cv::Mat> kitti = framesIn("kitti/07_first160/image_0");
  ASSERT_EQ(kitti.size(), 160u);
  const std::vector<const std::vector<cv::Mat>*> streams = {&gardensPointStream("day_right", "night_right"), &kitti};
  for (const std::vector<cv::Mat>* frames : streams)
  {
    const auto outcomes = runStream(*frames, shipped("default"));
    EXPECT_EQ(storedFrames(outcomes), frames->size());
  }
}

TEST(OnlineDetector, AStreamShorterThanASequenceIsTooEarlyOrExcluded)
{
  const std::vector<cv::Mat>& frames = gardensPointStream("day_right", "");
  const auto outcomes = runStream(std::vector<cv::Mat>(frames.begin(), frames.begin() + 25), shipped("default"));
  for (size_t t = 0; t < outcomes.size(); ++t)
  {
    EXPECT_TRUE(outcomes[t].stored);
    EXPECT_TRUE(outcomes[t].status == FrameStatus::TooEarly || outcomes[t].status == FrameStatus::Excluded)
        << t << ": " << toString(outcomes[t].status);
  }
}

TEST(OnlineDetector, ATimeJumpIsRefusedAndNothingIsStored)
{
  OnlineDetector detector(shipped("default"));
  FrameInput input;
  for (double stamp : {10.0, 11.0, 12.0})
  {
    input.image = openable_test::gardensPoint("day_right", static_cast<int>(stamp));  // moving: stored
    input.stamp = stamp;
    EXPECT_TRUE(detector.process(input).stored);
  }
  input.stamp = 5.0;
  const FrameOutcome jumped = detector.process(input);
  EXPECT_EQ(jumped.status, FrameStatus::TimeJump);
  EXPECT_FALSE(jumped.stored);
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 3u);
  detector.reset();  // a new stream may start earlier
  EXPECT_TRUE(detector.process(input).stored);
}

TEST(OnlineDetector, ExclusionInSecondsKeepsRecentFramesOut)
{
  Config c = shipped("paper");
  c.exclusion_window = 0;
  c.exclusion_seconds = 30.0;
  c.min_candidates = 1;
  OnlineDetector detector(c);
  FrameInput input;
  input.image = openable_test::gardensPoint("day_right", 0);
  FrameOutcome outcome;
  for (int i = 0; i < 40; ++i)  // one frame a second
  {
    input.stamp = 100.0 + i;
    outcome = detector.process(input);
    if (i > 0 && i < 30)
    {
      EXPECT_EQ(outcome.status, FrameStatus::Excluded) << i;
    }
  }
  EXPECT_EQ(outcome.detection.candidates, 10u);  // frames 0..9 are 30 s or more before frame 39
}

TEST(OnlineDetector, KeyframesByDistanceAndAngle)
{
  OnlineOptions options;
  options.keyframe_distance = 1.0;
  OnlineDetector by_distance(shipped("paper"), options);
  options.keyframe_distance = 0.0;
  options.keyframe_angle = 0.5;
  OnlineDetector by_angle(shipped("paper"), options);
  FrameInput input;
  input.image = openable_test::gardensPoint("day_right", 0);
  input.has_pose = true;
  int stored_distance = 0, stored_angle = 0;
  for (int i = 0; i < 20; ++i)
  {
    input.stamp = 1.0 + i;
    input.pose = {0.3 * i, 0, 0, 0, 0, 0, 1};  // 0.3 m a frame, no rotation
    const FrameOutcome moved = by_distance.process(input);
    stored_distance += moved.stored;
    if (!moved.stored)
    {
      EXPECT_EQ(moved.status, FrameStatus::NotKeyframe);
    }
    const double half = 0.1 * i;  // 0.2 rad a frame about z
    input.pose = {0, 0, 0, 0, 0, std::sin(half), std::cos(half)};
    stored_angle += by_angle.process(input).stored;
  }
  EXPECT_EQ(stored_distance, 5);  // at 0, 1.2, 2.4, 3.6 and 4.8 m (frames 0, 4, 8, 12, 16)
  EXPECT_EQ(stored_angle, 7);     // every third frame turns 0.6 rad >= 0.5
}

// A camera that only turns on the spot, built from a real 360-degree panorama: 90-degree views 2.25 degrees
// apart, two full turns. The second turn sees the first turn's views again: loops with the same heading only
// (a place is a position and a heading). (Turning back half way through the second turn is not asserted:
// the sequence goes on the old way for about 6 frames, 6 loops 9 to 31 degrees off; doc/results.md.)
TEST(OnlineDetector, ACameraThatOnlyTurnsOnTheSpotClosesLoopsWithTheSameHeadingOnly)
{
  const cv::Mat pano = cv::imread(openable_test::sharedData("panoramic/streetview_pairs/2_1.jpg"), cv::IMREAD_COLOR);
  ASSERT_FALSE(pano.empty());
  cv::Mat wrapped;
  cv::hconcat(pano, pano, wrapped);
  constexpr int kStep = 8, kWidth = 320;
  const int turn = pano.cols / kStep;  // 160 views a turn
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 2 * turn; ++i)
    frames.push_back(wrapped(cv::Rect((i % turn) * kStep, pano.rows / 4, kWidth, pano.rows / 2)).clone());
  const auto outcomes = runStream(frames, shipped("default"));
  int right = 0, wrong = 0;
  for (size_t t = 0; t < outcomes.size(); ++t)
  {
    if (!outcomes[t].published())
      continue;
    EXPECT_GE(t, size_t(turn)) << "the first turn has nothing to revisit";
    const int apart = std::abs(int(outcomes[t].detection.best.id % turn) - int(t % turn));
    const bool same_heading = std::min(apart, turn - apart) <= 2;
    right += same_heading ? 1 : 0;
    wrong += same_heading ? 0 : 1;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(right, turn * 7 / 10);  // measured 146 of 160
  RecordProperty("right", right);
}

TEST(OnlineDetector, RequiredVerificationNeverLetsAnUnverifiedLoopThrough)
{
  const auto& frames = gardensPointStream("day_right", "night_right");
  OnlineOptions options;
  options.verify = true;  // but no camera is ever given
  const auto required = runStream(frames, shipped("default"), options);
  options.verify_required = false;
  const auto flagged = runStream(frames, shipped("default"), options);
  int unverified = 0, published = 0;
  for (size_t t = 0; t < frames.size(); ++t)
  {
    EXPECT_FALSE(required[t].published()) << t;
    unverified += required[t].status == FrameStatus::Unverified;
    // Passed the decision: published, or (the run ending within confirm_frames) unconfirmed; or one of a run's
    // first frames, which may join it (run_start_tolerance): published with it, or left inconsistent.
    published += flagged[t].published() || flagged[t].status == FrameStatus::Unconfirmed ||
                 flagged[t].status == FrameStatus::Inconsistent;
    EXPECT_FALSE(flagged[t].verified);
    if (flagged[t].published())
    {
      EXPECT_EQ(flagged[t].verification_note, "no camera yet");
    }
  }
  EXPECT_GT(unverified, 50);
  EXPECT_EQ(unverified, published);  // the same candidates: flagged instead of dropped
}

TEST(OnlineDetector, RefusesAnEmptyMapAndAMapOfAnotherConfiguration)
{
  const Config hog = shipped("default");
  EXPECT_THROW(OnlineDetector(hog, PlaceDatabase(OnlineDetector(hog).describer().layout())), Error);
  const Config ldb = shipped("paper");
  PlaceDatabase map(OnlineDetector(ldb).describer().layout(), 0, ldb.toYaml());
  FrameInput first;
  first.image = openable_test::gardensPoint("day_right", 0);
  map.add(OnlineDetector(ldb).describe(first));
  EXPECT_THROW(OnlineDetector(hog, map), Error);
  EXPECT_NO_THROW(OnlineDetector(ldb, map));
}

TEST(OnlineDetector, BadInputThrowsBeforeAnythingIsStored)
{
  OnlineDetector detector(shipped("default"));
  EXPECT_THROW(detector.process(FrameInput()), Error);
  EXPECT_EQ(detector.loopDetector().map().frameCount(), 0u);
  Config stereo = shipped("paper");
  stereo.camera_type = "stereo";
  stereo.descriptor = "D-LDB";
  OnlineDetector dldb(stereo);
  FrameInput left_only;
  left_only.image = openable_test::gardensPoint("day_right", 0);
  try
  {
    dldb.process(left_only);
    FAIL() << "D-LDB without right image or disparity was accepted";
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("right image or a disparity"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dldb.loopDetector().map().frameCount(), 0u);
}
