// The ROS-free helpers the nodelets use: throttling, the sync watchdog's decision, the camera-ring
// synchroniser, "did you mean" names, and loading a reference map.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/node_support/fix_history.h"
#include "openable/description/frame_describer.h"
#include "openable/map/reference_map.h"
#include "openable/node_support/ring_sync.h"
#include "openable/node_support/sequence_gaps.h"
#include "openable/node_support/sync_watch.h"
#include "openable/node_support/throttle.h"
#include "test_util.h"

using namespace openable;

TEST(Throttle, OncePerPeriodPerKey)
{
  Throttle t;
  EXPECT_TRUE(t.ready("a", 0.0, 5.0));
  EXPECT_FALSE(t.ready("a", 4.9, 5.0));
  EXPECT_TRUE(t.ready("b", 4.9, 5.0));  // keys do not silence each other
  EXPECT_TRUE(t.ready("a", 5.0, 5.0));
  EXPECT_FALSE(t.ready("a", 9.0, 5.0));
}

TEST(SyncWatch, WarnsWhenMessagesDoNotPairUpOnceUntilNewOnesArrive)
{
  SyncWatch w({"left", "right"}, "set approximate_sync", 5.0, 0.0);
  EXPECT_EQ(w.check(4.0), "");  // not quiet for long enough yet
  const std::string nothing = w.check(6.0);
  EXPECT_NE(nothing.find("Check that the topics are published"), std::string::npos) << nothing;
  w.noteInput(0);
  w.noteInput(0);
  w.noteInput(1);
  const std::string unpaired = w.check(12.0);
  EXPECT_NE(unpaired.find("'left' 2, 'right' 1"), std::string::npos) << unpaired;
  EXPECT_NE(unpaired.find("set approximate_sync"), std::string::npos) << unpaired;
  EXPECT_EQ(w.check(18.0), "") << "the stream stopped: no repeat without new messages";
  w.noteInput(1);
  EXPECT_NE(w.check(24.0), "");
}

TEST(SyncWatch, AStreamThatWorkedAndStoppedIsNotWarnedAbout)
{
  SyncWatch w({"left", "right"}, "advice", 1.0, 0.0);
  w.noteInput(0);
  w.noteInput(1);
  w.noteSet(0.5);
  EXPECT_EQ(w.check(10.0), "");
  EXPECT_EQ(w.sets(), 1u);
  SyncWatch off({"a"}, "advice", 0.0, 0.0);
  EXPECT_EQ(off.check(1e6), "");  // timeout 0: never
}

TEST(RingSync, CompletesASetWithinTheSkewAndDropsWhatIsBehindIt)
{
  using Ring = RingSync<double>;
  Ring ring(3, 4, 0.01, [](const double& stamp) { return stamp; });
  Ring::Set set;
  EXPECT_FALSE(ring.add(0, 1.000, set));
  EXPECT_FALSE(ring.add(1, 1.005, set));
  EXPECT_FALSE(ring.add(0, 2.000, set));
  ASSERT_TRUE(ring.add(2, 0.995, set));
  EXPECT_EQ(set, (Ring::Set{1.000, 1.005, 0.995}));
  EXPECT_FALSE(ring.add(1, 2.5, set));  // 2.0 waits; 2.5 is too far from it
  EXPECT_FALSE(ring.add(2, 2.0, set));
  ASSERT_TRUE(ring.add(1, 2.0, set));
  EXPECT_EQ(set, (Ring::Set{2.0, 2.0, 2.0}));
  for (int i = 0; i < 6; ++i)
    ring.add(0, 10.0 + i, set);
  EXPECT_EQ(ring.dropped(), 2u);  // queue of 4
}

TEST(RingSync, EqualsANaiveSearchOnRandomArrivals)
{
  // Property: whenever a set completes, every member lies within max_skew of the newest arrival and no
  // input's member is older than one already used.
  std::mt19937 rng(3);
  RingSync<double> ring(4, 8, 0.02, [](const double& s) { return s; });
  std::vector<double> last_used(4, -1.0);
  RingSync<double>::Set set;
  for (int i = 0; i < 2000; ++i)
  {
    const size_t input = std::uniform_int_distribution<size_t>(0, 3)(rng);
    const double stamp = 0.1 * (i / 4) + std::uniform_real_distribution<double>(-0.015, 0.015)(rng);
    if (!ring.add(input, stamp, set))
      continue;
    for (size_t c = 0; c < 4; ++c)
    {
      EXPECT_LE(std::fabs(set[c] - stamp), 0.02 + 1e-9);
      EXPECT_GT(set[c], last_used[c]);
      last_used[c] = set[c];
    }
  }
}

TEST(ClosestName, SuggestsTheNearestKnownName)
{
  EXPECT_EQ(closestName("treshold", {"threshold", "top_k", "sequence_length"}), "threshold");
  EXPECT_EQ(closestName("sequence_lenght", {"threshold", "sequence_length"}), "sequence_length");
  EXPECT_EQ(closestName("x", {}), "");
  Config c;
  try
  {
    c.set("treshold", "0.1");
    FAIL();
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("did you mean 'threshold'"), std::string::npos) << e.what();
  }
}

TEST(ReferenceMap, LoadsACompatibleMapAndRefusesOthersNamingWhy)
{
  const std::string dir = ::testing::TempDir();
  const Config config;
  const FrameDescriber describer(config);
  PlaceDatabase map(describer.layout(), 0, config.toYaml());
  map.add(describer.describeImage(openable_test::gardensPoint("day_right", 0)));
  const std::string good = dir + "/reference_" + std::to_string(::getpid()) + ".map";
  map.save(good);
  EXPECT_EQ(loadReferenceMap(good, config).frameCount(), 1u);

  Config other = config;
  other.patch_size = 32;
  try
  {
    loadReferenceMap(good, other);
    FAIL();
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("patch_size '64' (running '32')"), std::string::npos) << e.what();
  }
  PlaceDatabase empty(describer.layout(), 0, config.toYaml());
  const std::string none = good + ".empty";
  empty.save(none);
  EXPECT_THROW(loadReferenceMap(none, config), Error);
  EXPECT_THROW(loadReferenceMap(good + ".missing", config), Error);
  std::remove(good.c_str());
  std::remove(none.c_str());
}

TEST(SequenceGaps, CountsTheNumbersThatNeverArrivedAndNothingElse)
{
  SequenceGaps gaps;  // unstamped frames (stamp 0): only seq counts
  gaps.note(0, 10, 0.0);  // the first message: nothing before it can be seen
  EXPECT_EQ(gaps.lost(), 0u);
  gaps.note(0, 11, 0.0);
  gaps.note(0, 14, 0.0);  // 12 and 13 were sent and dropped
  EXPECT_EQ(gaps.lost(), 2u);
  gaps.note(0, 3, 0.0);  // the publisher restarted: counting goes on from 3
  gaps.note(0, 3, 0.0);  // a publisher that does not number (seq stays): nothing
  gaps.note(0, 5, 0.0);
  EXPECT_EQ(gaps.lost(), 3u);
  // A stereo pair lost shows in both inputs: the frames lost are the larger count, not the sum.
  gaps.note(1, 0, 0.0);
  gaps.note(1, 3, 0.0);
  EXPECT_EQ(gaps.lost(), 3u);  // input 0: 3, input 1: 2
  gaps.note(1, 5, 0.0);
  EXPECT_EQ(gaps.lost(), 3u);  // both 3
  gaps.note(1, 7, 0.0);
  EXPECT_EQ(gaps.lost(), 4u);
  // Wrap-around of the 32-bit counter is a step back, not four billion lost frames.
  gaps.note(0, 4294967295u, 0.0);
  const uint64_t before = gaps.lost();
  gaps.note(0, 0, 0.0);
  EXPECT_EQ(gaps.lost(), before);
}

TEST(FixHistory, NearestFixWithinTheTolerance)
{
  FixHistory fixes;
  openable::GeoPosition found;
  EXPECT_FALSE(fixes.nearest(10.0, 1.0, found));
  for (int k = 0; k < 3; ++k)
  {
    openable::GeoPosition f;
    f.latitude = k;
    f.stamp = 10.0 + k;
    fixes.add(f);
  }
  ASSERT_TRUE(fixes.nearest(10.9, 0.5, found));
  EXPECT_EQ(found.latitude, 1.0);
  ASSERT_TRUE(fixes.nearest(11.5, 0.5, found));  // halfway: the later fix
  EXPECT_EQ(found.latitude, 2.0);
  EXPECT_FALSE(fixes.nearest(13.6, 0.5, found));  // the last fix is too old
  EXPECT_FALSE(fixes.nearest(9.0, 0.5, found));
  // Bounded: the oldest fixes leave.
  for (size_t k = 0; k < FixHistory::kCapacity; ++k)
  {
    openable::GeoPosition f;
    f.stamp = 100.0 + double(k);
    fixes.add(f);
  }
  EXPECT_FALSE(fixes.nearest(10.0, 0.5, found));
  fixes.clear();
  EXPECT_FALSE(fixes.nearest(100.0, 0.5, found));
}


TEST(SequenceGaps, UnnumberedFramesCountStepsOfSeveralCameraPeriods)
{
  SequenceGaps g;
  double stamp = 50.0;
  // seq 0 throughout (a converted bag): nothing can be said until the period is known.
  for (size_t i = 0; i <= SequenceGaps::kMinSteps; ++i)
    g.note(0, 0, stamp += (i == 3 ? 0.3 : 0.1));
  EXPECT_EQ(g.lost(), 0u) << "a gap before kMinSteps steps are known is not counted";
  g.note(0, 0, stamp += 0.4);  // 3 frames missing
  EXPECT_EQ(g.lost(), 3u);
  g.note(0, 0, stamp += 0.13);  // jitter: one step
  g.note(0, 0, stamp += 0.07);
  EXPECT_EQ(g.lost(), 3u);
  g.note(0, 0, stamp += 0.21);  // two periods and a bit: 1 missing
  EXPECT_EQ(g.lost(), 4u);
  g.note(0, 0, stamp += 0.0);  // a repeated stamp is not a step
  g.note(0, 0, 10.0);          // the stamps started over (a bag looped): the period is learnt again
  g.note(0, 0, 10.5);
  EXPECT_EQ(g.lost(), 4u);
}

TEST(SequenceGaps, EqualsANaiveCountOnRandomDropsFromASteadyCamera)
{
  // A 20 Hz camera whose frames reach the callback with random drops (none in the first 20 frames, as when
  // the detector is idle at the start); seq 0 throughout. The count is exactly the frames dropped.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial)
  {
    SequenceGaps g;
    uint64_t dropped = 0;
    for (int frame = 0; frame < 500; ++frame)
    {
      const bool drop = frame > 20 && frame < 499 && std::uniform_int_distribution<int>(0, 3)(rng) == 0;
      if (drop)
      {
        ++dropped;
        continue;
      }
      const double jitter = std::uniform_real_distribution<double>(-0.004, 0.004)(rng);
      g.note(0, 0, 1000.0 + 0.05 * frame + jitter);
    }
    EXPECT_EQ(g.lost(), dropped) << "trial " << trial;
  }
}
