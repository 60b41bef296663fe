// LoopConfirmation: a loop closure goes out once confirm_frames more stored frames went on with its run.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "openable/detection/loop_confirmation.h"
#include "openable/detection/loop_csv.h"
#include "openable/detection/online_detector.h"
#include "openable/error.h"
#include "test_util.h"

namespace openable
{
namespace
{
/// One input of the confirmation: a stored frame that passed the decision or not, or a standstill repeat.
enum class Step
{
  Passed,
  Failed,
  Repeat
};

/// Drives a LoopConfirmation as OnlineDetector does and returns every outcome in order, as process() gave them.
std::vector<FrameOutcome> drive(const std::vector<Step>& steps, int frames)
{
  LoopConfirmation confirmation(frames);
  std::vector<FrameOutcome> outcomes;
  FrameOutcome last;
  for (size_t i = 0; i < steps.size(); ++i)
  {
    FrameOutcome o;
    o.frame = i;
    if (steps[i] == Step::Repeat)
    {
      o = last;
      o.frame = i;
      o.stored = false;
      if (o.status != FrameStatus::Published && o.status != FrameStatus::Pending)
        o.status = FrameStatus::Standstill;
      confirmation.repeated(o);
      outcomes.push_back(o);
      continue;
    }
    o.stored = true;
    o.query.id = i;
    o.status = steps[i] == Step::Passed ? FrameStatus::Published : FrameStatus::NotUnique;
    std::vector<FrameOutcome> confirmed = confirmation.stored(o);
    last = o;
    o.confirmed = std::move(confirmed);
    outcomes.push_back(o);
  }
  return outcomes;
}

std::vector<FrameStatus> statuses(const std::vector<FrameOutcome>& outcomes)
{
  std::vector<FrameStatus> out;
  for (const FrameOutcome& o : outcomes)
    out.push_back(o.status);
  return out;
}

/// The rule written plainly: a stored frame that passed is published iff the next `frames` stored frames all
/// passed; a repeat has its stored frame's fate; a stored frame that failed keeps its status, and its repeats
/// are standstills.
std::vector<FrameStatus> reference(const std::vector<Step>& steps, int frames)
{
  std::vector<FrameStatus> out(steps.size(), FrameStatus::Standstill);
  FrameStatus fate = FrameStatus::Standstill;
  for (size_t i = 0; i < steps.size(); ++i)
  {
    if (steps[i] == Step::Repeat)
    {
      out[i] = fate;
      continue;
    }
    if (steps[i] == Step::Failed)
    {
      out[i] = FrameStatus::NotUnique;
      fate = FrameStatus::Standstill;
      continue;
    }
    int later = 0;
    bool confirmed = true;
    for (size_t j = i + 1; j < steps.size() && later < frames; ++j)
    {
      if (steps[j] == Step::Repeat)
        continue;
      ++later;
      confirmed = confirmed && steps[j] == Step::Passed;
    }
    fate = out[i] = confirmed && later == frames ? FrameStatus::Published : FrameStatus::Unconfirmed;
  }
  return out;
}
}  // namespace

TEST(LoopConfirmation, PublishesAFrameOnceThreeMoreFramesGoOnWithItsRun)
{
  const std::vector<Step> steps = {Step::Passed, Step::Passed, Step::Passed, Step::Passed, Step::Passed, Step::Failed};
  const std::vector<FrameOutcome> outcomes = drive(steps, 3);
  // As the frames come: every passing frame waits; frame 3 confirms frame 0, frame 4 frame 1; frame 5 ends the run.
  for (size_t i = 0; i < 5; ++i)
    EXPECT_EQ(outcomes[i].status, FrameStatus::Pending) << i;
  ASSERT_EQ(outcomes[3].confirmed.size(), 1u);
  EXPECT_EQ(outcomes[3].confirmed[0].frame, 0u);
  EXPECT_EQ(outcomes[3].confirmed[0].status, FrameStatus::Published);
  ASSERT_EQ(outcomes[4].confirmed.size(), 1u);
  EXPECT_EQ(outcomes[4].confirmed[0].frame, 1u);
  EXPECT_TRUE(outcomes[5].confirmed.empty());
  EXPECT_EQ(statuses(settled(outcomes)),
            (std::vector<FrameStatus>{FrameStatus::Published, FrameStatus::Published, FrameStatus::Unconfirmed,
                                      FrameStatus::Unconfirmed, FrameStatus::Unconfirmed, FrameStatus::NotUnique}));
}

TEST(LoopConfirmation, CountsWhatARunThatEndedLeftUnconfirmed)
{
  LoopConfirmation confirmation(3);
  FrameOutcome passed, failed;
  for (int i = 0; i < 5; ++i)
  {
    passed.status = FrameStatus::Published;
    confirmation.stored(passed);
  }
  confirmation.repeated(passed);  // a standstill repeating the last (pending) frame
  EXPECT_EQ(confirmation.pending(), 4u);  // frames 2, 3, 4 and the repeat; 0 and 1 went out
  failed.status = FrameStatus::NotUnique;
  confirmation.stored(failed);
  EXPECT_EQ(confirmation.dropped(), 4u);
  EXPECT_EQ(confirmation.pending(), 0u);
}

TEST(LoopConfirmation, ZeroFramesPublishesAtOnce)
{
  const std::vector<Step> steps = {Step::Passed, Step::Failed, Step::Passed, Step::Repeat};
  const std::vector<FrameOutcome> outcomes = drive(steps, 0);
  EXPECT_EQ(statuses(outcomes), (std::vector<FrameStatus>{FrameStatus::Published, FrameStatus::NotUnique,
                                                          FrameStatus::Published, FrameStatus::Published}));
  for (const FrameOutcome& o : outcomes)
    EXPECT_TRUE(o.confirmed.empty());
}

TEST(LoopConfirmation, AStopsRepeatsWaitWithTheirFrameAndGoOutWithIt)
{
  const std::vector<Step> steps = {Step::Passed, Step::Repeat, Step::Repeat, Step::Passed, Step::Passed};
  const std::vector<FrameOutcome> outcomes = drive(steps, 2);
  ASSERT_EQ(outcomes[4].confirmed.size(), 3u);  // frame 0 and its two repeats, in order
  EXPECT_EQ(outcomes[4].confirmed[0].frame, 0u);
  EXPECT_EQ(outcomes[4].confirmed[1].frame, 1u);
  EXPECT_EQ(outcomes[4].confirmed[2].frame, 2u);
  EXPECT_FALSE(outcomes[4].confirmed[1].stored);
}

TEST(LoopConfirmation, EqualsThePlainRuleOnRandomStreams)
{
  std::mt19937 random(20261126);
  for (int trial = 0; trial < 400; ++trial)
  {
    const int frames = trial % 6;
    std::vector<Step> steps(1 + random() % 60);
    for (Step& s : steps)
    {
      const unsigned r = random() % 10;
      s = r < 6 ? Step::Passed : (r < 8 ? Step::Repeat : Step::Failed);
    }
    EXPECT_EQ(statuses(settled(drive(steps, frames))), reference(steps, frames)) << "trial " << trial;
  }
}

TEST(LoopConfirmation, RefusesANegativeCountAndBoundsAStopsRepeats)
{
  EXPECT_THROW(LoopConfirmation(-1), Error);
  LoopConfirmation confirmation(1);
  FrameOutcome o;
  o.status = FrameStatus::Published;
  confirmation.stored(o);
  for (size_t i = 0; i < 2 * LoopConfirmation::kMaxRepeats; ++i)
    confirmation.repeated(o);
  EXPECT_LE(confirmation.pending(), LoopConfirmation::kMaxRepeats + 1);
  confirmation.reset();
  EXPECT_EQ(confirmation.pending(), 0u);
}

TEST(LoopCsvWriter, AStatusGivenLaterIsWhatBothFilesSay)
{
  LoopCsvWriter writer(false);
  LoopCsvFrame f;
  f.query = 7;
  f.match = 2;
  f.has_candidates = true;
  f.status = FrameStatus::Pending;
  const size_t row = writer.add(f);
  f.query = 8;
  writer.add(f);
  writer.setStatus(row, FrameStatus::Published);
  writer.settlePending();
  EXPECT_EQ(writer.frames()[0].status, FrameStatus::Published);
  EXPECT_EQ(writer.frames()[1].status, FrameStatus::Unconfirmed);
  EXPECT_NE(writer.loopClosures().find("\n7,2,"), std::string::npos);
  EXPECT_EQ(writer.loopClosures().find("\n8,2,"), std::string::npos);
  EXPECT_NE(writer.decisions().find("8,2,0,0,unconfirmed,0,"), std::string::npos) << writer.decisions();
  EXPECT_THROW(writer.setStatus(5, FrameStatus::Published), Error);
}

// On real images: the loops published with confirm_frames 3 are loops published without it, each one arriving
// with the third stored frame after its own, and the wrong loops a changing pace makes are the ones it drops.
TEST(LoopConfirmation, OnRealImagesEveryConfirmedLoopWasALoopAndArrivesThreeFramesLate)
{
  std::vector<cv::Mat> frames;
  for (const char* traversal : {"day_right", "night_right"})
    for (int i = 0; i < 200; ++i)
      frames.push_back(openable_test::gardensPoint(traversal, i));
  Config at_once = Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/default.yaml");
  at_once.confirm_frames = 0;
  Config confirmed = at_once;
  confirmed.confirm_frames = 3;
  OnlineDetector a(at_once), b(confirmed);
  std::vector<FrameOutcome> now, later;
  size_t arrived = 0;
  for (size_t i = 0; i < frames.size(); ++i)
  {
    FrameInput input;
    input.image = frames[i];
    input.stamp = 1.0 + double(i);
    now.push_back(a.process(input));
    later.push_back(b.process(input));
    for (const FrameOutcome& c : later.back().confirmed)
    {
      EXPECT_EQ(later.back().query.id, c.query.id + 3) << "frame " << i;
      EXPECT_DOUBLE_EQ(c.query.stamp, 1.0 + double(c.frame));
      ++arrived;
    }
  }
  const std::vector<FrameOutcome> settled_later = settled(later);
  size_t published = 0;
  for (size_t i = 0; i < frames.size(); ++i)
  {
    if (!settled_later[i].published())
      continue;
    ++published;
    EXPECT_TRUE(now[i].published()) << i;
    EXPECT_EQ(settled_later[i].detection.best.id, now[i].detection.best.id) << i;
  }
  EXPECT_EQ(arrived, published);
  EXPECT_GT(published, 140u);  // measured: 151 of the 157 published at once (the last 3 frames of each run wait)
}

}  // namespace openable
