// Checkers for detector paths no other rostest covers; each .test runs one of them (--gtest_filter):
// - stereo_approximate_sync.test: ~approximate_sync with the right stamps jittered by up to 9 ms around the
//   left ones (as two free-running cameras give): one history entry per pair, none rejected.
// - keyframe_angle.test: ~keyframe_angle 0.5 rad with the camera turning on the spot 0.12 rad per frame: a
//   keyframe every 5th frame; standing still or moving without turning (~keyframe_distance off) adds none.
// - rolling_window.test: ~matrix_mode rolling_window keeps one row per frame for the last ~matrix_size
//   frames (the whole_history detector beside it pools rows instead), oldest row on top.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
cv::Mat gardensPoint(const std::string& dir, int index)
{
  char path[1024];
  std::snprintf(path, sizeof(path), "%s/day_right/Image%03d.jpg", dir.c_str(), index);
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty()) << path;
  return image;
}

/// Keeps the last image of a topic (the distance_matrix pictures).
class LastImage
{
public:
  LastImage(ros::NodeHandle& nh, const std::string& topic)
  {
    sub_ = nh.subscribe(topic, 10, &LastImage::callback, this);
  }
  sensor_msgs::ImageConstPtr get()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_;
  }
  ros::Subscriber& subscriber()
  {
    return sub_;
  }

private:
  void callback(const sensor_msgs::ImageConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_ = msg;
  }
  ros::Subscriber sub_;
  std::mutex mutex_;
  sensor_msgs::ImageConstPtr last_;
};
}  // namespace

TEST(DetectorPaths, ApproximateSyncPairsJitteredStereoStamps)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir =
      pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/stereo/euroc_v101_micro");
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher left_pub = nh.advertise<sensor_msgs::Image>("left/image_rect", 50);
  ros::Publisher right_pub = nh.advertise<sensor_msgs::Image>("right/image_rect", 50);
  ASSERT_TRUE(waitFor([&] { return left_pub.getNumSubscribers() > 0 && right_pub.getNumSubscribers() > 0; }, 30.0));

  std::ifstream csv(dir + "/cam0/data.csv");
  ASSERT_TRUE(csv.good()) << dir;
  std::vector<std::string> files;
  for (std::string line; std::getline(csv, line);)
  {
    if (!line.empty() && line[0] != '#')
    {
      std::string file = line.substr(line.find(',') + 1);
      while (!file.empty() && (file.back() == '\r' || file.back() == ' '))
      {
        file.pop_back();
      }
      files.push_back(file);
    }
  }
  ASSERT_EQ(files.size(), 40u);
  // Left every 50 ms; right within +-9 ms of it (never identical), sometimes sent first.
  std::mt19937 random(13);
  std::uniform_int_distribution<int> jitter_ms(1, 9);
  ros::Time left_stamp(2000.0);
  int identical = 0;
  for (size_t i = 0; i < files.size(); ++i)
  {
    left_stamp += ros::Duration(0.05);
    const int sign = (random() % 2) ? 1 : -1;
    const ros::Time right_stamp = left_stamp + ros::Duration(sign * jitter_ms(random) * 1e-3);
    identical += right_stamp == left_stamp ? 1 : 0;
    const auto left = openable_ros_test::toMsg(cv::imread(dir + "/cam0/data/" + files[i], cv::IMREAD_GRAYSCALE),
                                               enc::MONO8, left_stamp, "cam0");
    const auto right = openable_ros_test::toMsg(cv::imread(dir + "/cam1/data/" + files[i], cv::IMREAD_GRAYSCALE),
                                                enc::MONO8, right_stamp, "cam1");
    if (i % 3 == 0)
    {
      right_pub.publish(right);
      left_pub.publish(left);
    }
    else
    {
      left_pub.publish(left);
      right_pub.publish(right);
    }
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_EQ(identical, 0);
  // ApproximateTime holds the newest set back until a later message proves it best: the last pair may
  // wait for more. 39 or 40 pairs stored, each of its own left and right image.
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("history size") >= 39; }, 30.0))
      << "history size " << diagnostics.value("history size") << " after 40 jittered pairs";
  ros::WallDuration(0.5).sleep();
  EXPECT_LE(diagnostics.number("history size"), 40);
  EXPECT_EQ(diagnostics.number("frames rejected"), 0);
  EXPECT_EQ(diagnostics.number("frames received"), diagnostics.number("history size"));
}

TEST(DetectorPaths, KeyframeAngleStoresAFrameEveryHalfRadianOfTurn)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  DiagnosticsWatcher diagnostics(nh);
  tf2_ros::TransformBroadcaster broadcaster;
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 30.0));

  ros::Time stamp(500.0);
  int published = 0;
  auto send = [&](int image_index, double x, double yaw)
  {
    stamp += ros::Duration(0.1);
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = "odom";
    t.child_frame_id = "camera";
    t.transform.translation.x = x;
    tf2::Quaternion q;
    q.setRPY(0.0, 0.0, yaw);
    t.transform.rotation.x = q.x();
    t.transform.rotation.y = q.y();
    t.transform.rotation.z = q.z();
    t.transform.rotation.w = q.w();
    broadcaster.sendTransform(t);
    ros::WallDuration(0.03).sleep();
    pub.publish(openable_ros_test::toMsg(gardensPoint(dir, image_index), enc::BGR8, stamp, "camera"));
    ++published;
    ros::WallDuration(0.03).sleep();
  };
  // Turning on the spot, 0.12 rad per frame: 0.48 rad after 4 frames is not enough, 0.60 after 5 is. So
  // frames 0, 5, 10, ..., 25 of 30 are keyframes (the first frame always is).
  for (int i = 0; i < 30; ++i)
  {
    send(i, 0.0, 0.12 * i);
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == published; }, 20.0));
  EXPECT_EQ(diagnostics.number("frames stored"), 6);
  EXPECT_EQ(diagnostics.number("frames skipped (not a keyframe)"), 24);
  // Standing still, then driving 20 m straight on without turning: ~keyframe_distance is 0 (off), so no
  // keyframe; only turning counts.
  const double heading = 0.12 * 29;
  for (int i = 0; i < 5; ++i)
  {
    send(30 + i, 0.0, heading);
  }
  for (int i = 0; i < 20; ++i)
  {
    send(35 + i, 1.0 * (i + 1), heading);
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == published; }, 20.0));
  EXPECT_EQ(diagnostics.number("frames stored"), 6);
  // Turning back the other way counts the same: keyframe 25 was at 3.0 rad; 0.6 rad back is a keyframe.
  send(60, 20.0, 3.0 - 0.6);
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == published; }, 20.0));
  EXPECT_EQ(diagnostics.number("frames stored"), 7);
}

TEST(DetectorPaths, RollingWindowKeepsOneRowPerFrameOfTheLastMatrixSizeFrames)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  const int size = pnh.param("matrix_size", 16);
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  LastImage rolling(nh, "rolling/distance_matrix");
  LastImage whole(nh, "whole/distance_matrix");
  ASSERT_TRUE(waitFor(
      [&]
      {
        // Both nodelets live in one manager: one subscriber connection for both.
        return pub.getNumSubscribers() > 0 && rolling.subscriber().getNumPublishers() > 0 &&
               whole.subscriber().getNumPublishers() > 0;
      },
      30.0));
  ros::WallDuration(1.0).sleep();  // the second nodelet's own subscription may follow the first one's
  const int frames = 40;
  ros::Time stamp(700.0);
  for (int i = 0; i < frames; ++i)
  {
    stamp += ros::Duration(0.1);
    pub.publish(openable_ros_test::toMsg(gardensPoint(dir, i), enc::BGR8, stamp, "camera"));
    // Slower than ~matrix_rate: every frame gets its picture.
    ros::WallDuration(0.1).sleep();
  }
  const auto latest = [&](LastImage& view) { return view.get() && view.get()->header.stamp == stamp; };
  ASSERT_TRUE(waitFor([&] { return latest(rolling) && latest(whole); }, 20.0)) << "no picture of the last frame";

  const cv::Mat window = cv_bridge::toCvCopy(rolling.get(), enc::BGR8)->image;
  const cv::Mat history = cv_bridge::toCvCopy(whole.get(), enc::BGR8)->image;
  std::printf("rolling_window %dx%d, whole_history %dx%d after %d frames\n", window.cols, window.rows, history.cols,
              history.rows, frames);
  // 40 frames do not fit 16 rows: the rolling window shows the last 16, one row each; the whole history
  // pools rows (4 frames per row -> 10 rows). Columns (the references) are pooled alike in both.
  EXPECT_EQ(window.rows, size);
  EXPECT_LT(history.rows, size);
  EXPECT_LE(window.cols, size);
  EXPECT_EQ(window.cols, history.cols);
  // Oldest shown row on top: frame 24 did not know the references after it (unknown: black on the right);
  // the newest row (frame 39) knows them all.
  const auto black = [](const cv::Vec3b& p) { return p == cv::Vec3b(0, 0, 0); };
  EXPECT_TRUE(black(window.at<cv::Vec3b>(0, window.cols - 1))) << window.at<cv::Vec3b>(0, window.cols - 1);
  int black_in_last_row = 0;
  for (int c = 0; c < window.cols; ++c)
  {
    black_in_last_row += black(window.at<cv::Vec3b>(window.rows - 1, c)) ? 1 : 0;
  }
  EXPECT_EQ(black_in_last_row, 0);

  // More frames: the window scrolls (still 16 rows), the whole history grows.
  for (int i = frames; i < frames + 8; ++i)
  {
    stamp += ros::Duration(0.1);
    pub.publish(openable_ros_test::toMsg(gardensPoint(dir, i), enc::BGR8, stamp, "camera"));
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return latest(rolling) && latest(whole); }, 20.0));
  EXPECT_EQ(cv_bridge::toCvCopy(rolling.get(), enc::BGR8)->image.rows, size);
  EXPECT_GT(cv_bridge::toCvCopy(whole.get(), enc::BGR8)->image.rows, history.rows);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_detector_paths");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
