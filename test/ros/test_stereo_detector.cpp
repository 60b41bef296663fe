// Checker for the stereo detector: the 40 real EuRoC V1_01 pairs through ExactTime give one history entry
// per pair; a pair whose right image has another size is rejected with a warning and the node stays up.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;

namespace
{
std::mutex log_mutex;
std::vector<std::string> warnings;

void logCallback(const rosgraph_msgs::LogConstPtr& msg)
{
  if (msg->level >= rosgraph_msgs::Log::WARN)
  {
    std::lock_guard<std::mutex> lock(log_mutex);
    warnings.push_back(msg->msg);
  }
}

bool warned(const std::string& a, const std::string& b)
{
  std::lock_guard<std::mutex> lock(log_mutex);
  for (const auto& w : warnings)
  {
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos)
    {
      return true;
    }
  }
  return false;
}
}  // namespace
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

TEST(StereoDetector, EveryExactPairIsOneHistoryEntryAndMismatchedPairsAreRejected)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir =
      pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/stereo/euroc_v101_micro");
  DiagnosticsWatcher diagnostics(nh);
  ros::Subscriber log_sub = nh.subscribe("/rosout", 100, logCallback);
  ros::Publisher left_pub = nh.advertise<sensor_msgs::Image>("left/image_rect", 50);
  ros::Publisher right_pub = nh.advertise<sensor_msgs::Image>("right/image_rect", 50);
  ASSERT_TRUE(waitFor([&] { return left_pub.getNumSubscribers() > 0 && right_pub.getNumSubscribers() > 0; }, 30.0))
      << "the detector did not subscribe to left/image_rect and right/image_rect within 30 s";

  // cam0/data.csv: "stamp_ns,file"; cam1 has the same stamps (synchronised cameras).
  std::ifstream csv(dir + "/cam0/data.csv");
  ASSERT_TRUE(csv.good()) << "cannot read " << dir << "/cam0/data.csv";
  std::vector<std::pair<ros::Time, std::string>> frames;
  std::string line;
  while (std::getline(csv, line))
  {
    if (line.empty() || line[0] == '#')
    {
      continue;
    }
    const size_t comma = line.find(',');
    ros::Time stamp;
    stamp.fromNSec(std::stoull(line.substr(0, comma)));
    std::string file = line.substr(comma + 1);
    while (!file.empty() && (file.back() == '\r' || file.back() == ' '))
    {
      file.pop_back();
    }
    frames.emplace_back(stamp, file);
  }
  ASSERT_EQ(frames.size(), 40u);

  ros::WallRate rate(20.0);
  for (const auto& frame : frames)
  {
    const cv::Mat left = cv::imread(dir + "/cam0/data/" + frame.second, cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(dir + "/cam1/data/" + frame.second, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(left.empty() || right.empty()) << frame.second;
    left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, frame.first, "cam0"));
    right_pub.publish(openable_ros_test::toMsg(right, enc::MONO8, frame.first, "cam1"));
    rate.sleep();
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("history size") == 40; }, 30.0))
      << "history size " << diagnostics.value("history size") << " after 40 exact pairs";
  EXPECT_EQ(diagnostics.number("frames received"), 40);
  EXPECT_EQ(diagnostics.number("frames rejected"), 0);

  // A pair whose right image has another size: rejected, named, nothing stored.
  const ros::Time later = frames.back().first + ros::Duration(0.05);
  const cv::Mat left = cv::imread(dir + "/cam0/data/" + frames[0].second, cv::IMREAD_GRAYSCALE);
  cv::Mat small;
  cv::resize(cv::imread(dir + "/cam1/data/" + frames[0].second, cv::IMREAD_GRAYSCALE), small, cv::Size(376, 240));
  left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, later, "cam0"));
  right_pub.publish(openable_ros_test::toMsg(small, enc::MONO8, later, "cam1"));
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("rejected: left/right mismatch") == 1; }, 10.0));
  EXPECT_EQ(diagnostics.number("history size"), 40);

  // The node stays up: the next good pair is stored.
  const ros::Time next = later + ros::Duration(0.05);
  left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, next, "cam0"));
  right_pub.publish(openable_ros_test::toMsg(cv::imread(dir + "/cam1/data/" + frames[0].second, cv::IMREAD_GRAYSCALE),
                                             enc::MONO8, next, "cam1"));
  EXPECT_TRUE(waitFor([&] { return diagnostics.number("history size") == 41; }, 10.0));
  // Pairs were described with D-LDB (disparity from SGBM): the describe latency is reported.
  EXPECT_GT(std::stod(diagnostics.value("describe latency mean (ms)")), 0.0);
  EXPECT_TRUE(warned("/left/image_rect' is 752x480", "/right/image_rect' is 376x240"))
      << "the size mismatch was not named";

  // Only left images (the right camera died): after ~sync_warning_timeout a warning names both topics.
  ros::Time alone = next;
  for (int i = 0; i < 5; ++i)
  {
    alone += ros::Duration(0.05);
    left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, alone, "cam0"));
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_TRUE(waitFor([&] { return warned("'/left/image_rect' 5, '/right/image_rect' 0", "~approximate_sync"); }, 10.0))
      << "no warning naming the topics after ~sync_warning_timeout without a pair";
  EXPECT_EQ(diagnostics.number("history size"), 41);

  // A stamp before the previous one with ~reset_on_time_jump (the .test sets it): a new history.
  const ros::Time restart = frames.front().first;
  left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, restart, "cam0"));
  right_pub.publish(openable_ros_test::toMsg(cv::imread(dir + "/cam1/data/" + frames[0].second, cv::IMREAD_GRAYSCALE),
                                             enc::MONO8, restart, "cam1"));
  EXPECT_TRUE(waitFor([&] { return diagnostics.number("history size") == 1; }, 10.0))
      << "history size " << diagnostics.value("history size") << " after a time jump with ~reset_on_time_jump";
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_stereo_detector");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
