// openable_offline --poses: keyframes from odometry, as a nodelet with ~fixed_frame and ~keyframe_distance.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "../core/test_util.h"
#include "openable/io/npy.h"
#include "run_tool.h"

namespace fs = std::filesystem;

namespace
{
using openable_test::Result;

struct Folder
{
  fs::path path = fs::temp_directory_path() / ("openable_offline_poses_" + std::to_string(::getpid()));
  Folder()
  {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Folder()
  {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

/// The first `frames` images of the bundled day_right traversal, in a folder of their own.
std::string firstFrames(const Folder& folder, int frames)
{
  const fs::path images = folder.path / "images";
  fs::create_directories(images);
  char name[32];
  for (int i = 0; i < frames; ++i)
  {
    std::snprintf(name, sizeof(name), "Image%03d.jpg", i);
    fs::copy_file(openable_test::sampleData(std::string("day_right/") + name), images / name);
  }
  return images.string();
}

/// A TUM trajectory: the camera drives 1 m a frame along x, but stands still for frames 10..29 (those keep
/// frame 10's position); stamps 10 Hz from 100 s.
std::string standingTrajectory(const Folder& folder, int frames)
{
  std::ostringstream tum;
  tum << "# timestamp tx ty tz qx qy qz qw\n";
  double x = 0.0;
  for (int i = 0; i < frames; ++i)
  {
    if (i > 0 && !(i >= 11 && i <= 29))
      x += 1.0;
    tum << 100.0 + 0.1 * i << " " << x << " 0 0 0 0 0 1\n";
  }
  const std::string path = (folder.path / "poses.tum").string();
  std::ofstream(path) << tum.str();
  return path;
}

/// Status of each frame (the `status` column of decisions.csv), by row.
std::vector<std::string> statuses(const std::string& decisions_csv)
{
  std::ifstream in(decisions_csv);
  std::string line;
  std::getline(in, line);  // header: query,match,distance,score,status,accepted
  std::vector<std::string> out;
  while (std::getline(in, line))
  {
    std::istringstream fields(line);
    std::string field;
    for (int column = 0; column < 5; ++column)
      std::getline(fields, field, ',');
    out.push_back(field);
  }
  return out;
}

std::string common(const std::string& images, const std::string& output)
{
  return "--config " + std::string(OPENABLE_SOURCE_DIR) + "/config/default.yaml --reference " + images +
         " --output " + output + " --quiet";
}
}  // namespace

TEST(OfflinePoses, StandingStillStoresNoKeyframe)
{
  const Folder folder;
  const std::string images = firstFrames(folder, 40);
  const std::string out = (folder.path / "out").string();
  // Single images and no exclusion, so the last frame is compared with every stored one (see below).
  const Result r = openable_test::runTool(OPENABLE_OFFLINE_BINARY,
                                          common(images, out) + " --poses " + standingTrajectory(folder, 40) +
                                              " --set sequence_length=1 --set exclusion_window=0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> status = statuses(out + "/decisions.csv");
  ASSERT_EQ(status.size(), 40u);
  // Frame 10 is where the camera stopped: the last keyframe. Frame 30 is 1 m further: the next one.
  for (int i = 0; i < 40; ++i)
  {
    const bool standing = i >= 11 && i <= 29;
    if (standing)
      EXPECT_EQ(status[size_t(i)], "not_keyframe") << "frame " << i;
    else
      for (const char* unstored : {"not_keyframe", "standstill", "time_jump"})
        EXPECT_NE(status[size_t(i)], unstored) << "frame " << i;
  }
  EXPECT_NE(r.output.find("not_keyframe 19"), std::string::npos) << r.output;
  // Frame 39 was compared with exactly the stored frames: 0..10 and 30..38 (itself is stored after).
  const cv::Mat m = openable::readNpy(out + "/distance_matrix.npy");
  ASSERT_EQ(m.rows, 40);
  for (int column = 0; column < 40; ++column)
  {
    const bool stored = column <= 10 || (column >= 30 && column <= 38);
    EXPECT_EQ(std::isfinite(m.at<float>(39, column)), stored) << "column " << column;
  }

  // The same stream without --poses stores every frame: the keyframes came from the poses.
  const std::string plain = (folder.path / "plain").string();
  ASSERT_EQ(openable_test::runTool(OPENABLE_OFFLINE_BINARY, common(images, plain)).exit_code, 0);
  for (const std::string& s : statuses(plain + "/decisions.csv"))
    EXPECT_NE(s, "not_keyframe");

  // --keyframe-distance 0: the poses give stamps only, every frame is stored.
  const std::string every = (folder.path / "every").string();
  ASSERT_EQ(openable_test::runTool(OPENABLE_OFFLINE_BINARY, common(images, every) + " --poses " +
                                                                standingTrajectory(folder, 40) +
                                                                " --keyframe-distance 0")
                .exit_code,
            0);
  for (const std::string& s : statuses(every + "/decisions.csv"))
    EXPECT_NE(s, "not_keyframe");
}

TEST(OfflinePoses, BadPosesAndOptionsAreRefusedWithReasons)
{
  const Folder folder;
  const std::string images = firstFrames(folder, 12);
  const std::string out = (folder.path / "out").string();
  struct Case
  {
    std::string args, expected;
  };
  const std::string short_file = standingTrajectory(folder, 10);  // 10 poses for 12 frames
  const std::string bad_file = (folder.path / "bad.txt").string();
  std::ofstream(bad_file) << "1 0 0 0 0 1 0 0 0 0 1\n";
  const std::vector<Case> cases = {
      {"--poses " + short_file, "holds 10 poses but '" + images + "' has 12 frames"},
      {"--poses " + bad_file, bad_file + ":1: 11 numbers; expected a KITTI pose"},
      {"--poses /nonexistent.txt", "cannot read pose file '/nonexistent.txt'"},
      {"--keyframe-distance 2", "need --poses"},
      {"--poses " + short_file + " --keyframe-distance -1", "--keyframe-distance: '-1' is not allowed"},
      {"--poses " + short_file + " --keyframe-angle 4", "--keyframe-angle: '4' is not allowed"},
  };
  for (const Case& c : cases)
  {
    const Result r = openable_test::runTool(OPENABLE_OFFLINE_BINARY, common(images, out) + " " + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
  }
  EXPECT_FALSE(fs::exists(out + "/decisions.csv"));
}
