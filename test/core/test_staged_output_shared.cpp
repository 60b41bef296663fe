// Issue 22, "a kill -9 at any point of any tool leaves the earlier output set or the new one, never a mix,
// and no stale file after the next run": the shared-folder case of StagedOutput (the set's links through its
// current link), beyond one kill of the writer (test_staged_output.cpp). The next run's clean-up after a
// killed writer is itself killed at every step; an earlier set of plain files (from an owned folder) becomes
// links with the writer killed at every step of that; and two tools' sets share a folder with a user's file,
// one tool killed at every step, the other then writing its own set.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <functional>
#include <string>

#include "openable/io/atomic_file.h"
#include "openable/io/staged_output.h"
#include "output_set_files.h"
#include "staged_output_kills.h"

namespace fs = std::filesystem;
using namespace openable_test;  // Files, readText, visible, leftovers, kOld, kNew, writeSet, killedAt

namespace
{
const Files kOther = {{"metrics.json", "{}\n"}, {"pr_curve.csv", "p,r\n"}};
const char kUser[] = "user.txt";

/// Only the files of `files` (and what `visible` shows of them) in `seen`.
Files part(const Files& seen, const Files& files)
{
  Files out;
  for (const auto& entry : seen)
    if (files.count(entry.first) || entry.first == "only_old.txt" || entry.first == "only_new.txt")
      out.insert(entry);
  return out;
}

class StagedOutputSharedTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    root_ = fs::temp_directory_path() / ("openable_shared_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    dir_ = root_ / "out";
  }
  void TearDown() override
  {
    fs::remove_all(root_);
  }
  /// The earlier set kOld in a folder shared with the user's file.
  void startShared()
  {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / kUser) << "the user's\n";
    writeSet(dir_, kOld, "tool_a");
  }
  fs::path root_, dir_;
};
}  // namespace

TEST_F(StagedOutputSharedTest, AKillOfTheNextRunsCleanUpChangesNothingAReaderSees)
{
  int writer_kills = 0, cleanup_kills = 0;
  for (int step = 1; step < 200; ++step)
  {
    startShared();
    writeSet(dir_, kOld, "tool_a");  // the earlier set as links already
    if (!killedAt(step, [this] { writeSet(dir_, kNew, "tool_a"); }))
      break;
    ++writer_kills;
    const Files seen = visible(dir_, {kUser});
    EXPECT_TRUE(seen == kOld || seen == kNew) << "writer killed at " << step;
    // The next run's clean-up, killed at each of its steps; the one after finishes it.
    for (int again = 1; again < 50; ++again)
    {
      const fs::path copy = root_ / "copy";
      fs::remove_all(copy);
      fs::copy(dir_, copy, fs::copy_options::recursive | fs::copy_options::copy_symlinks);
      const bool killed = killedAt(again, [&copy] { openable::StagedOutput::recover(copy.string()); });
      cleanup_kills += killed;
      EXPECT_EQ(visible(copy, {kUser}), seen) << "writer killed at " << step << ", clean-up at " << again;
      openable::StagedOutput::recover(copy.string());
      EXPECT_EQ(visible(copy, {kUser}), seen) << "writer killed at " << step << ", clean-up at " << again;
      EXPECT_EQ(readText(copy / kUser), "the user's\n");
      EXPECT_TRUE(leftovers(copy).empty()) << "writer killed at " << step << ", clean-up at " << again;
      fs::remove_all(copy);
      if (!killed)
        break;
    }
  }
  std::cout << "writer killed " << writer_kills << " times; clean-ups killed: " << cleanup_kills << "\n";
  ::testing::Test::RecordProperty("writer_kills", writer_kills);
  EXPECT_GE(writer_kills, 8);  // staged, generation ready, links made, switched, earlier removed, ...
  EXPECT_GE(cleanup_kills, 3);  // a stale generation, its links
}

TEST_F(StagedOutputSharedTest, AnEarlierSetOfPlainFilesBecomesLinksWithAWholeSetAtEveryKill)
{
  int kills = 0, old_seen = 0, new_seen = 0;
  for (int step = 1; step < 200; ++step)
  {
    fs::remove_all(dir_);
    writeSet(dir_, kOld, "tool_a");  // an owned folder: plain files
    ASSERT_FALSE(fs::is_symlink(dir_ / "a.csv"));
    std::ofstream(dir_ / kUser) << "the user's\n";  // shared now
    if (!killedAt(step, [this] { writeSet(dir_, kNew, "tool_a"); }))
    {
      EXPECT_TRUE(fs::is_symlink(dir_ / "a.csv"));
      break;
    }
    ++kills;
    const Files seen = visible(dir_, {kUser});
    EXPECT_TRUE(seen == kOld || seen == kNew) << "killed at step " << step;
    old_seen += seen == kOld;
    new_seen += seen == kNew;
    writeSet(dir_, kNew, "tool_a");  // the next run
    EXPECT_EQ(visible(dir_, {kUser}), kNew) << "killed at step " << step;
    EXPECT_TRUE(leftovers(dir_).empty()) << "killed at step " << step << ": " << leftovers(dir_).front();
  }
  std::cout << "plain earlier set, killed " << kills << " times: earlier set after " << old_seen << ", new set after "
            << new_seen << "\n";
  EXPECT_GE(kills, 8);
  EXPECT_GT(old_seen, 0);
  EXPECT_GT(new_seen, 0);
}

TEST_F(StagedOutputSharedTest, AnotherToolsRunCompletesOrDropsAKilledSetAndLeavesNoStaleFile)
{
  int kills = 0, old_seen = 0, new_seen = 0;
  for (int step = 1; step < 200; ++step)
  {
    startShared();
    writeSet(dir_, kOther, "tool_b");
    if (!killedAt(step, [this] { writeSet(dir_, kNew, "tool_a"); }))
      break;
    ++kills;
    const Files right_after = part(visible(dir_, {kUser}), kOld);
    EXPECT_TRUE(right_after == kOld || right_after == kNew) << "killed at step " << step;
    // The next run is another tool's on the same folder: it settles tool_a's set and writes its own.
    writeSet(dir_, kOther, "tool_b");
    const Files seen = visible(dir_, {kUser});
    const Files a = part(seen, kOld);
    EXPECT_EQ(a, right_after) << "killed at step " << step;
    old_seen += a == kOld;
    new_seen += a == kNew;
    for (const auto& [name, text] : kOther)
      EXPECT_EQ(seen.count(name) ? seen.at(name) : "", text) << "killed at step " << step;
    EXPECT_EQ(seen.size(), kOther.size() + 3) << "killed at step " << step;
    EXPECT_EQ(readText(dir_ / kUser), "the user's\n");
    EXPECT_TRUE(leftovers(dir_).empty()) << "killed at step " << step << ": " << leftovers(dir_).front();
  }
  std::cout << "tool_a killed " << kills << " times: earlier set after " << old_seen << ", new set after " << new_seen
            << "\n";
  EXPECT_GE(kills, 10);
  EXPECT_GT(old_seen, 0);
  EXPECT_GT(new_seen, 0);
}
