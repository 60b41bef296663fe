// Issue 22, "a kill -9 at any point of any tool leaves the earlier output set or the new one, never a mix,
// and no stale file after the next run": the shared-folder case of StagedOutput (the journal), beyond one
// kill of the writer (test_staged_output.cpp). The next run that completes a killed writer's journal is
// itself killed at every step of that completion; and two tools' sets share a folder with a user's file,
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

bool hasCommit(const fs::path& dir)
{
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().rfind(".openable_commit.", 0) == 0)
      return true;
  return false;
}

/// Only the files of `files` (and what `visible` shows of them) in `seen`.
Files part(const Files& seen, const Files& files)
{
  Files out;
  for (const auto& entry : seen)
    if (files.count(entry.first) || entry.first == "only_old.txt" || entry.first == "only_new.txt")
      out.insert(entry);
  return out;
}

class StagedOutputJournalTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    root_ = fs::temp_directory_path() / ("openable_journal_" + std::to_string(::getpid()) + "_" +
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

TEST_F(StagedOutputJournalTest, AKillWhileTheNextRunCompletesAJournalStillEndsWithTheNewSet)
{
  int writer_kills_after_commit = 0, recovery_kills = 0;
  for (int step = 1; step < 200; ++step)
  {
    startShared();
    if (!killedAt(step, [this] { writeSet(dir_, kNew, "tool_a"); }))
      break;
    if (!hasCommit(dir_))
      continue;  // killed before the commit point: test_staged_output covers it
    ++writer_kills_after_commit;
    // The next run completes the journal and is killed at each step of that; the one after finishes it.
    for (int again = 1; again < 50; ++again)
    {
      const fs::path copy = root_ / "copy";
      fs::remove_all(copy);
      fs::copy(dir_, copy, fs::copy_options::recursive);
      const bool killed = killedAt(again, [&copy] { openable::StagedOutput::recover(copy.string()); });
      if (killed)
        ++recovery_kills;
      openable::StagedOutput::recover(copy.string());
      EXPECT_EQ(visible(copy, {kUser}), kNew) << "writer killed at " << step << ", recovery at " << again;
      EXPECT_EQ(readText(copy / kUser), "the user's\n");
      EXPECT_TRUE(leftovers(copy).empty()) << "writer killed at " << step << ", recovery at " << again;
      fs::remove_all(copy);
      if (!killed)
        break;
    }
  }
  std::cout << "writer killed after its commit: " << writer_kills_after_commit << " steps; recoveries killed: "
            << recovery_kills << "\n";
  ::testing::Test::RecordProperty("writer_kills_after_commit", writer_kills_after_commit);
  ::testing::Test::RecordProperty("recovery_kills", recovery_kills);
  EXPECT_GE(writer_kills_after_commit, 3);  // committed, set files moved, earlier file removed, ...
  EXPECT_GE(recovery_kills, 3);
}

TEST_F(StagedOutputJournalTest, AnotherToolsRunCompletesOrDropsAKilledSetAndLeavesNoStaleFile)
{
  int kills = 0, old_seen = 0, new_seen = 0;
  for (int step = 1; step < 200; ++step)
  {
    startShared();
    writeSet(dir_, kOther, "tool_b");
    if (!killedAt(step, [this] { writeSet(dir_, kNew, "tool_a"); }))
      break;
    ++kills;
    // The next run is another tool's on the same folder: it settles tool_a's set and writes its own.
    writeSet(dir_, kOther, "tool_b");
    const Files seen = visible(dir_, {kUser});
    const Files a = part(seen, kOld);
    EXPECT_TRUE(a == kOld || a == kNew) << "killed at step " << step;
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
