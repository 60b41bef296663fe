// Progress: the line's text, and when it is written (fake clock, string stream), on a terminal and not.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "progress.h"

using openable::formatDuration;
using openable::formatProgress;
using openable::Progress;

namespace
{
std::vector<std::string> splitLines(const std::string& text)
{
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

struct FakeClock
{
  double now = 100.0;
  Progress::Clock clock()
  {
    return [this] { return now; };
  }
};

Progress::Options options(bool terminal, size_t total = 1000)
{
  Progress::Options o;
  o.label = "tool";
  o.total = total;
  o.terminal = terminal;
  o.interval = 5.0;
  o.redraw = 0.1;
  return o;
}
}  // namespace

TEST(Progress, DurationsAsClockText)
{
  EXPECT_EQ(formatDuration(0.0), "0:00");
  EXPECT_EQ(formatDuration(4.6), "0:05");
  EXPECT_EQ(formatDuration(754.0), "12:34");
  EXPECT_EQ(formatDuration(3723.0), "1:02:03");
  EXPECT_EQ(formatDuration(-3.0), "0:00");
  EXPECT_EQ(formatDuration(1.0 / 0.0), "0:00");
}

TEST(Progress, LineNamesDoneTotalRateAndTimeLeft)
{
  // 250 of 1000 frames in 10 s: 25 frames/s, 750 left -> 30 s.
  EXPECT_EQ(formatProgress("kitti_to_bag", "frames", 250, 1000, 10.0),
            "kitti_to_bag: 250/1000 frames (25%), 25.0 frames/s, 0:30 left");
  EXPECT_EQ(formatProgress("eval", "settings", 390, 390, 12.0), "eval: 390/390 settings (100%), 32.5 settings/s");
  // Unknown total: no percentage, no time left.
  EXPECT_EQ(formatProgress("x", "frames", 7, 0, 2.0), "x: 7 frames, 3.5 frames/s");
  // Nothing measured yet: no rate (it would be infinite or zero).
  EXPECT_EQ(formatProgress("x", "frames", 0, 10, 0.0), "x: 0/10 frames (0%)");
  EXPECT_EQ(formatProgress("x", "frames", 3, 10, 0.0), "x: 3/10 frames (30%)");
}

TEST(Progress, PlainLinesEveryIntervalAndAFinalOne)
{
  FakeClock fake;
  std::ostringstream out;
  {
    Progress progress(options(false), out, fake.clock());
    for (int i = 1; i <= 1000; ++i)
    {
      fake.now += 1.0 / 64.0;  // 64 frames/s (exact in binary): 15.6 s in all, lines at 5, 10, 15 s + final
      progress.step();
    }
    progress.finish();
    progress.finish();  // once only
  }
  const auto lines = splitLines(out.str());
  ASSERT_EQ(lines.size(), 4u) << out.str();
  EXPECT_EQ(lines[0], "tool: 320/1000 frames (32%), 64.0 frames/s, 0:11 left");
  EXPECT_EQ(lines[1], "tool: 640/1000 frames (64%), 64.0 frames/s, 0:06 left");
  EXPECT_EQ(lines[3], "tool: 1000/1000 frames (100%), 64.0 frames/s");
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
}

TEST(Progress, TerminalRedrawsOneLineAndEndsIt)
{
  FakeClock fake;
  std::ostringstream out;
  Progress progress(options(true, 10), out, fake.clock());
  progress.update(1);  // no time passed: not drawn yet
  EXPECT_EQ(out.str(), "");
  fake.now += 0.5;
  progress.update(2);
  const std::string two = "tool: 2/10 frames (20%), 4.0 frames/s, 0:02 left";
  EXPECT_EQ(out.str(), "\r" + two);
  fake.now += 0.05;  // within the redraw period: not redrawn
  progress.update(3);
  EXPECT_EQ(out.str(), "\r" + two);
  fake.now += 1.95;
  progress.update(10);
  progress.finish();
  // The shorter line is padded over the rest of the longer one; the final draw ends the line.
  const std::string ten = "tool: 10/10 frames (100%), 4.0 frames/s";
  EXPECT_EQ(out.str(), "\r" + two + "\r" + ten + std::string(two.size() - ten.size(), ' ') + "\r" + ten + "\n");
}

TEST(Progress, QuietWritesNothingAndCountsStillAdvance)
{
  FakeClock fake;
  std::ostringstream out;
  Progress::Options o = options(false);
  o.quiet = true;
  {
    Progress progress(o, out, fake.clock());
    for (int i = 0; i < 100; ++i)
    {
      fake.now += 1.0;
      progress.step();
    }
    EXPECT_EQ(progress.done(), 100u);
  }
  EXPECT_EQ(out.str(), "");
}

TEST(Progress, SmallerCountsAreIgnoredAndTheDestructorFinishes)
{
  FakeClock fake;
  std::ostringstream out;
  {
    Progress progress(options(false, 4), out, fake.clock());
    fake.now += 1.0;
    progress.update(3);
    progress.update(1);
    EXPECT_EQ(progress.done(), 3u);
  }
  EXPECT_EQ(out.str(), "tool: 3/4 frames (75%), 3.0 frames/s, 0:00 left\n");
}
