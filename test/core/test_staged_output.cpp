// Issue 22, finding 5: output sets are all-or-nothing. A child process writes a new set over an earlier one
// through StagedOutput and is killed (SIGKILL) at every step of the write and the publish, in a folder the set
// owns (atomic exchange) and in one shared with a user's file (the set's links); a write that fails (the file size
// limit: a full disk as the process sees it) leaves the earlier set; leftovers of dead runs go at the next run.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "openable/io/atomic_file.h"
#include "openable/error.h"
#include "openable/io/staged_output.h"
#include "output_set_files.h"
#include "staged_output_kills.h"

namespace fs = std::filesystem;

namespace
{
using namespace openable_test;  // Files, readText, visible, leftovers, kOld, kNew, writeSet, killedAt

class StagedOutputTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    root_ = fs::temp_directory_path() / ("openable_staged_output_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
    dir_ = root_ / "out";
  }
  void TearDown() override
  {
    fs::remove_all(root_);
  }

  /// Kills a writer of kNew at every step, starting each time from kOld (plus the user's file when
  /// `shared`); returns the number of kills. Checks old-or-new after each and no leftover after the next run.
  int killAtEveryStep(bool shared)
  {
    int kills = 0, old_seen = 0, new_seen = 0;
    for (int step = 1; step < 200; ++step)
    {
      fs::remove_all(dir_);
      fs::create_directories(dir_);
      if (shared)
        std::ofstream(dir_ / "user.txt") << "the user's\n";
      writeSet(dir_, kOld);
      if (!killedAt(step, [this] { writeSet(dir_, kNew); }))
      {
        EXPECT_EQ(visible(dir_, {"user.txt"}), kNew);
        break;
      }
      ++kills;
      // What a reader sees right after the kill, before any clean-up, is a whole set.
      const Files right_after = visible(dir_, {"user.txt"});
      EXPECT_TRUE(right_after == kOld || right_after == kNew) << "killed at step " << step;
      openable::StagedOutput::recover(dir_.string());  // what the next run does first
      const Files seen = visible(dir_, {"user.txt"});
      EXPECT_EQ(seen, right_after) << "killed at step " << step;  // the clean-up changes nothing a reader sees
      old_seen += seen == kOld;
      new_seen += seen == kNew;
      EXPECT_TRUE(leftovers(dir_).empty()) << "killed at step " << step << ": " << leftovers(dir_).front();
      if (shared)
      {
        EXPECT_EQ(readText(dir_ / "user.txt"), "the user's\n");
      }
      writeSet(dir_, kNew);  // the next run
      EXPECT_EQ(visible(dir_, {"user.txt"}), kNew);
      EXPECT_TRUE(leftovers(dir_).empty());
    }
    std::cout << (shared ? "shared folder (links): " : "owned folder (exchange): ") << kills
              << " kills, earlier set after " << old_seen << ", new set after " << new_seen << "\n";
    EXPECT_GT(old_seen, 0);
    EXPECT_GT(new_seen, 0);
    return kills;
  }

  fs::path root_, dir_;
};

TEST_F(StagedOutputTest, KillAtEveryStepOfAnOwnedFolderLeavesTheEarlierOrTheNewSet)
{
  EXPECT_GE(killAtEveryStep(false), 10);
}

TEST_F(StagedOutputTest, KillAtEveryStepOfASharedFolderLeavesTheEarlierOrTheNewSetAndTheUsersFile)
{
  EXPECT_GE(killAtEveryStep(true), 10);
}

TEST_F(StagedOutputTest, SetsReplaceOnlyTheirOwnFiles)
{
  writeSet(dir_, kOld);
  EXPECT_EQ(visible(dir_), kOld);
  writeSet(dir_, kNew);  // only_old.txt was the set's: gone
  EXPECT_EQ(visible(dir_), kNew);
  std::ofstream(dir_ / "notes.txt") << "mine\n";
  {
    openable::StagedOutput other(dir_.string(), "other_tool");
    openable::writeFileAtomically(other.path("other.csv"), "x\n");
    other.publish();
  }
  writeSet(dir_, kOld);  // shared now: the set's links; notes.txt and the other tool's file stay
  Files expected = kOld;
  expected["notes.txt"] = "mine\n";
  expected["other.csv"] = "x\n";
  EXPECT_EQ(visible(dir_), expected);
  EXPECT_TRUE(leftovers(dir_).empty());
}

TEST_F(StagedOutputTest, AFileAddedWhileTheSetIsMadeAndALinkedFolderStay)
{
  writeSet(dir_, kOld);
  {
    openable::StagedOutput output(dir_.string(), "test_set");  // owned when it starts
    for (const auto& [name, text] : kNew)
      openable::writeFileAtomically(output.path(name), text);
    std::ofstream(dir_ / "late.txt") << "put there during the run\n";
    output.publish();
  }
  Files expected = kNew;
  expected["late.txt"] = "put there during the run\n";
  EXPECT_EQ(visible(dir_), expected);

  fs::create_directory_symlink(dir_, root_ / "link");
  writeSet(root_ / "link", kOld);
  EXPECT_TRUE(fs::is_symlink(root_ / "link"));
  expected = kOld;
  expected["late.txt"] = "put there during the run\n";
  EXPECT_EQ(visible(dir_), expected);
  EXPECT_TRUE(leftovers(dir_).empty());
}

TEST_F(StagedOutputTest, AFailedWriteLeavesTheEarlierSetAndNoStagingFolder)
{
  writeSet(dir_, kOld);
  const pid_t child = ::fork();
  if (child == 0)
  {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4000, 4000};  // b.png of the new set is 5000 bytes: a full disk for this process
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try
    {
      writeSet(dir_, kNew);
    }
    catch (const openable::Error& e)
    {
      ::_exit(std::string(e.what()).find("disk full") != std::string::npos ? 3 : 4);
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3);
  EXPECT_EQ(visible(dir_), kOld);
  EXPECT_TRUE(leftovers(dir_).empty());
}

TEST_F(StagedOutputTest, LeftoversOfDeadRunsGoAtTheNextRunThoseOfLiveOnesStay)
{
  const pid_t dead = ::fork();
  if (dead == 0)
    ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string d = std::to_string(dead);
  writeSet(dir_, kOld);
  fs::create_directories(root_ / ("out.openable_staging." + d));
  fs::create_directories(dir_ / (".openable_staging.test_set." + d));
  fs::create_directories(dir_ / (".openable_output." + d));  // the staging folder of earlier versions
  std::ofstream(dir_ / ("a.csv.tmp." + d)) << "half";  // a.csv is the set's
  std::ofstream(dir_ / ("notes.tmp." + d)) << "the user's";  // not the set's: stays
  std::ofstream(root_ / ("map.bin.tmp." + d)) << "half a map";
  fs::create_directories(root_ / "out.openable_staging.1");  // pid 1 runs: not ours to remove
  writeSet(dir_, kNew);
  openable::writeFileAtomically((root_ / "map.bin").string(), "a map");
  EXPECT_EQ(visible(dir_, {"notes.tmp." + d}), kNew);
  EXPECT_EQ(leftovers(dir_), (std::vector<std::string>{(dir_ / ("notes.tmp." + d)).string(),
                                                       (root_ / "out.openable_staging.1").string()}));
  EXPECT_FALSE(fs::exists(root_ / ("map.bin.tmp." + d)));
  EXPECT_EQ(readText(root_ / "map.bin"), "a map");
}

TEST_F(StagedOutputTest, AKilledSingleFileWriteLeavesTheOldFileAndNoTemporaryAfterTheNextWrite)
{
  const fs::path file = root_ / "map.bin";
  int kills = 0;
  for (int step = 1; step < 10; ++step)
  {
    openable::writeFileAtomically(file.string(), "old map");
    if (!killedAt(step, [&file] { openable::writeFileAtomically(file.string(), "new map"); }))
      break;
    ++kills;
    const std::string seen = readText(file);
    EXPECT_TRUE(seen == "old map" || seen == "new map") << seen;
    openable::writeFileAtomically(file.string(), "next");
    EXPECT_TRUE(leftovers(root_ / "x").empty());
  }
  EXPECT_EQ(kills, 3);  // written, synced, renamed
}

}  // namespace
