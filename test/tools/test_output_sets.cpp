// Issue 22, finding 5, on the real tools: openable_eval, openable_trajectory, openable_map export and
// openable_offline (into a folder shared with the user's files, with --map-out) are killed with SIGKILL after
// random delays while they write a new output set over an earlier one. Right after each kill the folder holds
// the earlier set or the new one (openable_offline's shared folder too: its files are links through one current
// link), and after the next run no staging folder, stale generation or temporary file is left. On a full disk (the file size limit) openable_eval exits 1 and leaves the earlier set.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <thread>

#include "openable/io/npy.h"
#include "openable/io/staged_output.h"
#include "../core/output_set_files.h"
#include "../core/test_util.h"

namespace fs = std::filesystem;

namespace
{
using openable_test::Files;
using openable_test::leftovers;
using openable_test::readText;
using openable_test::visible;

/// Starts `binary arguments` (output to /dev/null) as a child of its own: its pid.
pid_t start(const std::string& binary, const std::string& arguments, long file_size_limit = 0)
{
  const std::string command = "exec '" + binary + "' " + arguments + " >/dev/null 2>&1";
  const pid_t child = ::fork();
  if (child == 0)
  {
    if (file_size_limit > 0)
    {
      ::signal(SIGXFSZ, SIG_IGN);
      const rlimit limit{static_cast<rlim_t>(file_size_limit), static_cast<rlim_t>(file_size_limit)};
      ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return child;
}

int finish(pid_t child)
{
  int status = 0;
  ::waitpid(child, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

int runTool(const std::string& binary, const std::string& arguments)
{
  return finish(start(binary, arguments));
}

class OutputSetsTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    root_ = fs::temp_directory_path() / ("openable_output_sets_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override
  {
    fs::remove_all(root_);
  }

  /// Runs `old_args` then `new_args` into `out` (prepared by `prepare`) `kills` times, killing the second run
  /// after a random delay; `same` tells whether what is seen is the earlier set or the new one.
  void killRuns(const std::string& binary, const std::string& old_args, const std::string& new_args,
                const fs::path& out, int kills, const std::function<void()>& prepare,
                const std::function<int(const Files&)>& which, const std::function<void()>& after_old = [] {})
  {
    // How long a whole run takes: the kills fall from the start to just past its end.
    prepare();
    ASSERT_EQ(runTool(binary, old_args), 0);
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(runTool(binary, new_args), 0);
    const double whole = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::mt19937 random(22);
    std::uniform_real_distribution<double> delay(0.0, 1.1 * whole);
    int killed = 0, earlier = 0, later = 0;
    for (int k = 0; k < kills; ++k)
    {
      prepare();
      ASSERT_EQ(runTool(binary, old_args), 0);
      after_old();
      const pid_t child = start(binary, new_args);
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(delay(random)));
      ::kill(child, SIGKILL);
      killed += finish(child) == -SIGKILL;
      const int seen = which(visible(out));
      EXPECT_NE(seen, 0) << "kill " << k << ": neither the earlier set nor the new one";
      earlier += seen == 1;
      later += seen == 2;
      ASSERT_EQ(runTool(binary, new_args), 0);  // the next run
      EXPECT_EQ(which(visible(out)), 2);
      EXPECT_EQ(leftovers(out), std::vector<std::string>()) << "kill " << k;
    }
    std::cout << fs::path(binary).filename().string() << ": " << kills << " kills after 0-" << int(1.1 * whole)
              << " ms (" << killed << " before the run ended): earlier set " << earlier << ", new set " << later
              << ", mixed " << kills - earlier - later << "\n";
  }

  /// A judge of exact sets: 1 for `old_set`, 2 for `new_set`, else 0.
  static std::function<int(const Files&)> exactly(const Files& old_set, const Files& new_set)
  {
    return [old_set, new_set](const Files& seen) { return seen == old_set ? 1 : seen == new_set ? 2 : 0; };
  }

  fs::path root_;
};

TEST_F(OutputSetsTest, EvalKilledOrOutOfDiskLeavesTheEarlierOrTheNewSet)
{
  cv::Mat m(60, 60, CV_32F);
  cv::randu(m, 0.0, 1.0);
  openable::writeNpy((root_ / "m.npy").string(), m);
  const std::string common = "--matrix '" + (root_ / "m.npy").string() + "' --output '";
  const fs::path out = root_ / "out";
  ASSERT_EQ(runTool(OPENABLE_EVAL_BINARY, common + (root_ / "old").string() + "' --tolerance 0"), 0);
  ASSERT_EQ(runTool(OPENABLE_EVAL_BINARY, common + (root_ / "new").string() + "' --tolerance 3"), 0);
  const Files old_set = visible(root_ / "old"), new_set = visible(root_ / "new");
  ASSERT_EQ(old_set.size(), 3u);  // metrics.json, pr_curve.csv, pr_curve.png
  ASSERT_NE(old_set, new_set);
  killRuns(OPENABLE_EVAL_BINARY, common + out.string() + "' --tolerance 0", common + out.string() + "' --tolerance 3",
           out, 20, [&] { fs::remove_all(out); }, exactly(old_set, new_set));

  // The reproducer: a full disk (here the file size limit, below the PNG's size) fails the run and
  // keeps the earlier metrics.json and pr_curve.csv beside the earlier pr_curve.png.
  ASSERT_EQ(runTool(OPENABLE_EVAL_BINARY, common + out.string() + "' --tolerance 0"), 0);
  EXPECT_EQ(finish(start(OPENABLE_EVAL_BINARY, common + out.string() + "' --tolerance 3",
                         static_cast<long>(new_set.at("pr_curve.png").size() / 2))),
            1);
  EXPECT_EQ(visible(out), old_set);
  EXPECT_EQ(leftovers(out), std::vector<std::string>());
}

TEST_F(OutputSetsTest, TrajectoryKilledLeavesTheEarlierOrTheNewSet)
{
  std::ofstream(root_ / "loops.txt") << "100 10\n300 20\n900 50\n";
  const std::string common = "--poses " + openable_test::sharedData("kitti/poses/06.txt") + " --loops " +
                             (root_ / "loops.txt").string() + " --output ";
  const fs::path out = root_ / "out";
  ASSERT_EQ(runTool(OPENABLE_TRAJECTORY_BINARY, common + (root_ / "old").string() + " --distance 5"), 0);
  ASSERT_EQ(runTool(OPENABLE_TRAJECTORY_BINARY, common + (root_ / "new").string() + " --distance 400"), 0);
  const Files old_set = visible(root_ / "old"), new_set = visible(root_ / "new");
  ASSERT_EQ(old_set.size(), 2u);
  ASSERT_NE(old_set, new_set);
  killRuns(OPENABLE_TRAJECTORY_BINARY, common + out.string() + " --distance 5",
           common + out.string() + " --distance 400", out, 20, [&] { fs::remove_all(out); },
           exactly(old_set, new_set));
}

/// The first 60 frames of Gardens Point day_right (data/sample) linked into `folder`.
void shortStream(const fs::path& folder)
{
  fs::create_directories(folder);
  std::vector<fs::path> frames;
  for (const auto& entry : fs::directory_iterator(std::string(OPENABLE_SOURCE_DIR) + "/data/sample/day_right"))
    frames.push_back(entry.path());
  std::sort(frames.begin(), frames.end());
  for (size_t i = 0; i < 60 && i < frames.size(); ++i)
    fs::create_symlink(frames[i], folder / frames[i].filename());
}

TEST_F(OutputSetsTest, OfflineKilledLeavesTheEarlierOrTheNewSetAndTheUsersFiles)
{
  // As the demo does: the output folder also holds the input stream and the user's notes (a shared folder).
  const fs::path out = root_ / "out", map = root_ / "run.map";
  const std::string base = std::string("--config ") + OPENABLE_SOURCE_DIR + "/config/default.yaml --quiet --reference " +
                           (out / "stream").string() + " --map-out " + map.string() + " --output " + out.string();
  const std::string old_args = base + " --set exclusion_window=20", new_args = base + " --set exclusion_window=5";
  const auto prepare = [&]
  {
    fs::remove_all(out);
    shortStream(out / "stream");
    std::ofstream(out / "notes.txt") << "the user's notes\n";
  };
  prepare();
  ASSERT_EQ(runTool(OPENABLE_OFFLINE_BINARY, old_args), 0);
  const Files old_set = visible(out, {"timings.json"});
  ASSERT_EQ(runTool(OPENABLE_OFFLINE_BINARY, new_args), 0);
  const Files new_set = visible(out, {"timings.json"});
  ASSERT_EQ(old_set.size(), 5u);  // the user's notes and four outputs besides timings.json
  ASSERT_NE(old_set.at("decisions.csv"), new_set.at("decisions.csv"));
  // timings.json differs from run to run: the earlier one is read after each earlier run.
  std::string old_timings;
  const auto which = [&](const Files& seen_all)
  {
    Files seen = seen_all;
    const std::string timings = seen.count("timings.json") ? seen["timings.json"] : "";
    seen.erase("timings.json");
    if (timings.empty())
      return 0;
    if (seen == old_set && timings == old_timings)
      return 1;
    return seen == new_set && timings != old_timings ? 2 : 0;
  };
  killRuns(OPENABLE_OFFLINE_BINARY, old_args, new_args, out, 20, prepare, which,
           [&] { old_timings = readText(out / "timings.json"); });
  EXPECT_EQ(readText(out / "notes.txt"), "the user's notes\n");
}

TEST_F(OutputSetsTest, MapExportKilledLeavesTheEarlierOrTheNewSet)
{
  shortStream(root_ / "stream");
  const std::string base = std::string("--config ") + OPENABLE_SOURCE_DIR + "/config/default.yaml --quiet --reference " +
                           (root_ / "stream").string() + " --output " + (root_ / "run").string() + " --map-out ";
  ASSERT_EQ(runTool(OPENABLE_OFFLINE_BINARY, base + (root_ / "a.map").string() + " --session earlier"), 0);
  ASSERT_EQ(runTool(OPENABLE_OFFLINE_BINARY, base + (root_ / "b.map").string() + " --session later"), 0);
  const fs::path out = root_ / "out";
  ASSERT_EQ(runTool(OPENABLE_MAP_BINARY, "export " + (root_ / "a.map").string() + " --csv " + (root_ / "old").string()), 0);
  ASSERT_EQ(runTool(OPENABLE_MAP_BINARY, "export " + (root_ / "b.map").string() + " --csv " + (root_ / "new").string()), 0);
  const Files old_set = visible(root_ / "old"), new_set = visible(root_ / "new");
  ASSERT_EQ(old_set.size(), 2u);
  ASSERT_NE(old_set, new_set);
  killRuns(OPENABLE_MAP_BINARY, "export " + (root_ / "a.map").string() + " --csv " + out.string(),
           "export " + (root_ / "b.map").string() + " --csv " + out.string(), out, 20, [&] { fs::remove_all(out); },
           exactly(old_set, new_set));
}

}  // namespace
