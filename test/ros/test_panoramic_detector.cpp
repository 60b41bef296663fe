// Checker for the panoramic detector: a route of 30 panoramic places, driven forward, then (after other
// places) driven back in the opposite direction. Driving back, the camera sees every place rotated by
// 180 degrees (its sub-panoramas circularly shifted by half the ring) and the places come in reverse order:
// the loop closures of the return trip must say direction -1, with the right place and a half-ring shift.
//
// Each panorama is 6 real Gardens Point images side by side (one per sub-panorama), so every place has
// real, distinct content; the return trip is darker (x0.8), as another time of day would be.
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>

#include <cstdio>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
const int kSubPanoramas = 6;
const int kPlaces = 30;
const int kOtherPlaces = 12;

std::mutex loops_mutex;
std::vector<openable_ros::LoopClosureConstPtr> loops;

void loopCallback(const openable_ros::LoopClosureConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(loops_mutex);
  loops.push_back(msg);
}

/// Sub-panoramas `first .. first + 5` of a traversal, side by side (160x120 each).
cv::Mat panorama(const std::string& dir, const std::string& traversal, int first)
{
  std::vector<cv::Mat> tiles;
  for (int i = 0; i < kSubPanoramas; ++i)
  {
    char path[1024];
    std::snprintf(path, sizeof(path), "%s/%s/Image%03d.jpg", dir.c_str(), traversal.c_str(), first + i);
    const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    if (image.empty())
    {
      return cv::Mat();
    }
    cv::Mat tile;
    cv::resize(image, tile, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
    tiles.push_back(tile);
  }
  cv::Mat out;
  cv::hconcat(tiles, out);
  return out;
}

/// The same panorama seen facing the other way: rotated by half a turn (half the sub-panoramas).
cv::Mat facingBack(const cv::Mat& pano)
{
  const int half = pano.cols / 2;
  cv::Mat out;
  cv::hconcat(pano.colRange(half, pano.cols), pano.colRange(0, half), out);
  out.convertTo(out, -1, 0.8, 0.0);
  return out;
}
}  // namespace

TEST(PanoramicDetector, ReversedRevisitIsReportedWithDirectionMinusOne)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  const double min_reverse_fraction = pnh.param("min_reverse_fraction", 0.8);
  // ~ring true: every sub-panorama goes out on its own camera topic (ring/cam0 .. ring/cam5, the
  // detector's ~cameras), with the same stamp; false: one panoramic image on `image`.
  const bool ring = pnh.param("ring", false);
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("image", 100);
  std::vector<ros::Publisher> camera_pubs;
  for (int i = 0; ring && i < kSubPanoramas; ++i)
  {
    camera_pubs.push_back(nh.advertise<sensor_msgs::Image>("ring/cam" + std::to_string(i), 100));
  }
  ros::Subscriber sub = nh.subscribe("loop_closures", 1000, loopCallback);
  ASSERT_TRUE(waitFor(
      [&]
      {
        for (const auto& camera_pub : camera_pubs)
        {
          if (camera_pub.getNumSubscribers() == 0)
          {
            return false;
          }
        }
        return (ring || pub.getNumSubscribers() > 0) && sub.getNumPublishers() > 0;
      },
      30.0));

  std::vector<cv::Mat> stream;
  for (int place = 0; place < kPlaces; ++place)
  {
    stream.push_back(panorama(dir, "day_right", place * kSubPanoramas));
  }
  for (int other = 0; other < kOtherPlaces; ++other)
  {
    stream.push_back(panorama(dir, "night_right", other * kSubPanoramas));
  }
  for (int place = kPlaces - 1; place >= 0; --place)
  {
    stream.push_back(facingBack(stream[size_t(place)]));
  }
  ros::Time stamp(10.0);
  ros::WallRate rate(30.0);
  for (const auto& image : stream)
  {
    ASSERT_FALSE(image.empty()) << "cannot read the Gardens Point images under " << dir;
    stamp += ros::Duration(0.1);
    if (ring)
    {
      const int width = image.cols / kSubPanoramas;
      for (int i = 0; i < kSubPanoramas; ++i)
      {
        const cv::Mat tile = image.colRange(i * width, (i + 1) * width).clone();
        camera_pubs[size_t(i)].publish(openable_ros_test::toMsg(tile, enc::BGR8, stamp, "cam" + std::to_string(i)));
      }
    }
    else
    {
      pub.publish(openable_ros_test::toMsg(image, enc::BGR8, stamp, "panoramic_camera"));
    }
    rate.sleep();
  }
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == long(stream.size()); }, 30.0));
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("loop closures") >= 0; }, 5.0));
  ASSERT_TRUE(waitFor(
      [&]
      {
        std::lock_guard<std::mutex> lock(loops_mutex);
        return diagnostics.number("loop closures") == long(loops.size());
      },
      10.0));

  const int return_start = kPlaces + kOtherPlaces;
  int reverse_correct = 0;
  int other = 0;
  std::lock_guard<std::mutex> lock(loops_mutex);
  for (const auto& loop : loops)
  {
    const int query = int(loop->query_id);
    if (query < return_start)
    {
      ++other;
      continue;
    }
    const int place = kPlaces - 1 - (query - return_start);
    std::printf("query %d (place %d) -> match %u, distance %.3f, direction %d, shift %d\n", query, place,
                loop->match_id, loop->distance, loop->direction, loop->shift);
    if (loop->direction == -1 && std::abs(int(loop->match_id) - place) <= 1 &&
        std::abs(int(loop->shift)) == kSubPanoramas / 2)
    {
      ++reverse_correct;
    }
  }
  std::printf(
      "panoramic: %d of %d return-trip frames reported as reverse loops with the right place and shift; "
      "%d loops elsewhere\n",
      reverse_correct, kPlaces, other);
  // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares the docs with these.
  RecordProperty("reverse_correct", reverse_correct);
  RecordProperty("return_frames", kPlaces);
  RecordProperty("other_loops", other);
  EXPECT_GE(double(reverse_correct) / kPlaces, min_reverse_fraction);
  EXPECT_EQ(other, 0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_panoramic_detector");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
