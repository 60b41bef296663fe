// LoopDecision: known answers on hand-made detections, and a property test against a naive reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "openable/detection/loop_decision.h"

using namespace openable;

namespace
{
Config decisionConfig()
{
  Config c = Config::paper();
  c.min_uniqueness = 0.1;
  c.min_candidates = 10;
  c.consistent_frames = 3;
  c.consistency_tolerance = 1;
  return c;
}

Detection candidate(uint64_t match, float uniqueness, size_t candidates = 100, float distance = 0.2f, int direction = 1)
{
  Detection d;
  d.has_candidates = true;
  d.candidates = candidates;
  d.best.id = match;
  d.best.distance = distance;
  d.best.direction = static_cast<int8_t>(direction);
  d.uniqueness = uniqueness;
  Candidate rival = d.best;  // the second best place, beyond the uniqueness window
  rival.id += 50;
  d.top = {d.best, rival};
  return d;
}

/// A candidate whose best path holds `pace` (places a frame).
Detection paced(uint64_t match, float pace, float uniqueness = 0.3f)
{
  Detection d = candidate(match, uniqueness);
  d.best.pace = pace;
  return d;
}

/// The reach-back at any pace (max_pace 3, run_start_tolerance 1) with these consistency keys.
Config reachBackConfig(int consistent_frames, int consistency_tolerance)
{
  Config c = decisionConfig();
  c.consistent_frames = consistent_frames;
  c.consistency_tolerance = consistency_tolerance;
  c.max_pace = 3;
  c.run_start_tolerance = 1;
  return c;
}
}  // namespace

TEST(LoopDecision, StatusWordsAreTheDocumentedOnes)
{
  EXPECT_STREQ(toString(FrameStatus::Published), "published");
  EXPECT_STREQ(toString(FrameStatus::TooEarly), "too_early");
  EXPECT_STREQ(toString(FrameStatus::Excluded), "excluded");
  EXPECT_STREQ(toString(FrameStatus::AboveThreshold), "above_threshold");
  EXPECT_STREQ(toString(FrameStatus::NotUnique), "not_unique");
  EXPECT_STREQ(toString(FrameStatus::Inconsistent), "inconsistent");
  EXPECT_STREQ(toString(FrameStatus::Featureless), "featureless");
  EXPECT_STREQ(toString(FrameStatus::FailedVerification), "failed_verification");
  EXPECT_STREQ(toString(FrameStatus::Unverified), "unverified");
  EXPECT_STREQ(toString(FrameStatus::NotKeyframe), "not_keyframe");
  EXPECT_STREQ(toString(FrameStatus::TimeJump), "time_jump");
}

TEST(LoopDecision, SaysWhyThereIsNoLoop)
{
  LoopDecision decision(decisionConfig());
  Detection nothing;
  EXPECT_EQ(decision.decide(nothing), FrameStatus::TooEarly);
  nothing.excluded = true;
  EXPECT_EQ(decision.decide(nothing), FrameStatus::Excluded);
  EXPECT_EQ(decision.decide(candidate(5, 1.0f, 9)), FrameStatus::TooEarly);  // a lone candidate is not "unique"
  EXPECT_EQ(decision.decide(candidate(5, 0.05f)), FrameStatus::NotUnique);

  Config thresholded = decisionConfig();
  thresholded.threshold = 0.1;
  LoopDecision gated(thresholded);
  EXPECT_EQ(gated.decide(candidate(5, 0.9f, 100, 0.2f)), FrameStatus::AboveThreshold);

  Config ungated = decisionConfig();
  ungated.min_uniqueness = 0.0;
  LoopDecision open(ungated);
  EXPECT_EQ(open.decide(candidate(5, 0.9f)), FrameStatus::NotUnique);  // no gate: nothing is a loop
}

TEST(LoopDecision, PublishesOnlyAfterConsistentFramesAdvanceTogether)
{
  LoopDecision decision(decisionConfig());
  EXPECT_EQ(decision.decide(candidate(40, 0.3f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(41, 0.3f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(42, 0.3f)), FrameStatus::Published);
  EXPECT_EQ(decision.decide(candidate(44, 0.3f)), FrameStatus::Published);     // one frame off: within tolerance 1
  EXPECT_EQ(decision.decide(candidate(90, 0.3f)), FrameStatus::Inconsistent);  // jumped: a new run starts
  EXPECT_EQ(decision.decide(candidate(91, 0.3f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(92, 0.01f)), FrameStatus::NotUnique);  // a failing frame ends the run
  EXPECT_EQ(decision.decide(candidate(93, 0.3f)), FrameStatus::Inconsistent);
}

TEST(LoopDecision, APublishedFrameCountsItsRunsOwnFramesBeforeIt)
{
  // What the confirmation asks to take back what a broken run had reached back to: the run's frames before this one.
  LoopDecision decision(decisionConfig());
  decision.decide(candidate(40, 0.3f));
  EXPECT_EQ(decision.ownFramesBefore(), 0u);  // not published
  decision.decide(candidate(41, 0.3f));
  decision.decide(candidate(42, 0.3f));
  EXPECT_EQ(decision.ownFramesBefore(), 2u);  // 40 and 41
  decision.decide(candidate(43, 0.3f));
  EXPECT_EQ(decision.ownFramesBefore(), 3u);
  decision.decide(candidate(90, 0.3f));
  EXPECT_EQ(decision.ownFramesBefore(), 0u);  // a new run, not yet consistent
}

TEST(LoopDecision, AMatchThatStaysPutNeverBecomesConsistent)
{
  // A "hub" place that every frame matches (a tunnel, a wall): each step of 0 is within the tolerance of
  // 1, but over the run the match does not advance with the frames.
  LoopDecision decision(decisionConfig());
  for (int i = 0; i < 20; ++i)
    EXPECT_NE(decision.decide(candidate(19, 0.5f)), FrameStatus::Published) << i;
}

TEST(LoopDecision, ReverseRevisitsAdvanceBackwards)
{
  LoopDecision decision(decisionConfig());
  EXPECT_EQ(decision.decide(candidate(50, 0.3f, 100, 0.2f, -1)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(49, 0.3f, 100, 0.2f, -1)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(48, 0.3f, 100, 0.2f, -1)), FrameStatus::Published);
  EXPECT_EQ(decision.decide(candidate(49, 0.3f, 100, 0.2f, 1)), FrameStatus::Inconsistent);  // direction changed
}

TEST(LoopDecision, ARunsFirstFramesOnItsLineJoinItWhenItIsPublished)
{
  Config c = reachBackConfig(5, 2);
  LoopDecision decision(c);
  for (uint64_t m : {10, 11, 12, 13})
  {
    EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
    EXPECT_EQ(decision.joinedBefore().size(), 0u);
  }
  EXPECT_EQ(decision.decide(candidate(14, 0.3f)), FrameStatus::Published);
  EXPECT_EQ(decision.joinedBefore().size(), 4u);  // every earlier frame: on the line
  EXPECT_EQ(decision.decide(candidate(15, 0.3f)), FrameStatus::Published);
  EXPECT_EQ(decision.joinedBefore().size(), 0u);  // only where the run becomes consistent

  // The sequence lagged at the start: 13 is 2 places off the line 10 -> 14, within the consistency rule's 2 but
  // not the 1 of the frames published after the fact; counted back from the published frame, it stops there (a
  // frame unique enough but off the line is not a look-alike place to pass over).
  decision.reset();
  for (uint64_t m : {10, 13, 12, 13})
    EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(14, 0.3f)), FrameStatus::Published);
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{1, 2}));  // 13 and 12

  // A look-alike place for two not-unique frames (40, 41) before the run: the frames before them on the line join it
  // too; three in a row end the reach-back.
  for (const bool three : {false, true})
  {
    decision.reset();
    for (uint64_t m : {5, 6, 7, 40, 41})
      EXPECT_EQ(decision.decide(candidate(m, 0.01f)), FrameStatus::NotUnique);
    if (three)
      decision.decide(candidate(42, 0.01f));
    for (uint64_t m : {10, 11, 12, 13})
      decision.decide(candidate(m, 0.3f));
    EXPECT_EQ(decision.decide(candidate(14, 0.3f)), FrameStatus::Published);
    const std::vector<size_t> expected =
        three ? std::vector<size_t>{1, 2, 3, 4} : std::vector<size_t>{1, 2, 3, 4, 7, 8, 9};
    EXPECT_EQ(decision.joinedBefore(), expected);
  }

  // Before the run, frames not unique enough to start it, on its line extended back: they join it too, back to the
  // first that was decided otherwise or the third in a row off the line (4: the line says 6; 20: 5).
  decision.reset();
  for (uint64_t m : {20, 4, 7, 8, 9})
  {
    EXPECT_EQ(decision.decide(candidate(m, 0.01f)), FrameStatus::NotUnique);
    EXPECT_TRUE(decision.mayJoinLater());
  }
  for (uint64_t m : {10, 11, 12, 13})
    EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(14, 0.3f)), FrameStatus::Published);
  EXPECT_FALSE(decision.mayJoinLater());
  EXPECT_EQ(decision.joinedBefore().size(), 7u);  // 13, 12, 11, 10, then 9, 8, 7
  EXPECT_EQ(decision.decide(Detection()), FrameStatus::TooEarly);
  EXPECT_FALSE(decision.mayJoinLater());  // no best match

  c.run_start_tolerance = -1;  // off
  LoopDecision off(c);
  off.decide(candidate(9, 0.01f));
  EXPECT_FALSE(off.mayJoinLater());  // nothing is held for a reach-back that never comes
  for (uint64_t m : {10, 11, 12, 13, 14})
  {
    off.decide(candidate(m, 0.3f));
    EXPECT_FALSE(off.mayJoinLater());
  }
  EXPECT_EQ(off.joinedBefore().size(), 0u);
}

// A run's own frames that were published and then held (the run broke before they were confirmed) passed the
// gates on their run's line: a new run whose line passes within consistency_tolerance of them takes them, when
// the frame after each joined too; the frames that never passed keep run_start_tolerance.
TEST(LoopDecision, HeldFramesOfABrokenRunJoinWithinConsistencyTolerance)
{
  Config c = reachBackConfig(4, 2);
  LoopDecision decision(c);
  const std::vector<uint64_t> matches = {13, 14, 16, 17, 18, 21, 22, 22, 23, 23, 24};
  const std::vector<FrameStatus> statuses = {
      FrameStatus::Inconsistent, FrameStatus::Inconsistent, FrameStatus::Inconsistent, FrameStatus::Published,
      FrameStatus::Published,    FrameStatus::Published,    FrameStatus::Published,    FrameStatus::Published,
      FrameStatus::Published,    FrameStatus::Inconsistent, FrameStatus::Published};
  for (size_t k = 0; k < matches.size(); ++k)
    EXPECT_EQ(decision.decide(candidate(matches[k], 0.3f)), statuses[k]) << k;
  // The line through the last four matches (22, 23, 23, 24: 2/3 of a place a frame), extended back: 23, 22, 22 and
  // 21 lie within 1 of it; 18, a published frame right before them, 2 places (20 on the line) joins too; 17 is 2.33
  // off and ends the reach-back.
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{1, 2, 3, 4, 5, 6}));

  c.consistency_tolerance = 1;  // the run's own frames held no looser than the frames before a run
  LoopDecision tight(c);
  for (size_t k = 0; k < matches.size(); ++k)
    tight.decide(candidate(matches[k], 0.3f));
  EXPECT_EQ(tight.joinedBefore(), (std::vector<size_t>{1, 2, 3, 4, 5}));
}

// The frames before a run also join on the line of the best path's pace through the run's last match, where their
// own path held that pace and the run's line agrees with it within a step of the grid: the run's line through its
// first and last matches is tilted by a place off at either end (here 39 .. 47 over 3 frames: 2.67 a frame at pace
// 3). Once a frame is on the path's line alone, the reach-back keeps to that line.
TEST(LoopDecision, FramesBeforeARunJoinOnTheLineOfItsPathsPace)
{
  const Config c = reachBackConfig(4, 1);
  const std::vector<uint64_t> before = {25, 27, 30, 33, 36}, run = {39, 42, 45, 47};
  const auto decideStream = [&](float pace_before)
  {
    LoopDecision decision(c);
    for (uint64_t match : before)  // not unique enough to start a run
      EXPECT_EQ(decision.decide(paced(match, pace_before, 0.05f)), FrameStatus::NotUnique) << match;
    for (size_t k = 0; k < run.size(); ++k)
      EXPECT_EQ(decision.decide(paced(run[k], 3.0f)),
                k + 1 < run.size() ? FrameStatus::Inconsistent : FrameStatus::Published)
          << k;
    return decision.joinedBefore();
  };
  // On the run's line (47 - 2.67 k): 45, 42, 39, 36, 33 and 30 (31.0, 1 off); 27 is 1.33 off it, and 1 off the
  // path's line (47 - 3 k = 26), so it joins there; 25 lies on the run's line (25.7) but 2 off the path's: not taken.
  EXPECT_EQ(decideStream(3.0f), (std::vector<size_t>{1, 2, 3, 4, 5, 6, 7}));
  // Frames whose path went at another pace: the run's line alone (27 passed over as not unique, 25 on it).
  EXPECT_EQ(decideStream(1.0f), (std::vector<size_t>{1, 2, 3, 4, 5, 6, 8}));
}

// Once the reach-back goes on along the path's line alone, a frame that passed the gates itself (Inconsistent) is
// still judged on the run's line: its own run began on a slower path at the revisit's start (GP day_right then
// day_left 140-199, the view channel: revisit frames 71-80 cut off behind frames joined on the path's line). A frame
// that was not unique is not: past the path's line it is passed over, as before.
TEST(LoopDecision, AFrameThatPassedTheGatesJoinsOnTheRunsLineAfterThePathsLineAlone)
{
  const Config c = reachBackConfig(6, 1);
  const auto decideStream = [&](float first_uniqueness)
  {
    LoopDecision decision(c);
    for (uint64_t m : {31, 32, 33})  // a slower path's frames, unique or not
      decision.decide(paced(m, 0.75f, first_uniqueness));
    for (uint64_t m : {32, 33, 35, 36, 37, 38})  // not unique, at the run's path's pace
      EXPECT_EQ(decision.decide(paced(m, 1.15f, 0.05f)), FrameStatus::NotUnique) << m;
    for (uint64_t m : {40, 41, 42, 43, 44})
      EXPECT_EQ(decision.decide(paced(m, 1.15f)), FrameStatus::Inconsistent) << m;
    EXPECT_EQ(decision.decide(paced(45, 1.15f)), FrameStatus::Published);
    return decision.joinedBefore();
  };
  // The run's line 45 - k takes 44 .. 38 (back 1-6, 38 one off) and 37, 36, 35; 33 and 32 are 2 off it but on the
  // path's line (45 - 1.15 k: 33.5, 32.35). Then 33, 32, 31 lie on the run's line exactly, 1.8 and more off the path's.
  EXPECT_EQ(decideStream(0.3f), (std::vector<size_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14}));
  EXPECT_EQ(decideStream(0.05f), (std::vector<size_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
}

// On the path's line a frame joins within run_start_tolerance only, never the wider tolerance (consistency_tolerance)
// of a held frame of a broken run: a run that broke lagging the revisit would join the next run's line places off
// (the place server, GP day_left then night_right: night_right 41 as day_left 38).
TEST(LoopDecision, AHeldFrameJoinsOnThePathsLineWithinRunStartToleranceOnly)
{
  const Config c = reachBackConfig(5, 2);
  LoopDecision decision(c);
  for (uint64_t m : {4, 7, 10, 13})
    EXPECT_EQ(decision.decide(paced(m, 3.0f)), FrameStatus::Inconsistent) << m;
  EXPECT_EQ(decision.decide(paced(16, 3.0f)), FrameStatus::Published);  // run A, held as published
  for (uint64_t m : {22, 25, 28, 31})  // 22 is 3 off A's line (19): A breaks, run B begins
    EXPECT_EQ(decision.decide(paced(m, 3.0f)), FrameStatus::Inconsistent) << m;
  EXPECT_EQ(decision.decide(paced(33, 3.0f)), FrameStatus::Published);
  // B's line: 33 - 2.75 k (A's 16 is 3.25 off it); the path's line at pace 3: 33 - 3 k, A's 16 is 2 off (k = 5):
  // within the held frame's tolerance of 2, not within run_start_tolerance. Only B's own frames join.
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{1, 2, 3, 4}));
}

// A published run broken by a dip of uniqueness resumes where a frame's match lies on its line, extended, at
// continue_uniqueness (run_resume_frames); never off the line, never after run_resume_frames frames, never with 0.
TEST(LoopDecision, ABrokenRunResumesOnItsLineWithinRunResumeFrames)
{
  Config c = decisionConfig();  // min_uniqueness 0.1, consistent_frames 3, consistency_tolerance 1
  c.continue_uniqueness = 0.05;
  c.run_start_tolerance = 1;
  c.run_resume_frames = 4;  // a frame at most 4 frames after the line's last published one
  const auto publishRun = [](LoopDecision& decision)
  {
    for (uint64_t m : {10, 11})
      EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
    EXPECT_EQ(decision.decide(candidate(12, 0.3f)), FrameStatus::Published);
  };
  LoopDecision decision(c);
  publishRun(decision);
  EXPECT_EQ(decision.decide(candidate(3, 0.01f)), FrameStatus::NotUnique);   // the dip: a look-alike place
  EXPECT_EQ(decision.decide(candidate(14, 0.02f)), FrameStatus::NotUnique);  // on the line, below continue_uniqueness
  EXPECT_EQ(decision.decide(candidate(15, 0.07f)), FrameStatus::Published);  // on the line (12 + 3), unique enough
  // 14 joins it; past the dip, the run's own frames 12, 11, 10 (the confirmation takes those it still holds).
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{1, 3, 4, 5}));
  EXPECT_EQ(decision.decide(candidate(16, 0.07f)), FrameStatus::Published);  // and the run goes on

  // Off the line (the line says 15, 17 is 2 off with tolerance 1): nothing resumes; a run must start again.
  decision.reset();
  publishRun(decision);
  decision.decide(candidate(3, 0.01f));
  decision.decide(candidate(14, 0.01f));
  EXPECT_EQ(decision.decide(candidate(17, 0.07f)), FrameStatus::NotUnique);

  // The 4th frame after the line's last published one may resume it; the 5th may not.
  decision.reset();
  publishRun(decision);
  for (uint64_t m : {3, 4, 5})
    decision.decide(candidate(m, 0.01f));
  EXPECT_EQ(decision.decide(candidate(16, 0.07f)), FrameStatus::Published);
  decision.reset();
  publishRun(decision);
  for (uint64_t m : {3, 4, 5, 6})
    decision.decide(candidate(m, 0.01f));
  EXPECT_EQ(decision.decide(candidate(17, 0.07f)), FrameStatus::NotUnique);

  c.run_resume_frames = 0;  // off
  LoopDecision off(c);
  publishRun(off);
  off.decide(candidate(3, 0.01f));
  EXPECT_EQ(off.decide(candidate(14, 0.07f)), FrameStatus::NotUnique);
}

TEST(LoopDecision, ScoreIsTheUniquenessAndZeroWhileTooEarly)
{
  const LoopDecision decision(decisionConfig());
  EXPECT_FLOAT_EQ(decision.score(candidate(1, 0.25f)), 0.25f);
  EXPECT_FLOAT_EQ(decision.score(candidate(1, 1.0f, 9)), 0.0f);  // a lone candidate: no rival, no meaning
  Detection alone = candidate(1, 1.0f);
  alone.top.resize(1);  // enough places, but none outside the uniqueness window: no rival either
  EXPECT_FLOAT_EQ(decision.score(alone), 0.0f);
  EXPECT_FLOAT_EQ(decision.score(Detection()), 0.0f);
}

namespace
{
/// Random streams against a naive reference that re-derives each decision from the whole list of earlier
/// detections. With `geometry`, each frame also gets a random verification answer: a frame passes when it is
/// unique enough, or when it is at least verified_min_uniqueness unique and verified.
void expectNaiveReference(bool geometry)
{
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial)
  {
    Config c = decisionConfig();
    c.consistent_frames = 1 + trial % 10;
    c.consistency_tolerance = trial % 3;
    c.verified_min_uniqueness = geometry ? 0.05 : -1.0;
    c.run_start_tolerance = trial % 3 - 1;
    LoopDecision decision(c);
    std::vector<Detection> seen;
    std::vector<bool> verified;
    std::vector<FrameStatus> statuses;  // what each earlier frame was decided
    uint64_t match = 100;
    for (int t = 0; t < 200; ++t)
    {
      const int kind = std::uniform_int_distribution<int>(0, 9)(rng);
      match =
          kind < 6 ? match + 1 : (kind < 8 ? match + std::uniform_int_distribution<int>(0, 4)(rng) : 300 - match % 50);
      const float u = std::uniform_real_distribution<float>(0.0f, 0.3f)(rng);
      seen.push_back(candidate(match, u));
      // Most frames' paths at the first pass's pace, some a step of the grid faster (the path's line, below).
      seen.back().best.pace = std::uniform_int_distribution<int>(0, 3)(rng) == 0 ? 1.15f : 1.0f;
      verified.push_back(std::bernoulli_distribution(0.5)(rng));
      // Naive: the run is the longest suffix of passing frames where every step and the whole span advance
      // one place per frame within the tolerance.
      const auto passes = [&](size_t k)
      {
        const float uniqueness = seen[k].uniqueness;
        return uniqueness >= c.min_uniqueness || (geometry && uniqueness >= c.verified_min_uniqueness && verified[k]);
      };
      FrameStatus expected = FrameStatus::NotUnique;
      std::vector<size_t> joined;  // frames back from this one
      if (passes(seen.size() - 1))
      {
        // Runs restart where a step or the span from the run's start breaks: replay from the start.
        int run = 0;
        uint64_t start = 0, previous = 0;
        std::vector<double> matches;  // the run's
        for (size_t k = 0; k < seen.size(); ++k)
        {
          if (!passes(k))
          {
            run = 0;
            matches.clear();
            continue;
          }
          const long id = static_cast<long>(seen[k].best.id);
          const bool agrees = run > 0 && std::labs(id - static_cast<long>(previous) - 1) <= c.consistency_tolerance &&
                              std::labs(id - static_cast<long>(start) - run) <= c.consistency_tolerance;
          if (agrees)
            ++run;
          else
          {
            run = 1;
            start = seen[k].best.id;
            matches.clear();
          }
          previous = seen[k].best.id;
          matches.push_back(static_cast<double>(previous));
        }
        expected = run >= c.consistent_frames ? FrameStatus::Published : FrameStatus::Inconsistent;
        // The frame that publishes the run (at this pace, its consistent_frames-th): the frames before it (every
        // frame here has candidates; a published one may still be held by the confirmation) within
        // run_start_tolerance of the line through the run's first and last match, extended back, join it, counted
        // back to the first that is not, passing over at most kMaxSkipped NotUnique ones in a row (at most kMaxJoined
        // back). A Published one right after a joined one (or right before this frame) may be consistency_tolerance
        // off the line.
        if (run == c.consistent_frames && c.run_start_tolerance >= 0 && run > 1)
        {
          const double slope = (matches.back() - matches.front()) / static_cast<double>(matches.size() - 1);
          // Or on the line of this frame's path pace, for frames whose path held it, when the run's line agrees
          // with it within LoopDecision::kPathAgrees; once a frame is on that line alone, only that line.
          const double pace = seen.back().best.pace;
          const bool path_agrees = std::fabs(slope - pace) <= LoopDecision::kPathAgrees * pace;
          bool path_only = false;
          size_t off_line = 0;
          for (size_t back = 1; back <= std::min(statuses.size(), LoopDecision::kMaxJoined); ++back)
          {
            const double line = matches.back() - slope * static_cast<double>(back);
            const bool held_run_frame = statuses[statuses.size() - back] == FrameStatus::Published &&
                                        (joined.empty() ? back == 1 : joined.back() == back - 1);
            const int tolerance =
                held_run_frame ? std::max(c.run_start_tolerance, c.consistency_tolerance) : c.run_start_tolerance;
            const Detection& earlier = seen[seen.size() - 1 - back];
            // (but a frame that passed the gates itself, Inconsistent, is judged on the run's line still)
            const bool run_line_holds = !path_only || statuses[statuses.size() - back] == FrameStatus::Inconsistent;
            const bool on_run_line = run_line_holds && std::fabs(double(earlier.best.id) - line) <= tolerance;
            const bool on_path_line =
                path_agrees && std::fabs(earlier.best.pace - pace) <= LoopDecision::kSamePace * pace &&
                std::fabs(double(earlier.best.id) - (matches.back() - pace * static_cast<double>(back))) <=
                    c.run_start_tolerance;
            if (on_run_line || on_path_line)
            {
              path_only = path_only || !on_run_line;
              joined.push_back(back);
              off_line = 0;
            }
            else if (statuses[statuses.size() - back] != FrameStatus::NotUnique ||
                     ++off_line > LoopDecision::kMaxSkipped)
              break;
          }
        }
      }
      const bool answer = verified.back();
      const LoopDecision::GeometryCheck check = [answer] { return answer; };
      ASSERT_EQ(decision.decide(seen.back(), geometry ? check : LoopDecision::GeometryCheck()), expected)
          << "trial " << trial << " frame " << t;
      ASSERT_EQ(decision.joinedBefore(), joined) << "trial " << trial << " frame " << t;
      ASSERT_TRUE(decision.mayJoinLater() == (expected != FrameStatus::Published && c.run_start_tolerance >= 0))
          << "trial " << trial << " frame " << t;
      statuses.push_back(expected);
    }
  }
}
}  // namespace

TEST(LoopDecision, EqualsANaiveReferenceOnRandomStreams)
{
  expectNaiveReference(false);
}

TEST(LoopDecision, WithGeometryEqualsANaiveReferenceOnRandomStreams)
{
  expectNaiveReference(true);
}

TEST(LoopDecision, APublishedRunContinuesThroughLessUniqueFramesOnItsLineOnly)
{
  Config c = decisionConfig();  // min_uniqueness 0.1, 3 consistent frames, tolerance 1
  c.continue_uniqueness = 0.03;
  LoopDecision decision(c);
  // A run may not START below min_uniqueness: 0.05 never publishes by itself.
  EXPECT_EQ(decision.decide(candidate(10, 0.05f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(11, 0.05f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(20, 0.2f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(21, 0.2f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(22, 0.2f)), FrameStatus::Published);
  // Published: a frame on the run's line goes on at continue_uniqueness.
  EXPECT_EQ(decision.decide(candidate(23, 0.05f)), FrameStatus::Published);
  EXPECT_EQ(decision.decide(candidate(24, 0.035f)), FrameStatus::Published);
  // Below continue_uniqueness the run ends, and a new one needs min_uniqueness again.
  EXPECT_EQ(decision.decide(candidate(25, 0.02f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(26, 0.05f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(40, 0.2f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(41, 0.2f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(42, 0.2f)), FrameStatus::Published);
  // Off the line (a look-alike place elsewhere) it ends too, even when nearly unique enough.
  EXPECT_EQ(decision.decide(candidate(90, 0.09f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(91, 0.09f)), FrameStatus::NotUnique);
  // A sequence growing worse than the run's last unique frame (by more than 5 %) is a camera leaving the
  // route: the run ends.
  for (uint64_t m = 60; m < 63; ++m)
    EXPECT_NE(decision.decide(candidate(m, 0.2f, 100, 0.2f)), FrameStatus::NotUnique);
  EXPECT_EQ(decision.decide(candidate(63, 0.05f, 100, 0.205f)), FrameStatus::Published);
  EXPECT_EQ(decision.decide(candidate(64, 0.05f, 100, 0.25f)), FrameStatus::NotUnique);
  // A distance gate still holds inside a run.
  c.threshold = 0.3;
  decision.setOptions(DecisionOptions::from(c));
  for (uint64_t m = 50; m < 53; ++m)
    decision.decide(candidate(m, 0.2f));
  EXPECT_EQ(decision.decide(candidate(53, 0.05f, 100, 0.205f)), FrameStatus::Published);
  EXPECT_EQ(decision.decide(candidate(54, 0.05f, 100, 0.35f)), FrameStatus::AboveThreshold);
}

TEST(LoopDecision, ContinuationIsOffAtOrAboveMinUniqueness)
{
  Config c = decisionConfig();
  c.continue_uniqueness = c.min_uniqueness;
  LoopDecision decision(c);
  for (uint64_t m = 20; m < 23; ++m)
    decision.decide(candidate(m, 0.2f));
  EXPECT_EQ(decision.decide(candidate(23, 0.09f)), FrameStatus::NotUnique);
}

namespace
{
/// A geometry check that answers `accept` and counts how often it was asked.
struct CountingGeometry
{
  bool accept = true;
  int asked = 0;
  LoopDecision::GeometryCheck check()
  {
    return [this]
    {
      ++asked;
      return accept;
    };
  }
};

Config verifiedConfig(double verified_min_uniqueness)
{
  Config c = decisionConfig();
  c.verified_min_uniqueness = verified_min_uniqueness;
  return c;
}
}  // namespace

TEST(LoopDecision, GeometryStandsInForUniquenessButTheRunMustStillBeConsistent)
{
  LoopDecision decision(verifiedConfig(0.02));
  CountingGeometry geometry;
  // Below min_uniqueness (0.1): confirmed by geometry, each frame joins the run; published once consistent.
  EXPECT_EQ(decision.decide(candidate(40, 0.05f), geometry.check()), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(41, 0.05f), geometry.check()), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(42, 0.05f), geometry.check()), FrameStatus::Published);
  EXPECT_EQ(geometry.asked, 3);
  // A frame that passes the gates itself is not sent to verification by the decision.
  EXPECT_EQ(decision.decide(candidate(43, 0.3f), geometry.check()), FrameStatus::Published);
  EXPECT_EQ(geometry.asked, 3);
  // Geometry does not make an inconsistent run consistent: a jump starts a new run, verified or not.
  EXPECT_EQ(decision.decide(candidate(90, 0.05f), geometry.check()), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(candidate(91, 0.3f), geometry.check()), FrameStatus::Inconsistent);
}

TEST(LoopDecision, GeometryIsAskedOnlyForFramesThatLackAppearanceEvidence)
{
  LoopDecision decision(verifiedConfig(0.02));
  CountingGeometry geometry;
  EXPECT_EQ(decision.decide(candidate(40, 0.01f), geometry.check()), FrameStatus::NotUnique);  // below 0.02
  EXPECT_EQ(decision.decide(Detection(), geometry.check()), FrameStatus::TooEarly);           // no candidate
  EXPECT_EQ(decision.decide(candidate(40, 0.5f, 0), geometry.check()), FrameStatus::TooEarly);  // a short map's early place
  EXPECT_EQ(geometry.asked, 0);
  // Fewer than min_candidates places (10): geometry stands in for the minimum too.
  EXPECT_EQ(decision.decide(candidate(40, 0.5f, 5), geometry.check()), FrameStatus::Inconsistent);
  EXPECT_EQ(geometry.asked, 1);
  // Never for the distance gate.
  Config thresholded = verifiedConfig(0.02);
  thresholded.threshold = 0.1;
  LoopDecision gated(thresholded);
  EXPECT_EQ(gated.decide(candidate(5, 0.05f, 100, 0.2f), geometry.check()), FrameStatus::AboveThreshold);
  EXPECT_EQ(geometry.asked, 1);
  // Rejected by geometry: the frame is turned down as before, and the run ends.
  LoopDecision rejected(verifiedConfig(0.02));
  geometry.accept = false;
  EXPECT_EQ(rejected.decide(candidate(40, 0.05f), geometry.check()), FrameStatus::NotUnique);
  EXPECT_EQ(geometry.asked, 2);
}

TEST(LoopDecision, GeometryIsNeverAskedWhenOffOrAbsent)
{
  LoopDecision off(verifiedConfig(-1.0));
  CountingGeometry geometry;
  for (uint64_t i = 0; i < 5; ++i)
    EXPECT_EQ(off.decide(candidate(40 + i, 0.05f), geometry.check()), FrameStatus::NotUnique);
  EXPECT_EQ(geometry.asked, 0);
  LoopDecision without(verifiedConfig(0.0));
  for (uint64_t i = 0; i < 5; ++i)
    EXPECT_EQ(without.decide(candidate(40 + i, 0.05f)), FrameStatus::NotUnique);
}

TEST(LoopDecision, VerifiedMinUniquenessIsOffOrInTheUnitRange)
{
  for (double good : {-1.0, 0.0, 0.05, 1.0})
  {
    Config c;
    c.verified_min_uniqueness = good;
    EXPECT_TRUE(c.problems().empty()) << good;
  }
  for (double bad : {-0.5, -2.0, 1.5, std::nan("")})
  {
    Config c;
    c.verified_min_uniqueness = bad;
    EXPECT_FALSE(c.problems().empty()) << bad;
  }
}

namespace
{
Config reliefConfig()
{
  Config c = decisionConfig();
  c.max_pace = 3;
  c.min_relief = 1.0;
  return c;
}

Detection withRelief(uint64_t match, float relief, float uniqueness = 0.3f)
{
  Detection d = candidate(match, uniqueness);
  d.relief = relief;
  return d;
}
}  // namespace

TEST(LoopDecision, FeaturelessWhereTheMedianReliefOfTheLastFramesIsBelowMinRelief)
{
  // The median of the last kReliefFrames (5) reliefs: one low frame (a passing train) changes nothing, three of
  // five do; a run that went on along its line through them is published again at the first frame after.
  LoopDecision decision(reliefConfig());
  const std::vector<float> reliefs = {3, 3, 3, 0.3f, 3, 3, 0.3f, 0.3f, 0.3f, 3, 3, 3};
  const auto P = FrameStatus::Published, I = FrameStatus::Inconsistent, F = FrameStatus::Featureless;
  const std::vector<FrameStatus> expected = {I, I, P, P, P, P, P, F, F, F, F, P};
  for (size_t i = 0; i < reliefs.size(); ++i)
    EXPECT_EQ(decision.decide(withRelief(10 + i, reliefs[i])), expected[i]) << i;
  // NaN (unknown: the paper's matcher, a merged answer) is left out; min_relief 0 is off.
  LoopDecision unknown(reliefConfig());
  for (uint64_t i = 0; i < 4; ++i)
    EXPECT_NE(unknown.decide(withRelief(10 + i, std::nanf(""))), F) << i;
  Config off = reliefConfig();
  off.min_relief = 0.0;
  LoopDecision gateless(off);
  for (uint64_t i = 0; i < 4; ++i)
    EXPECT_NE(gateless.decide(withRelief(10 + i, 0.0f)), F) << i;
}

TEST(LoopDecision, ARunThatJumpsAmongLookAlikePlacesEndsThere)
{
  // During the stretch (frames 6 to 9 featureless) the match jumps 80 places: the run ends, and after the stretch
  // consistent_frames (3) frames must agree again.
  LoopDecision decision(reliefConfig());
  const std::vector<float> reliefs = {3, 3, 3, 3, 0.3f, 0.3f, 0.3f, 0.3f, 3, 3, 3, 3, 3};
  const auto P = FrameStatus::Published, I = FrameStatus::Inconsistent, F = FrameStatus::Featureless;
  const std::vector<FrameStatus> expected = {I, I, P, P, P, P, F, F, F, F, I, I, P};
  for (size_t i = 0; i < reliefs.size(); ++i)
    EXPECT_EQ(decision.decide(withRelief(i == 6 ? 90 : 10 + i, reliefs[i])), expected[i]) << i;
}

TEST(LoopDecision, TheReachBackPassesOverFeaturelessFrames)
{
  // A run's first frames before a featureless one join it once it is consistent: the featureless frame is neither
  // joined (it is no loop closure) nor the end of the frames that may be.
  Config c = reliefConfig();
  c.run_start_tolerance = 1;
  LoopDecision decision(c);
  EXPECT_EQ(decision.decide(withRelief(10, 3.0f)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(withRelief(11, 0.3f)), FrameStatus::Inconsistent);  // median of 3, 0.3: 3
  EXPECT_EQ(decision.decide(withRelief(12, 0.3f)), FrameStatus::Featureless);   // median of 3, 0.3, 0.3: 0.3
  EXPECT_TRUE(decision.joinedBefore().empty());
  EXPECT_EQ(decision.decide(withRelief(13, 3.0f)), FrameStatus::Published);  // the run coasted: 4 frames
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{2, 3}));
}

TEST(LoopDecision, ARunThatComesOutOfAStretchItCoastedThroughTakesTheStretchsFramesOnItsLine)
{
  // A published run (frames 2-4) coasts along its line through a featureless stretch (frames 5-8) and comes out of it
  // passing the gates (frame 9): the stretch's frames join it, and the frames before them (published, held while
  // the stretch left them unconfirmed). A featureless frame of a run not yet published never joins (above).
  Config c = reliefConfig();
  c.run_start_tolerance = 1;
  LoopDecision decision(c);
  const std::vector<float> reliefs = {3, 3, 3, 0.3f, 0.3f, 0.3f, 0.3f, 3, 3, 3};
  std::vector<FrameStatus> statuses;
  for (size_t i = 0; i < reliefs.size(); ++i)
  {
    statuses.push_back(decision.decide(withRelief(10 + i, reliefs[i])));
    if (i < 9)
      EXPECT_TRUE(decision.joinedBefore().empty() || i == 2) << i;
  }
  const auto P = FrameStatus::Published, I = FrameStatus::Inconsistent, F = FrameStatus::Featureless;
  EXPECT_EQ(statuses, (std::vector<FrameStatus>{I, I, P, P, P, F, F, F, F, P}));
  EXPECT_EQ(decision.joinedBefore(), (std::vector<size_t>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
}

TEST(LoopDecision, ACoastedRunPublishesAgainOnlyFromAFrameThatPassesTheGatesItself)
{
  // A published run coasts along its line through a featureless stretch (frames 5 to 8). After it, frames 9 and 10
  // are on the line but below min_uniqueness (0.1), at continue_uniqueness (0.05): a run that had not coasted goes on
  // through them, one that coasted neither goes on nor resumes (its sequence still holds the stretch and may lag the
  // revisit); frame 11 passes the gates itself and resumes the run on its line.
  Config c = reliefConfig();
  c.continue_uniqueness = 0.05;
  c.run_resume_frames = 30;
  const std::vector<float> uniqueness = {0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.3f, 0.07f, 0.07f, 0.3f};
  const auto run = [&](const std::vector<float>& reliefs)
  {
    LoopDecision decision(c);
    std::vector<FrameStatus> statuses;
    for (size_t i = 0; i < reliefs.size(); ++i)
      statuses.push_back(decision.decide(withRelief(10 + i, reliefs[i], uniqueness[i])));
    return statuses;
  };
  const auto P = FrameStatus::Published, I = FrameStatus::Inconsistent, F = FrameStatus::Featureless,
             N = FrameStatus::NotUnique;
  EXPECT_EQ(run({3, 3, 3, 0.3f, 0.3f, 0.3f, 0.3f, 3, 3, 3, 3, 3}),
            (std::vector<FrameStatus>{I, I, P, P, P, F, F, F, F, N, N, P}));
  // Without the stretch the same frames go on with the run at continue_uniqueness.
  EXPECT_EQ(run({3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3}), (std::vector<FrameStatus>{I, I, P, P, P, P, P, P, P, P, P, P}));
}

TEST(LoopDecision, APublishedRunCatchesUpWhenAFasterPathHoldsForTwoFramesAFewPlacesAhead)
{
  // A path of a faster pace takes over from one that lagged the revisit: the match jumps ahead of the run's line, and
  // the next frame goes on along the faster path. Then the run goes on, on a line at the new path's pace; a jump for
  // one frame, one further than kCatchUpPlaces, one at the run's own pace, or at one pace, breaks it.
  Config c = decisionConfig();  // min_uniqueness 0.1, consistency_tolerance 1
  c.consistent_frames = 5;      // (at 3 the last frames' own line would take the faster path at once)
  c.max_pace = 3;
  c.run_resume_frames = 30;  // as config/default.yaml: a broken run resumes on its line (rule (h))
  const auto publishRun = [](LoopDecision& decision)
  {
    for (uint64_t m : {10, 11, 12, 13})
      EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
    for (uint64_t m : {14, 15})
      EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Published);
  };
  LoopDecision decision(c);
  publishRun(decision);
  EXPECT_FALSE(decision.keepsSearching());
  EXPECT_EQ(decision.decide(paced(19, 1.5f)), FrameStatus::Inconsistent);  // the line says 16: 3 ahead
  EXPECT_FALSE(decision.keepsSearching());
  EXPECT_EQ(decision.decide(paced(21, 1.5f)), FrameStatus::Published);  // on the faster path's line (19 + 1.5)
  EXPECT_TRUE(decision.keepsSearching());                                   // the matcher goes on searching
  for (uint64_t m : {22, 24, 25, 27})
  {
    EXPECT_EQ(decision.decide(paced(m, 1.5f)), FrameStatus::Published) << m;
    EXPECT_TRUE(decision.keepsSearching()) << m;
  }
  EXPECT_EQ(decision.decide(paced(28, 1.5f)), FrameStatus::Published);
  EXPECT_FALSE(decision.keepsSearching());  // consistent_frames frames after it

  const auto jumpThen = [&](uint64_t jump, float jump_pace, uint64_t next, float next_pace)
  {
    LoopDecision d(c);
    publishRun(d);
    EXPECT_NE(d.decide(paced(jump, jump_pace)), FrameStatus::Published) << jump;
    const FrameStatus after = d.decide(paced(next, next_pace));
    EXPECT_FALSE(d.keepsSearching()) << jump << " then " << next;
    return after;
  };
  // One frame on a faster path, then back on the run's line: the run resumes on the line it had.
  EXPECT_EQ(jumpThen(19, 1.5f, 17, 1.0f), FrameStatus::Published);
  EXPECT_EQ(jumpThen(19, 1.5f, 23, 1.5f), FrameStatus::Inconsistent);  // the next frame off the faster path's line
  EXPECT_EQ(jumpThen(22, 1.5f, 24, 1.5f), FrameStatus::Inconsistent);  // 6 ahead: not a path catching up
  EXPECT_EQ(jumpThen(19, 1.0f, 20, 1.0f), FrameStatus::Inconsistent);  // at the run's own pace: a place further on

  c.max_pace = 1;  // one pace: nothing faster can take over
  LoopDecision one_pace(c);
  publishRun(one_pace);
  EXPECT_NE(one_pace.decide(paced(19, 1.0f)), FrameStatus::Published);
  EXPECT_NE(one_pace.decide(paced(20, 1.0f)), FrameStatus::Published);
  EXPECT_FALSE(one_pace.keepsSearching());
}

// A short map's first place starts no run (Detection::best_at_session_start): a path ending there has no past, and a
// short route's end "matches" its start.
TEST(LoopDecision, AShortMapsFirstPlaceStartsNoRun)
{
  const auto atStart = [](uint64_t match)
  {
    Detection d = candidate(match, 0.3f);
    d.short_map = true;
    d.best_at_session_start = match == 0;
    return d;
  };
  LoopDecision decision(decisionConfig());  // consistent_frames 3
  EXPECT_EQ(decision.decide(atStart(0)), FrameStatus::Excluded);
  EXPECT_EQ(decision.decide(atStart(0)), FrameStatus::Excluded);
  EXPECT_EQ(decision.decide(atStart(1)), FrameStatus::Inconsistent);  // the next place starts the run
  EXPECT_EQ(decision.decide(atStart(2)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(atStart(3)), FrameStatus::Published);

  // Unflagged (a long map: its first place is as old as any), place 0 starts a run as any other.
  LoopDecision long_map(decisionConfig());
  EXPECT_EQ(long_map.decide(candidate(0, 0.3f)), FrameStatus::Inconsistent);
}

// A short map's frames too early for a decision (fewer than min_candidates places, the revisit of a route shorter than
// the exclusion window beginning) have a best match all the same (MapMatcher::earlyPicks): a run on its line reaches
// back to them as to frames not unique (up to kMaxSkipped in a row off its line passed over); not one matched at the
// map's first place.
// A long map's too early frames (the stream's first, before any place may be compared) join nothing.
TEST(LoopDecision, AShortMapsFramesTooEarlyJoinTheRunOnTheirLine)
{
  const auto early = [](uint64_t match, bool short_map)
  {
    Detection d = candidate(match, 0.0f, 0);  // no candidate counted: too early
    d.short_map = short_map;
    return d;
  };
  for (const bool short_map : {true, false})
  {
    LoopDecision decision(reachBackConfig(3, 1));
    for (uint64_t m : {1, 20, 21, 22, 4, 5, 12, 7})
    {
      EXPECT_EQ(decision.decide(early(m, short_map)), FrameStatus::TooEarly);
      EXPECT_EQ(decision.mayJoinLater(), short_map);
    }
    for (uint64_t m : {8, 9})
      EXPECT_EQ(decision.decide(candidate(m, 0.3f)), FrameStatus::Inconsistent);
    EXPECT_EQ(decision.decide(candidate(10, 0.3f)), FrameStatus::Published);
    // 9, 8, 7, then 12 passed over (off the line, as a frame not unique may be), 5, 4; three off in a row end it.
    const std::vector<size_t> expected =
        short_map ? std::vector<size_t>{1, 2, 3, 5, 6} : std::vector<size_t>{1, 2};
    EXPECT_EQ(decision.joinedBefore(), expected) << (short_map ? "short map" : "long map");
  }
  // Not at the map's first place (the first pass's last frames match it; it starts no run either).
  LoopDecision decision(reachBackConfig(3, 1));
  Detection first_place = early(0, true);
  first_place.best_at_session_start = true;
  EXPECT_EQ(decision.decide(first_place), FrameStatus::TooEarly);
  EXPECT_FALSE(decision.mayJoinLater());
}

// A short map's run first published with no published line before it keeps the matcher searching (its pace prior on)
// for consistent_frames frames: a revisit's first frames fit any pace. A run on a long map, or one that restarts within
// run_resume_frames of a published line, follows its path's pace at once.
TEST(LoopDecision, AShortMapsFirstRunKeepsTheMatcherSearchingForConsistentFrames)
{
  Config c = decisionConfig();  // consistent_frames 3
  c.run_resume_frames = 30;
  const auto shortMap = [](uint64_t match, float uniqueness = 0.3f)
  {
    Detection d = candidate(match, uniqueness);
    d.short_map = true;
    return d;
  };
  LoopDecision decision(c);
  for (uint64_t m : {10, 11})
    EXPECT_EQ(decision.decide(shortMap(m)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(shortMap(12)), FrameStatus::Published);
  EXPECT_TRUE(decision.keepsSearching());
  EXPECT_EQ(decision.decide(shortMap(13)), FrameStatus::Published);
  EXPECT_TRUE(decision.keepsSearching());
  EXPECT_EQ(decision.decide(shortMap(14)), FrameStatus::Published);
  EXPECT_TRUE(decision.keepsSearching());
  EXPECT_EQ(decision.decide(shortMap(15)), FrameStatus::Published);
  EXPECT_FALSE(decision.keepsSearching());  // consistent_frames frames after the run's first published one

  // The run breaks and starts again within run_resume_frames of its line: no fresh start.
  EXPECT_EQ(decision.decide(shortMap(40, 0.0f)), FrameStatus::NotUnique);
  for (uint64_t m : {41, 42})
    EXPECT_EQ(decision.decide(shortMap(m)), FrameStatus::Inconsistent);
  EXPECT_EQ(decision.decide(shortMap(43)), FrameStatus::Published);
  EXPECT_FALSE(decision.keepsSearching());

  LoopDecision long_map(c);
  for (uint64_t m : {10, 11, 12})
    long_map.decide(candidate(m, 0.3f));
  EXPECT_FALSE(long_map.keepsSearching());
}
