// Checkers for detector paths no other rostest covers; each .test runs one of them (--gtest_filter):
// - stereo_approximate_sync.test: ~approximate_sync with the right stamps jittered by up to 9 ms around the
//   left ones (as two free-running cameras give): one history entry per pair, none rejected.
// - keyframe_angle.test: ~keyframe_angle 0.5 rad with the camera turning on the spot 0.12 rad per frame: a
//   keyframe every 5th frame; standing still or moving without turning (~keyframe_distance off) adds none.
// - queue_drops.test: a burst of 201 small frames into ~queue_size 1: every frame is either received or
//   counted in "frames dropped (queue)" (from header.seq gaps), and some are dropped.
// - navsat_fix.test: ~fix (sensor_msgs/NavSatFix): each stored frame keeps the fix nearest its stamp within
//   ~fix_tolerance, written to ~geo_file, which the KML export reads.
// - sim_time_guard.test: replay.launch's sim_time_guard deletes /use_sim_time when roslaunch stops it.
// - rolling_window.test: ~matrix_mode rolling_window keeps one row per frame for the last ~matrix_size
//   frames (the whole_history detector beside it pools rows instead), oldest row on top.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <tf2/LinearMath/Quaternion.h>
#include <sensor_msgs/NavSatFix.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <sys/wait.h>
#include <unistd.h>
#include <opencv2/imgproc.hpp>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "openable/view/trajectory_export.h"
#include "test_helpers.h"
#include "tf_sender.h"

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
  openable_ros_test::TfSender tf(nh);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 30.0));
  ASSERT_TRUE(tf.waitForListener(30.0)) << "the detector's tf listener did not connect within 30 s";

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
    tf.send(t);
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
  // Both pictures are always matrix_size x matrix_size pixels, however the history grows or is pooled (they
  // used to take the shape of the cells, so rviz re-laid out its panel on every publish).
  EXPECT_EQ(window.size(), cv::Size(size, size));
  EXPECT_EQ(history.size(), cv::Size(size, size));
  // 40 frames do not fit 16 rows: the rolling window shows the last 16, one row each (scale 1: a pixel row
  // per frame), the references pooled into fewer columns, black beyond them. The newest row (frame 39)
  // knows every reference: its used columns are the non-black ones, from the left.
  const auto black = [](const cv::Vec3b& p) { return p == cv::Vec3b(0, 0, 0); };
  int used = 0;
  while (used < window.cols && !black(window.at<cv::Vec3b>(window.rows - 1, used)))
  {
    ++used;
  }
  EXPECT_GT(used, 2);
  EXPECT_LT(used, size);
  for (int c = used; c < window.cols; ++c)
  {
    EXPECT_TRUE(black(window.at<cv::Vec3b>(window.rows - 1, c))) << "column " << c;
  }
  // Oldest shown row on top: frame 24 did not know the references after it (unknown: black on the right of
  // the used columns), and knew the first ones.
  EXPECT_TRUE(black(window.at<cv::Vec3b>(0, used - 1))) << window.at<cv::Vec3b>(0, used - 1);
  EXPECT_FALSE(black(window.at<cv::Vec3b>(0, 0))) << window.at<cv::Vec3b>(0, 0);

  // More frames: the window scrolls, the whole history grows; neither picture changes size.
  for (int i = frames; i < frames + 8; ++i)
  {
    stamp += ros::Duration(0.1);
    pub.publish(openable_ros_test::toMsg(gardensPoint(dir, i), enc::BGR8, stamp, "camera"));
    ros::WallDuration(0.1).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return latest(rolling) && latest(whole); }, 20.0));
  EXPECT_EQ(cv_bridge::toCvCopy(rolling.get(), enc::BGR8)->image.size(), cv::Size(size, size));
  EXPECT_EQ(cv_bridge::toCvCopy(whole.get(), enc::BGR8)->image.size(), cv::Size(size, size));
}

TEST(DetectorPaths, FramesDroppedInTheQueueAreCountedFromSeqGaps)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  DiagnosticsWatcher diagnostics(nh);
  // A deep publisher queue: what is lost, is lost in the detector's ~queue_size 1 subscriber queue.
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 1000);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 30.0));

  // Small frames, decoded before the burst, so they arrive far faster than the detector describes them.
  std::vector<sensor_msgs::ImagePtr> burst;
  ros::Time stamp(900.0);
  const int frames = 200;
  for (int i = 0; i <= frames; ++i)
  {
    cv::Mat small;
    cv::resize(gardensPoint(dir, i % 100), small, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
    stamp += ros::Duration(0.1);
    burst.push_back(openable_ros_test::toMsg(small, enc::BGR8, stamp, "camera"));
  }
  // The first frame alone: seq gaps can only be seen after a frame has arrived.
  pub.publish(burst[0]);
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == 1; }, 20.0));
  for (int i = 1; i <= frames; ++i)
  {
    pub.publish(burst[size_t(i)]);
  }
  // Every published frame is accounted for: received (the queue keeps the newest, so the last one always
  // arrives) or dropped.
  const auto accounted = [&]
  { return diagnostics.number("frames received") + diagnostics.number("frames dropped (queue)"); };
  EXPECT_TRUE(waitFor([&] { return accounted() == frames + 1; }, 30.0))
      << "received " << diagnostics.number("frames received") << " + dropped "
      << diagnostics.number("frames dropped (queue)") << ", published " << frames + 1;
  std::printf("burst of %d frames into ~queue_size 1: %ld received, %ld dropped (queue)\n", frames + 1,
              diagnostics.number("frames received"), diagnostics.number("frames dropped (queue)"));
  // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares (received and dropped vary by run).
  RecordProperty("sent", frames + 1);
  RecordProperty("accounted", std::to_string(accounted()));
  EXPECT_GT(diagnostics.number("frames dropped (queue)"), 0);
  EXPECT_LT(diagnostics.number("frames received"), frames + 1);
}

TEST(DetectorPaths, FramesDroppedFromASeq0BagAreCountedFromStamps)
{
  // Issue 23: a converted bag whose images all have seq 0, played by rosbag faster than the detector
  // (~queue_size 1) can keep up. seq says nothing, so the drops must come from the stamps (a 10 Hz camera).
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  DiagnosticsWatcher diagnostics(nh);
  const std::string bag_path = testing::TempDir() + "/openable_seq0_" + std::to_string(::getpid()) + ".bag";
  const int frames = 300;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    ros::Time record(100.0);
    for (int i = 0; i < frames; ++i)
    {
      cv::Mat small;
      cv::resize(gardensPoint(dir, i % 100), small, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
      auto msg = openable_ros_test::toMsg(small, enc::BGR8, ros::Time(900.0 + 0.1 * i), "camera");
      msg->header.seq = 0;
      // Recorded one by one for the first 30 frames (played at 100x: 10 ms apart, the detector keeps up),
      // then in a burst of 0.1 ms spacing (it cannot).
      record += ros::Duration(i < 30 ? 1.0 : 0.01);
      bag.write("/image", record, msg);
    }
  }
  const pid_t player = fork();
  if (player == 0)
  {
    execlp("rosbag", "rosbag", "play", "-q", "-r", "100", "--wait-for-subscribers", bag_path.c_str(),
           static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(player, 0);
  int status = 0;
  const bool played = waitFor([&] { return waitpid(player, &status, WNOHANG) == player; }, 90.0);
  if (!played)
  {
    kill(player, SIGKILL);
    waitpid(player, &status, 0);
  }
  std::remove(bag_path.c_str());
  ASSERT_TRUE(played) << "rosbag play did not finish within 90 s";
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "rosbag play failed";
  const auto accounted = [&]
  { return diagnostics.number("frames received") + diagnostics.number("frames dropped (queue)"); };
  EXPECT_TRUE(waitFor([&] { return accounted() == frames; }, 30.0))
      << "received " << diagnostics.number("frames received") << " + dropped "
      << diagnostics.number("frames dropped (queue)") << ", in the bag " << frames;
  std::printf("seq-0 bag of %d frames at 100x into ~queue_size 1: %ld received, %ld dropped (queue), worst "
              "diagnostics level %d\n",
              frames, diagnostics.number("frames received"), diagnostics.number("frames dropped (queue)"),
              diagnostics.worstLevel());
  // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares (received and dropped vary by run).
  RecordProperty("sent", frames);
  RecordProperty("accounted", std::to_string(accounted()));
  EXPECT_GT(diagnostics.number("frames dropped (queue)"), 0);
  EXPECT_GE(diagnostics.worstLevel(), int(diagnostic_msgs::DiagnosticStatus::WARN));
}

TEST(DetectorPaths, EachStoredFrameKeepsTheNearestFixForTheKml)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  const std::string geo_file = pnh.param<std::string>("geo_file", "");
  ASSERT_FALSE(geo_file.empty());
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher fix_pub = nh.advertise<sensor_msgs::NavSatFix>("fix", 100);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && fix_pub.getNumSubscribers() > 0; }, 30.0));

  // A hand-made walk: one fix a second, north-east by 0.001 degrees each; then a receiver without a fix.
  auto fix = [](double stamp, double latitude, double longitude, double altitude, int8_t status)
  {
    sensor_msgs::NavSatFix f;
    f.header.stamp = ros::Time(stamp);
    f.header.frame_id = "gps";
    f.status.status = status;
    f.latitude = latitude;
    f.longitude = longitude;
    f.altitude = altitude;
    return f;
  };
  for (int k = 0; k < 5; ++k)
  {
    fix_pub.publish(fix(1000.0 + k, 48.0 + 0.001 * k, 11.0 + 0.001 * k, 500.0 + k, sensor_msgs::NavSatStatus::STATUS_FIX));
  }
  fix_pub.publish(fix(1009.9, 10.0, 10.0, 0.0, sensor_msgs::NavSatStatus::STATUS_NO_FIX));  // ignored
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("fixes received") == 5; }, 20.0))
      << "fixes received: " << diagnostics.value("fixes received");

  // Frames (tolerance 0.5 s): 1000.1 -> fix 0, 1000.9 -> fix 1, 1002.2 -> fix 2, 1003.5 -> halfway, the later
  // fix 4, 1010.0 -> none within 0.5 s (the NO_FIX message does not count).
  const std::vector<double> stamps = {1000.1, 1000.9, 1002.2, 1003.5, 1010.0};
  for (size_t i = 0; i < stamps.size(); ++i)
  {
    pub.publish(openable_ros_test::toMsg(gardensPoint(dir, int(i)), enc::BGR8, ros::Time(stamps[i]), "camera"));
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == 5; }, 20.0));
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames with a fix") == 4; }, 10.0))
      << "frames with a fix: " << diagnostics.value("frames with a fix");

  // ~geo_file, read by the KML export's own reader.
  const std::map<int, openable::GeoPosition> positions = openable::loadGeoPositions(geo_file);
  ASSERT_EQ(positions.size(), 4u);
  const int first = positions.begin()->first;
  const std::vector<int> fix_of_frame = {0, 1, 2, 4};
  for (int f = 0; f < 4; ++f)
  {
    ASSERT_EQ(positions.count(first + f), 1u) << "frame " << first + f;
    const openable::GeoPosition& p = positions.at(first + f);
    const int k = fix_of_frame[size_t(f)];
    EXPECT_NEAR(p.latitude, 48.0 + 0.001 * k, 1e-9) << "frame " << f;
    EXPECT_NEAR(p.longitude, 11.0 + 0.001 * k, 1e-9) << "frame " << f;
    EXPECT_NEAR(p.altitude, 500.0 + k, 1e-3) << "frame " << f;
    EXPECT_NEAR(p.stamp, 1000.0 + k, 1e-6) << "frame " << f;
  }
  EXPECT_EQ(positions.count(first + 4), 0u) << "the frame without a fix within 0.5 s got one";

  // The KML of that path with one loop (frame 3 back to frame 0): the path and the loop's placemark.
  const std::string kml = openable::trajectoryKml(positions, {{first + 3, first, true}}, "navsat");
  size_t placemarks = 0;
  for (size_t at = kml.find("<Placemark>"); at != std::string::npos; at = kml.find("<Placemark>", at + 1))
  {
    ++placemarks;
  }
  EXPECT_EQ(placemarks, 2u) << kml;
  EXPECT_NE(kml.find("11.004000000,48.004000000"), std::string::npos) << kml;
}

TEST(DetectorPaths, SimTimeGuardDeletesUseSimTimeWhenStopped)
{
  // replay.launch's guard: started with /use_sim_time true, stopped as roslaunch stops nodes (SIGINT).
  ros::param::set("/use_sim_time", true);
  const pid_t guard = fork();
  ASSERT_GE(guard, 0);
  if (guard == 0)
  {
    execl(SIM_TIME_GUARD_BINARY, SIM_TIME_GUARD_BINARY, "__name:=sim_time_guard_under_test", static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto registered = []
  {
    std::vector<std::string> nodes;
    ros::master::getNodes(nodes);
    return std::find(nodes.begin(), nodes.end(), "/sim_time_guard_under_test") != nodes.end();
  };
  ASSERT_TRUE(waitFor(registered, 30.0)) << "sim_time_guard did not start";
  EXPECT_TRUE(ros::param::has("/use_sim_time")) << "deleted while the launch still runs";
  ASSERT_EQ(kill(guard, SIGINT), 0);
  int status = -1;
  ASSERT_TRUE(waitFor([&] { return waitpid(guard, &status, WNOHANG) == guard; }, 20.0)) << "did not stop on SIGINT";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_FALSE(ros::param::has("/use_sim_time")) << "/use_sim_time outlived the launch";
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
