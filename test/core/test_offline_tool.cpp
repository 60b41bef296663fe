// openable_offline end to end: the command line other tools and checks rely on.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "openable/npy.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace
{
struct Result
{
  int exit_code;
  std::string output;  // stdout and stderr
};

Result run(const std::string& arguments)
{
  const std::string command = std::string(OPENABLE_OFFLINE_BINARY) + " " + arguments + " 2>&1";
  Result r{-1, ""};
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe)
    return r;
  char buffer[512];
  while (fgets(buffer, sizeof(buffer), pipe))
    r.output += buffer;
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string config()
{
  return std::string(OPENABLE_SOURCE_DIR) + "/config/paper.yaml";
}

std::string freshDir(const std::string& name)
{
  const fs::path dir = fs::temp_directory_path() / ("openable_offline_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir.string();
}
}  // namespace

TEST(OfflineTool, DayLeftVsNightRightWritesA200By200Matrix)
{
  const std::string out = freshDir("gp");
  const Result r = run("--config " + config() + " --reference " + openable_test::sharedData("gardens_point/day_left") +
                       " --query " + openable_test::sharedData("gardens_point/night_right") + " --output " + out +
                       " --set sequence_length=5 --set threshold=0.3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat m = openable::readNpy(out + "/distance_matrix.npy");
  EXPECT_EQ(m.rows, 200);
  EXPECT_EQ(m.cols, 200);
  for (const char* file :
       {"distance_matrix.png", "distance_matrix_thresholded.png", "loop_closures.csv", "timings.json"})
    EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
  std::ifstream csv(out + "/loop_closures.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "query,match,distance,score,status");
  std::ifstream json(out + "/timings.json");
  const std::string timings((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  for (const char* key :
       {"\"preprocess\"", "\"describe\"", "\"match\"", "\"frames\": 400", "\"database_bytes\"", "per_frame_ms"})
    EXPECT_NE(timings.find(key), std::string::npos) << key;
  EXPECT_FALSE(cv::imread(out + "/distance_matrix.png").empty());
}

TEST(OfflineTool, LoopClosureModeMarksExcludedAndFutureFramesNaN)
{
  const std::string out = freshDir("loop");
  const Result r = run("--config " + config() + " --reference " + openable_test::sharedData("gardens_point/day_right") +
                       " --output " + out + " --set exclusion_window=10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat m = openable::readNpy(out + "/distance_matrix.npy");
  ASSERT_EQ(m.rows, 200);
  ASSERT_EQ(m.cols, 200);
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j)
      ASSERT_EQ(std::isnan(m.at<float>(i, j)), j > i - 11) << i << "," << j;
}

TEST(OfflineTool, BadConfigurationGivesOneLineReasonAndNonZeroExit)
{
  const std::string out = freshDir("bad");
  const std::string ref = " --reference " + openable_test::sharedData("gardens_point/day_right");
  struct Case
  {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"--config " + config() + ref + " --output " + out + " --set descriptor=NOPE", "expected LDB"},
      {"--config " + config() + ref + " --output " + out + " --set sequence_length=0", "sequence_length"},
      {"--config " + config() + ref + " --output " + out + " --set threshold=2", "threshold"},
      {"--config " + config() + ref + " --output " + out + " --set no_such_key=1", "unknown configuration key"},
      {"--config /nonexistent.yaml" + ref + " --output " + out, "cannot read configuration"},
      {"--config " + config() + " --reference /nonexistent --output " + out, "does not exist"},
      {"--config " + config() + ref + " --output /proc/forbidden", "cannot"},
      {"--config " + config() + ref, "required"},
  };
  for (const auto& c : cases)
  {
    const Result r = run(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
  EXPECT_FALSE(fs::exists(out + "/distance_matrix.npy"));
}

TEST(OfflineTool, UnreadableImageInFolderIsReportedAndSkipped)
{
  const std::string in = freshDir("in");
  const std::string out = freshDir("out");
  fs::create_directories(in);
  for (int i = 0; i < 4; ++i)
    fs::copy_file(openable_test::sharedData("gardens_point/day_right/Image00" + std::to_string(i) + ".jpg"),
                  in + "/Image00" + std::to_string(i) + ".jpg");
  std::ofstream(in + "/Image002.jpg", std::ios::trunc) << "not a jpeg";
  const Result r =
      run("--config " + config() + " --reference " + in + " --output " + out + " --set exclusion_window=0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Image002.jpg"), std::string::npos) << r.output;
  const cv::Mat m = openable::readNpy(out + "/distance_matrix.npy");
  ASSERT_EQ(m.rows, 4);
  for (int j = 0; j < 4; ++j)
    EXPECT_TRUE(std::isnan(m.at<float>(2, j)));  // the unreadable frame keeps its (empty) row
  EXPECT_FALSE(std::isnan(m.at<float>(3, 0)));
}
