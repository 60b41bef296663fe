// openable_trajectory end to end: KITTI 06 with its published loops plus wrong ones drawn red in the PNG,
// the CSV, the KML of a hand-made path, and one-line reasons with non-zero exits for bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "openable/evaluation/evaluation.h"
#include "openable/view/trajectory_plot.h"
#include "../core/test_util.h"

#ifndef OPENABLE_TRAJECTORY_BINARY
#error "OPENABLE_TRAJECTORY_BINARY (path of the openable_trajectory executable) must be defined by the build"
#endif

namespace fs = std::filesystem;

namespace
{
struct ToolRun
{
  int status = -1;
  std::string out, err;
};

std::string readText(const fs::path& path)
{
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class TrajectoryToolTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("openable_trajectory_tool_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const
  {
    return (dir_ / name).string();
  }
  ToolRun run(const std::string& arguments) const
  {
    const std::string command = std::string("'") + OPENABLE_TRAJECTORY_BINARY + "' " + arguments + " >'" +
                                path("stdout") + "' 2>'" + path("stderr") + "'";
    const int raw = std::system(command.c_str());
    ToolRun r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = readText(path("stdout"));
    r.err = readText(path("stderr"));
    return r;
  }
  fs::path dir_;
};

const std::string kPoses = openable_test::sharedData("kitti/poses/06.txt");
const std::string kTruth = openable_test::sharedData("kitti/loop_ground_truth/kitti06GroundTruth.txt");
}  // namespace

TEST_F(TrajectoryToolTest, Kitti06PublishedLoopsGreenAndWrongOnesRed)
{
  // The detections: every 10th published loop, as openable_offline's CSV, plus three wrong ones.
  std::ifstream truth(kTruth);
  std::ofstream csv(path("loop_closures.csv"));
  csv << "query,match,distance\n";
  int n = 0, published = 0;
  for (std::string line; std::getline(truth, line);)
  {
    if (line.empty() || line[0] == '#' || n++ % 10 != 0)
      continue;
    const size_t space = line.find(' ');
    csv << line.substr(0, space) << "," << line.substr(space + 1) << ",0.1\n";
    ++published;
  }
  csv << "450,120,0.2\n550,15,0.2\n1000,400,0.2\n";
  csv.close();
  const ToolRun r =
      run("--poses " + kPoses + " --loops " + path("loop_closures.csv") + " --pairs " + kTruth + " --times " +
          openable_test::sharedData("kitti/times_06.txt") + " --output " + path("out") + " --title 'KITTI 06'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("loops: " + std::to_string(published + 3)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("agree with the ground truth: " + std::to_string(published)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("disagree: 3"), std::string::npos) << r.out;

  const cv::Mat image = cv::imread(path("out/trajectory.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(image.size(), cv::Size(1000, 800));
  const openable::TrajectoryPlot plot(openable::loadKittiPositions(kPoses), cv::Size(1000, 800));
  for (const auto& loop : {std::make_pair(450, 120), std::make_pair(550, 15), std::make_pair(1000, 400)})
  {
    const cv::Point2d middle = 0.5 * (plot.framePixel(loop.first) + plot.framePixel(loop.second));
    const cv::Vec3b bgr = image.at<cv::Vec3b>(int(std::lround(middle.y)), int(std::lround(middle.x)));
    EXPECT_TRUE(bgr[2] > 180 && bgr[1] < 70 && bgr[0] < 70) << loop.first << "-" << loop.second << ": " << bgr;
  }
  const cv::Point2d start_again = plot.framePixel(829);
  const cv::Vec3b bgr = image.at<cv::Vec3b>(int(std::lround(start_again.y)), int(std::lround(start_again.x)));
  EXPECT_TRUE(bgr[1] > 120 && bgr[2] < 70 && bgr[0] < 70) << bgr;

  const std::string table = readText(path("out/trajectory.csv"));
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 1102);
  EXPECT_NE(table.find("\n450,"), std::string::npos);
  EXPECT_NE(table.find(",120,0\n"), std::string::npos) << "frame 450: wrong partner 120, disagreeing";
  const size_t line_829 = table.find("\n829,");
  ASSERT_NE(line_829, std::string::npos);
  const std::string row = table.substr(line_829 + 1, table.find('\n', line_829 + 1) - line_829 - 1);
  EXPECT_EQ(row.substr(row.size() - 4), ",0,1") << row;   // 829 closes the loop on frame 0, agreeing
  EXPECT_EQ(row.substr(0, 14), "829,86.146690,") << row;  // its stamp from times_06.txt
  EXPECT_FALSE(fs::exists(path("out/trajectory.kml")));   // no --geo
}

TEST_F(TrajectoryToolTest, KmlFromGeographicPositions)
{
  std::ofstream(path("geo.csv")) << "frame,stamp,latitude,longitude,altitude\n"
                                    "0,0.0,36.8381,-2.4597,12\n1,1.0,36.8385,-2.4597,12\n"
                                    "2,2.0,36.8385,-2.4590,12\n3,3.0,36.8381,-2.4590,12\n"
                                    "4,4.0,36.83811,-2.45969,12\n";
  std::ofstream(path("loops.txt")) << "4 0\n3 1\n";
  std::ofstream(path("truth.txt")) << "4 0\n";
  const ToolRun r = run("--geo " + path("geo.csv") + " --loops " + path("loops.txt") + " --pairs " + path("truth.txt") +
                        " --output " + path("out"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(path("out/trajectory.png")));  // no --poses
  const std::string command = std::string(PYTHON3_EXECUTABLE) + " '" + OPENABLE_SOURCE_DIR +
                              "/test/core/check_kml.py' '" + path("out/trajectory.kml") + "' 5 2 1 >'" +
                              path("check.log") + "' 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << readText(path("check.log"));
}

TEST_F(TrajectoryToolTest, BadInputGivesOneLineReason)
{
  std::ofstream(path("far.txt")) << "5000 3\n";
  const struct
  {
    std::string args;
    int status;
    std::string reason;
  } cases[] = {
      {"", 2, ""},
      {"--poses " + kPoses + " --output " + path("o"), 2, "--loops and --output are required"},
      {"--loops " + kTruth + " --output " + path("o"), 2, "--poses"},
      {"--poses " + kPoses + " --loops " + kTruth + " --output " + path("o") + " --pairs " + kTruth + " --distance 5",
       2, "not both"},
      {"--poses " + kPoses + " --loops /nonexistent.csv --output " + path("o"), 1, "/nonexistent.csv"},
      {"--poses " + kPoses + " --loops " + path("far.txt") + " --output " + path("o"), 1, "frame 5000"},
      {"--poses " + kPoses + " --loops " + kTruth + " --output " + path("o") + " --size 10x10", 2, "--size"},
  };
  for (const auto& c : cases)
  {
    const ToolRun r = run(c.args);
    EXPECT_EQ(r.status, c.status) << c.args << "\n" << r.err;
    if (!c.reason.empty())
    {
      EXPECT_NE(r.err.find(c.reason), std::string::npos) << c.args << "\n" << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
  }
}

TEST_F(TrajectoryToolTest, AFolderAsLoopsOrBadTimesLeaveNoSummaryAndNoOutput)
{
  // Issue 22: an (empty) output folder given as --loops was read as 0 loops; a bad --times failed after the
  // summary was printed. Every input is now read first.
  fs::create_directories(path("empty_run"));
  ToolRun r = run("--poses " + kPoses + " --loops " + path("empty_run") + " --output " + path("o"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("is a folder; expected a file (loop_closures.csv"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  std::ofstream(path("times.txt")) << "0.0\nnot a time\n";
  r = run("--poses " + kPoses + " --loops " + kTruth + " --times " + path("times.txt") + " --output " + path("o"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("is not one time in seconds"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(path("o/trajectory.png")));
}
