// Checker for the stereo pipeline users already run: raw EuRoC V1_01 pairs with their camera_info go into
// Debian's stereo_image_proc (rectification and block-matching disparity); its `disparity` and
// `left/image_rect` go into the StereoDetector nodelet with ~use_disparity. Asserted: stereo_image_proc
// publishes a stereo_msgs/DisparityImage per pair, the detector stores one history entry per pair, and the
// D-LDB best matches of the two revisits of euroc_v101_revisits are their real places.
//
// The stream: 5 pairs of euroc_v101_micro (the MAV at its start, a distractor place), then the revisit
// pairs in the order 1, 2, 0, 3 with stamps 0.5 s apart (made up: the real ones put pair 0 right after
// pair 1, where any best match would be trivially right). Pair 0 revisits the place of pair 1 ~98 s later;
// pair 3 is 0.5 s from pair 2. So the query 0 chooses among 6 frames, the query 3 among 7.
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <stereo_msgs/DisparityImage.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

#include "euroc_camera_info.h"
#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
std::mutex mutex;
std::vector<openable_ros::LoopClosureConstPtr> loops;
std::vector<stereo_msgs::DisparityImageConstPtr> disparities;

void loopCallback(const openable_ros::LoopClosureConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex);
  loops.push_back(msg);
}

void disparityCallback(const stereo_msgs::DisparityImageConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex);
  disparities.push_back(msg);
}

struct Pair
{
  std::string left, right, name;
};

/// Every `step`-th pair of the micro set (EuRoC layout: cam0/data.csv with "stamp_ns,file").
std::vector<Pair> microPairs(const std::string& dir, size_t count, size_t step)
{
  std::vector<Pair> pairs;
  std::ifstream csv(dir + "/cam0/data.csv");
  std::string line;
  for (size_t index = 0; std::getline(csv, line) && pairs.size() < count;)
  {
    if (line.empty() || line[0] == '#')
    {
      continue;
    }
    std::string file = line.substr(line.find(',') + 1);
    while (!file.empty() && (file.back() == '\r' || file.back() == ' '))
    {
      file.pop_back();
    }
    if (index++ % step == 0)
    {
      pairs.push_back({dir + "/cam0/data/" + file, dir + "/cam1/data/" + file, "micro " + file});
    }
  }
  return pairs;
}
}  // namespace

TEST(StereoImageProc, DisparityOfStereoImageProcFeedsTheDetector)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string stereo = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/stereo");
  const std::string revisits = stereo + "/euroc_v101_revisits";
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher left_pub = nh.advertise<sensor_msgs::Image>("stereo/left/image_raw", 20);
  ros::Publisher right_pub = nh.advertise<sensor_msgs::Image>("stereo/right/image_raw", 20);
  ros::Publisher left_info_pub = nh.advertise<sensor_msgs::CameraInfo>("stereo/left/camera_info", 20);
  ros::Publisher right_info_pub = nh.advertise<sensor_msgs::CameraInfo>("stereo/right/camera_info", 20);
  ros::Subscriber loop_sub = nh.subscribe("loop_closures", 100, loopCallback);
  ros::Subscriber disparity_sub = nh.subscribe("stereo/disparity", 100, disparityCallback);
  // stereo_image_proc subscribes to its inputs only once its outputs have subscribers (the detector's).
  ASSERT_TRUE(waitFor(
      [&]
      {
        return left_pub.getNumSubscribers() > 0 && right_pub.getNumSubscribers() > 0 &&
               left_info_pub.getNumSubscribers() > 0 && right_info_pub.getNumSubscribers() > 0 &&
               loop_sub.getNumPublishers() > 0 && disparity_sub.getNumPublishers() > 0;
      },
      30.0))
      << "stereo_image_proc did not subscribe to stereo/{left,right}/{image_raw,camera_info} within 30 s";
  // The internal nodelet chain (debayer -> rectify -> disparity) connects in steps: give it a moment.
  ros::WallDuration(1.0).sleep();

  const cv::Size size(752, 480);
  const auto infos =
      openable_ros_test::eurocStereoInfo(openable_ros_test::loadEurocCamera(revisits + "/sensorLeft.yaml"),
                                         openable_ros_test::loadEurocCamera(revisits + "/sensorRight.yaml"), size);

  std::vector<Pair> stream = microPairs(stereo + "/euroc_v101_micro", 5, 8);
  ASSERT_EQ(stream.size(), 5u);
  for (int k : {1, 2, 0, 3})
  {
    const std::string id = std::to_string(k);
    stream.push_back({revisits + "/left_img_" + id + ".png", revisits + "/right_img_" + id + ".png", "revisit " + id});
  }
  std::vector<ros::Time> stamps;
  ros::Time stamp(1000.0);
  for (const Pair& pair : stream)
  {
    const cv::Mat left = cv::imread(pair.left, cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(pair.right, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(left.empty() || right.empty()) << pair.name;
    ASSERT_EQ(left.size(), size) << pair.name;
    stamp += ros::Duration(0.5);
    stamps.push_back(stamp);
    sensor_msgs::CameraInfo left_info = infos[0], right_info = infos[1];
    left_info.header.stamp = right_info.header.stamp = stamp;
    // One frame for both cameras, as camera drivers of a stereo rig do: stereo_image_proc asserts it (the
    // right camera's offset is in its P).
    left_info.header.frame_id = right_info.header.frame_id = "stereo_optical";
    left_info_pub.publish(left_info);
    right_info_pub.publish(right_info);
    left_pub.publish(openable_ros_test::toMsg(left, enc::MONO8, stamp, "stereo_optical"));
    right_pub.publish(openable_ros_test::toMsg(right, enc::MONO8, stamp, "stereo_optical"));
    // One pair at a time through block matching and D-LDB (each well under this on one core).
    ros::WallDuration(0.5).sleep();
  }
  const long pairs = long(stream.size());
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("history size") == pairs; }, 30.0))
      << "history size " << diagnostics.value("history size") << " after " << pairs << " pairs";
  EXPECT_EQ(diagnostics.number("frames received"), pairs);
  EXPECT_EQ(diagnostics.number("frames rejected"), 0);
  ASSERT_TRUE(waitFor(
      [&]
      {
        std::lock_guard<std::mutex> lock(mutex);
        return long(disparities.size()) == pairs && diagnostics.number("loop closures") == long(loops.size()) &&
               long(loops.size()) == pairs - 1;
      },
      10.0))
      << disparities.size() << " disparity images and " << loops.size() << " loop closures for " << pairs << " pairs";

  std::lock_guard<std::mutex> lock(mutex);
  for (const auto& d : disparities)
  {
    EXPECT_EQ(d->image.encoding, enc::TYPE_32FC1);
    EXPECT_EQ(d->image.width, 752u);
    EXPECT_GT(d->f, 400.0);
    EXPECT_NEAR(d->T, 0.11, 0.01);  // the EuRoC baseline, from the right P
  }
  // Every frame after the first has a best match (threshold 1, no exclusion): the revisits must match
  // their own places.
  auto matchOf = [&](size_t index) -> ros::Time
  {
    for (const auto& loop : loops)
    {
      if (loop->header.stamp == stamps[index])
      {
        return loop->match_stamp;
      }
    }
    return ros::Time();
  };
  auto nameOf = [&](const ros::Time& t) -> std::string
  {
    for (size_t i = 0; i < stamps.size(); ++i)
    {
      if (stamps[i] == t)
      {
        return stream[i].name;
      }
    }
    return "none";
  };
  for (const auto& loop : loops)
  {
    std::printf("stereo_image_proc -> D-LDB: %s best matches %s, distance %.3f\n", nameOf(loop->header.stamp).c_str(),
                nameOf(loop->match_stamp).c_str(), loop->distance);
    // Quoted in doc/ros_api.md (e.g. distance.revisit_0); test/docs/check_doc_numbers.py compares.
    std::string query_name = nameOf(loop->header.stamp);
    std::replace(query_name.begin(), query_name.end(), ' ', '_');
    RecordProperty("distance." + query_name, std::to_string(loop->distance));
  }
  EXPECT_EQ(nameOf(matchOf(7)), "revisit 1") << "pair 0 (a revisit 98 s later) did not find the place of pair 1";
  EXPECT_EQ(nameOf(matchOf(8)), "revisit 2") << "pair 3 did not find the place of pair 2";
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_stereo_image_proc");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
