// Checker for ~map_mode continue against the mono nodelet: a map of one session ("day", written here with
// the core) loaded as the base of a new session "night"; the night's frames close loops with the day's;
// ~save_map writes both sessions; a map already holding "night" is refused with the state kept; ~reset
// returns to a fresh map.
#include <gtest/gtest.h>
#include <openable_ros/LoadMap.h>
#include <openable_ros/LoopClosure.h>
#include <openable_ros/SaveMap.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <cstdio>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/map/session_map.h"
#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;

namespace
{
cv::Mat dayImage(int index)
{
  char path[1024];
  std::snprintf(path, sizeof(path), "%s/../shared/data/gardens_point/day_right/Image%03d.jpg", OPENABLE_SOURCE_DIR,
                index);
  return cv::imread(path, cv::IMREAD_COLOR);
}

std::string tempMap(const std::string& name)
{
  return "/tmp/openable_sessions_" + std::to_string(getpid()) + "_" + name + ".map";
}

/// A map of one session "day": day_right frames [0, count), described as the nodelet describes
/// (the paper's configuration, as the launch file loads it; only matching keys differ there).
void writeDayMap(const std::string& path, int count)
{
  const openable::Config config = openable::Config::paper();
  openable::FrameDescriber describer(config);
  openable::SessionMap map(describer.layout(), config.toYaml());
  const uint32_t day = map.addSession({"day", "robot_a", 0.0});
  for (int i = 0; i < count; ++i)
  {
    openable::FrameInfo info;
    info.stamp = 10.0 + i;
    map.add(day, describer.describeImage(dayImage(i)), info);
  }
  map.save(path);
}
}  // namespace

TEST(DetectorSessions, ContinueSaveRefuseAndReset)
{
  ros::NodeHandle nh;
  DiagnosticsWatcher diagnostics(nh);
  std::mutex mutex;
  std::vector<openable_ros::LoopClosureConstPtr> loops;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("image", 50);
  ros::Subscriber loop_sub = nh.subscribe<openable_ros::LoopClosure>(
      "loop_closures", 1000,
      [&](const openable_ros::LoopClosureConstPtr& msg)
      {
        std::lock_guard<std::mutex> lock(mutex);
        loops.push_back(msg);
      });
  ASSERT_TRUE(waitFor([&] { return image_pub.getNumSubscribers() > 0 && loop_sub.getNumPublishers() > 0; }, 30.0));
  ASSERT_TRUE(ros::service::waitForService("mono_detector/load_map", ros::Duration(30.0)));
  ros::ServiceClient save = nh.serviceClient<openable_ros::SaveMap>("mono_detector/save_map");
  ros::ServiceClient load = nh.serviceClient<openable_ros::LoadMap>("mono_detector/load_map");
  ros::ServiceClient reset = nh.serviceClient<std_srvs::Trigger>("mono_detector/reset");

  const std::string day_map = tempMap("day");
  writeDayMap(day_map, 40);
  openable_ros::LoadMap load_request;
  load_request.request.path = day_map;
  ASSERT_TRUE(load.call(load_request));
  ASSERT_TRUE(load_request.response.success) << load_request.response.message;
  EXPECT_NE(load_request.response.message.find("continuing it as session 'night'"), std::string::npos)
      << load_request.response.message;

  // The night run: the day's places 0..29 again. Continuing, the frames are stored (the history grows
  // from the map's 40) and close loops with the day's session.
  for (int i = 0; i < 30; ++i)
  {
    image_pub.publish(openable_ros_test::toMsg(dayImage(i), "bgr8", ros::Time(100.0 + i)));
    ros::WallDuration(0.02).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("history size") == 70; }, 20.0))
      << "history size " << diagnostics.number("history size");
  {
    std::lock_guard<std::mutex> lock(mutex);
    ASSERT_GE(loops.size(), 20u);
    for (const auto& loop : loops)
    {
      EXPECT_EQ(loop->query_session, 1u);
      EXPECT_EQ(loop->match_session, 0u);
      const long night_frame = long(loop->header.stamp.toSec() - 100.0 + 0.5);
      EXPECT_LE(std::labs(night_frame - long(loop->match_id)), 2) << night_frame << " -> " << loop->match_id;
    }
  }

  // ~save_map writes both sessions.
  const std::string both = tempMap("both");
  openable_ros::SaveMap save_request;
  save_request.request.path = both;
  ASSERT_TRUE(save.call(save_request));
  ASSERT_TRUE(save_request.response.success) << save_request.response.message;
  EXPECT_EQ(save_request.response.frames, 70u);
  {
    const openable::SessionMap saved = openable::SessionMap::load(both);
    ASSERT_EQ(saved.sessionCount(), 2u);
    EXPECT_EQ(saved.session(0).name, "day");
    EXPECT_EQ(saved.session(1).name, "night");
    EXPECT_EQ(saved.session(1).robot, "robot_b");
    EXPECT_EQ(saved.frames(1).size(), 30u);
  }

  // A map that already holds "night" cannot be continued as "night": refused, the state kept.
  load_request.request.path = both;
  ASSERT_TRUE(load.call(load_request));
  EXPECT_FALSE(load_request.response.success);
  EXPECT_NE(load_request.response.message.find("'night' is already in the map"), std::string::npos)
      << load_request.response.message;
  ros::WallDuration(0.5).sleep();  // two diagnostics periods: a changed history would show
  EXPECT_EQ(diagnostics.number("history size"), 70);

  // ~reset: a fresh map, loop-closure mode, nothing of the day left.
  std_srvs::Trigger trigger;
  ASSERT_TRUE(reset.call(trigger));
  EXPECT_NE(trigger.response.message.find("fresh map"), std::string::npos) << trigger.response.message;
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("history size") == 0; }, 10.0));
  EXPECT_EQ(diagnostics.value("mode").find("loop closure"), 0u) << diagnostics.value("mode");
  std::remove(day_map.c_str());
  std::remove(both.c_str());
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_detector_sessions");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
