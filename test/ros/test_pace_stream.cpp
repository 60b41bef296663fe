// Checker for a revisit that is not driven at the first pass's pace (issue 20, issue 23): Gardens Point
// day_right at one frame a metre, then night_right at double speed (every second image) with a 30-second
// standstill half way (the same image, 10 Hz stamps), as a 10 Hz camera on a robot would record it. The
// detector runs as mono.launch starts it (see mono_pace_*.test): with ~odometry the checker also publishes
// the camera's pose on tf (odom -> camera, one metre an image, still during the stop).
//
// What is asserted is what a pose graph receives: no wrong loop (during the stop, after it, anywhere), most
// night images closed with their day twin, and a history that does not grow while the camera stands still.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>

#include <cstdio>
#include <map>
#include <mutex>
#include <set>
#include <vector>

#include "test_helpers.h"
#include "tf_sender.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;

namespace
{
/// One published frame: which traversal, which image of it, and where the camera is (metres along the path).
struct StreamFrame
{
  bool night = false;
  int image = 0;
};

/// day_right 0..frames-1, then night_right every `step`-th image, image `stop_image` repeated `stop_frames`
/// times more (the standstill).
std::vector<StreamFrame> paceStream(int frames, int step, int stop_image, int stop_frames)
{
  std::vector<StreamFrame> stream;
  for (int i = 0; i < frames; ++i)
    stream.push_back({false, i});
  for (int i = 0; i < frames; i += step)
  {
    stream.push_back({true, i});
    if (i == stop_image)
      for (int k = 0; k < stop_frames; ++k)
        stream.push_back({true, i});
  }
  return stream;
}

class LoopRecorder
{
public:
  void loop(const openable_ros::LoopClosureConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    loops_.push_back(msg);
  }
  std::vector<openable_ros::LoopClosureConstPtr> loops()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return loops_;
  }

private:
  std::mutex mutex_;
  std::vector<openable_ros::LoopClosureConstPtr> loops_;
};
}  // namespace

TEST(MonoDetectorPace, StandstillAndDoubleSpeedPublishOnlyRightLoops)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string data_dir = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
  const bool odometry = pnh.param("odometry", false);
  const double rate = pnh.param("rate", 40.0);  // wall-clock frames a second (a bag played at 4x)
  const int frames = pnh.param("frames_per_traversal", 200);
  const int step = pnh.param("night_step", 2);
  const int stop_image = pnh.param("stop_image", 100);
  const double stop_seconds = pnh.param("stop_seconds", 30.0);
  const double min_recall = pnh.param("min_recall", 0.0);
  const double camera_period = 0.1;  // the stamps of a 10 Hz camera
  const int stop_frames = int(stop_seconds / camera_period);

  LoopRecorder recorder;
  DiagnosticsWatcher diagnostics(nh);
  openable_ros_test::TfSender tf(nh);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("image", 100);
  ros::Subscriber loop_sub = nh.subscribe("loop_closures", 10000, &LoopRecorder::loop, &recorder);
  ASSERT_TRUE(waitFor([&] { return image_pub.getNumSubscribers() > 0 && loop_sub.getNumPublishers() > 0; }, 30.0))
      << "the detector did not subscribe to 'image' / advertise 'loop_closures' within 30 s";
  if (odometry)
  {
    ASSERT_TRUE(tf.waitForListener(30.0)) << "the detector's tf listener did not connect within 30 s";
  }

  const std::vector<StreamFrame> stream = paceStream(frames, step, stop_image, stop_frames);
  std::map<ros::Time, size_t> index_of_stamp;
  ros::Time stamp(1000.0);
  ros::WallRate pacing(rate);
  for (size_t index = 0; index < stream.size(); ++index)
  {
    const StreamFrame& frame = stream[index];
    stamp += ros::Duration(camera_period);
    index_of_stamp[stamp] = index;
    if (odometry)
    {
      // Both traversals follow the same path, one metre an image; the pose stays put during the stop.
      geometry_msgs::TransformStamped t;
      t.header.stamp = stamp;
      t.header.frame_id = "odom";
      t.child_frame_id = "camera";
      t.transform.translation.x = frame.image;
      t.transform.rotation.w = 1.0;
      tf.send(t);
    }
    char path[1024];
    std::snprintf(path, sizeof(path), "%s/%s/Image%03d.jpg", data_dir.c_str(), frame.night ? "night_right" : "day_right",
                  frame.image);
    const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty()) << "cannot read " << path;
    image_pub.publish(openable_ros_test::toMsg(image, sensor_msgs::image_encodings::BGR8, stamp));
    pacing.sleep();
  }
  const long total = long(stream.size());
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") >= total; }, 60.0))
      << "the detector received " << diagnostics.number("frames received") << " of " << total << " frames";
  // Standing still adds no place: only the frames where the camera moved are stored.
  const int night_images = (frames + step - 1) / step;
  EXPECT_EQ(diagnostics.number("frames stored"), frames + night_images) << "of " << total << " frames";
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("loop closures") == long(recorder.loops().size()); }, 10.0));
  // Every frame counted once: a confirmed loop closure's frame (and each repeat of it) moves from pending to
  // published, one whose run ended to unconfirmed; only the last frames of the stream may still wait.
  EXPECT_EQ(diagnostics.number("frames published"), long(recorder.loops().size()));
  EXPECT_LE(diagnostics.number("frames pending"), 3);

  int correct = 0;
  int wrong = 0;
  int wrong_after_stop = 0;
  std::set<int> closed;  // night images with a right loop closure
  for (const auto& loop : recorder.loops())
  {
    const auto query = index_of_stamp.find(loop->header.stamp);
    const auto match = index_of_stamp.find(loop->match_stamp);
    ASSERT_TRUE(query != index_of_stamp.end()) << "loop closure stamped " << loop->header.stamp;
    ASSERT_TRUE(match != index_of_stamp.end()) << "match stamped " << loop->match_stamp;
    const StreamFrame& q = stream[query->second];
    const StreamFrame& m = stream[match->second];
    if (q.night && !m.night && std::abs(q.image - m.image) <= 2)
    {
      ++correct;
      closed.insert(q.image);
      continue;
    }
    ++wrong;
    wrong_after_stop += q.night && q.image >= stop_image;
    ADD_FAILURE() << "wrong loop closure: " << (q.night ? "night" : "day") << " image " << q.image << " (frame "
                  << query->second << ") with " << (m.night ? "night" : "day") << " image " << m.image;
  }
  const double recall = double(closed.size()) / night_images;
  std::printf("pace stream (%s): %zu frames, %ld stored; %zu published, %d wrong (%d at or after the stop); "
              "%zu of %d night images closed (recall %.3f)\n",
              odometry ? "odometry keyframes" : "images only", stream.size(), diagnostics.number("frames stored"),
              recorder.loops().size(), wrong, wrong_after_stop, closed.size(), night_images, recall);
  // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares the docs with these.
  RecordProperty("frames", int(stream.size()));
  RecordProperty("stored", std::to_string(diagnostics.number("frames stored")));
  RecordProperty("published", int(recorder.loops().size()));
  RecordProperty("wrong", wrong);
  RecordProperty("night_closed", int(closed.size()));
  RecordProperty("night_images", night_images);
  RecordProperty("recall", std::to_string(recall));
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(recall, min_recall);
  EXPECT_GT(correct, 0);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_pace_stream");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
