// Checker for poses and keyframing against the mono nodelet with ~fixed_frame odom and
// ~keyframe_distance 1 m: poses come from tf at each image's stamp, a frame is stored only after the camera
// moved 1 m, standstill stores nothing, a frame whose transform is missing is kept without pose, and loop
// closures carry both camera poses.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdio>
#include <mutex>
#include <vector>

#include "test_helpers.h"
#include "tf_sender.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
std::mutex mutex;
std::vector<openable_ros::LoopClosureConstPtr> loops;
visualization_msgs::MarkerArrayConstPtr markers;

void loopCallback(const openable_ros::LoopClosureConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex);
  loops.push_back(msg);
}

void markersCallback(const visualization_msgs::MarkerArrayConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex);
  markers = msg;
}
}  // namespace

TEST(DetectorTf, PosesFromTfAndKeyframesByDistance)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  DiagnosticsWatcher diagnostics(nh);
  openable_ros_test::TfSender tf(nh);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  ros::Subscriber loop_sub = nh.subscribe("loop_closures", 100, loopCallback);
  ros::Subscriber marker_sub = nh.subscribe("loop_markers", 10, markersCallback);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && loop_sub.getNumPublishers() > 0; }, 30.0));
  ASSERT_TRUE(tf.waitForListener(30.0)) << "the detector's tf listener did not connect within 30 s";

  // The camera walks along x at 0.5 m per frame over images 0..39 (20 keyframes), stands still for 10
  // frames (no keyframe), then walks the same path again 5 m to the side (y = 5): the second walk revisits
  // the places of the first, so its keyframes close loops with poses 5 m apart.
  ros::Time stamp(500.0);
  int published = 0;
  auto send = [&](int image_index, double x, double y, const std::string& frame)
  {
    stamp += ros::Duration(0.1);
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = "odom";
    t.child_frame_id = "camera";
    t.transform.translation.x = x;
    t.transform.translation.y = y;
    t.transform.rotation.w = 1.0;
    tf.send(t);
    ros::WallDuration(0.03).sleep();
    char path[1024];
    std::snprintf(path, sizeof(path), "%s/day_right/Image%03d.jpg", dir.c_str(), image_index);
    const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty()) << path;
    pub.publish(openable_ros_test::toMsg(image, enc::BGR8, stamp, frame));
    ++published;
    ros::WallDuration(0.03).sleep();
  };
  for (int i = 0; i < 40; ++i)
  {
    send(i, 0.5 * i, 0.0, "camera");
  }
  for (int i = 0; i < 10; ++i)
  {
    send(39, 19.5, 0.0, "camera");
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == published; }, 20.0));
  EXPECT_EQ(diagnostics.number("frames stored"), 20);
  EXPECT_EQ(diagnostics.number("frames skipped (not a keyframe)"), 30);

  // A frame whose transform does not exist: kept, without pose.
  send(100, 0.0, 0.0, "no_such_frame");
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames stored") == 21; }, 10.0));

  for (int i = 0; i < 40; ++i)
  {
    send(i, 0.5 * i, 5.0, "camera");
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == published; }, 20.0));
  // The move of 5 m sideways makes the first frame of the second walk a keyframe too: 1 + 19 more.
  EXPECT_EQ(diagnostics.number("frames stored"), 41);
  ASSERT_TRUE(waitFor(
      [&]
      {
        std::lock_guard<std::mutex> lock(mutex);
        return !loops.empty() && diagnostics.number("loop closures") == long(loops.size());
      },
      10.0));
  std::lock_guard<std::mutex> lock(mutex);
  int with_poses = 0;
  for (const auto& loop : loops)
  {
    if (!loop->has_poses)
    {
      continue;
    }
    ++with_poses;
    // Same place, the other walk: same x (within the 2 frames tolerance, 1 m), 5 m apart in y.
    EXPECT_NEAR(loop->query_pose.position.y, 5.0, 1e-6);
    EXPECT_NEAR(loop->match_pose.position.y, 0.0, 1e-6);
    EXPECT_NEAR(loop->query_pose.position.x, loop->match_pose.position.x, 1.0 + 1e-6);
    EXPECT_NEAR(loop->query_pose.orientation.w, 1.0, 1e-9);
  }
  std::printf("tf: %zu loop closures, %d with poses\n", loops.size(), with_poses);
  EXPECT_GE(with_poses, 10);
  ASSERT_TRUE(waitFor(
      [&] {
        return markers && markers->markers.size() == 3 && markers->markers[1].points.size() >= 2 * size_t(with_poses);
      },
      10.0));
  EXPECT_EQ(markers->markers[0].header.frame_id, "odom");
  EXPECT_EQ(markers->markers[0].points.size(), 40u);  // trajectory: the 40 keyframes with a pose
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_detector_tf");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
