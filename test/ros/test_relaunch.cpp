// Checker for issue 23, "no stale parameters": mono.launch started twice in a row on one master with a
// partial YAML (config:=test/ros/partial.yaml) publishes the same loop closures both times, although each
// start finds other keys left in its namespace (as an earlier launch or a `rosparam set` leaves them). The
// launch clears the namespace (clear_params), so a partial YAML means "config/default.yaml with these
// changes" every time.
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <set>
#include <string>
#include <utility>

#include "test_helpers.h"

using openable_ros_test::waitFor;

namespace
{
using LoopSet = std::set<std::pair<uint64_t, uint64_t>>;

class LoopRecorder
{
public:
  void loop(const openable_ros::LoopClosureConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    loops_.insert({msg->query_id, msg->match_id});
  }
  void decision(const openable_ros::LoopClosureConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_decided_ = msg->header.stamp;
  }
  ros::Time lastDecided()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_decided_;
  }
  LoopSet take()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    LoopSet out;
    out.swap(loops_);
    return out;
  }

private:
  std::mutex mutex_;
  LoopSet loops_;
  ros::Time last_decided_;
};

/// `roslaunch openable_ros mono.launch ...` in its own process group (so SIGINT reaches every child).
pid_t startLaunch(const std::string& partial_yaml)
{
  const pid_t pid = fork();
  if (pid == 0)
  {
    setpgid(0, 0);
    const std::string config = "config:=" + partial_yaml;
    execlp("roslaunch", "roslaunch", "openable_ros", "mono.launch", "image:=/image", config.c_str(),
           static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// SIGINT as Ctrl-C would, waiting up to 30 s for roslaunch to stop its nodes; SIGKILL after that.
void stopLaunch(pid_t pid)
{
  kill(-pid, SIGINT);
  int status = 0;
  const bool stopped = waitFor([&] { return waitpid(pid, &status, WNOHANG) == pid; }, 30.0);
  if (!stopped)
  {
    kill(-pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
}
}  // namespace

TEST(Relaunch, TwoLaunchesWithAPartialYamlPublishTheSameLoops)
{
  ros::NodeHandle nh;
  const std::string data_dir = OPENABLE_SOURCE_DIR "/../shared/data/gardens_point";
  const std::string partial = OPENABLE_SOURCE_DIR "/test/ros/partial.yaml";
  const int frames = 200;
  LoopRecorder recorder;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/image", 100);
  ros::Subscriber loop_sub = nh.subscribe("/loop_closures", 1000, &LoopRecorder::loop, &recorder);
  // Each frame is sent once the previous one is decided: no frame is dropped, however loaded the machine.
  ros::Subscriber decision_sub = nh.subscribe("/decisions", 1000, &LoopRecorder::decision, &recorder);

  // Keys left behind by "earlier launches": a different one before each start, so a launch that kept
  // them would differ between the two runs.
  const std::vector<std::pair<std::string, int>> stale = {{"/mono_detector/sequence_length", 5},
                                                          {"/mono_detector/consistent_frames", 2}};
  std::vector<LoopSet> runs;
  for (const auto& [key, value] : stale)
  {
    ros::param::set(key, value);
    const pid_t launch = startLaunch(partial);
    ASSERT_GT(launch, 0);
    const bool up = waitFor([&] { return image_pub.getNumSubscribers() > 0 && loop_sub.getNumPublishers() > 0 &&
                                         decision_sub.getNumPublishers() > 0; },
                            60.0);
    if (!up)
      stopLaunch(launch);
    ASSERT_TRUE(up) << "mono.launch did not subscribe to /image within 60 s";
    for (int index = 0; index < 2 * frames; ++index)
    {
      const bool night = index >= frames;
      char path[1024];
      std::snprintf(path, sizeof(path), "%s/%s/Image%03d.jpg", data_dir.c_str(), night ? "night_right" : "day_right",
                    night ? index - frames : index);
      const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
      ASSERT_FALSE(image.empty()) << path;
      const ros::Time stamp(1000.0 + 0.1 * index);
      image_pub.publish(openable_ros_test::toMsg(image, sensor_msgs::image_encodings::BGR8, stamp));
      const bool decided = waitFor([&] { return recorder.lastDecided() == stamp; }, 20.0);
      if (!decided)
        stopLaunch(launch);
      ASSERT_TRUE(decided) << "no decision for frame " << index << " within 20 s";
    }
    stopLaunch(launch);
    ASSERT_TRUE(waitFor([&] { return loop_sub.getNumPublishers() == 0; }, 20.0));
    runs.push_back(recorder.take());
    std::printf("launch %zu (stale %s = %d left in the namespace): %zu loop closures\n", runs.size(), key.c_str(),
                value, runs.back().size());
    // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares the docs with these.
    RecordProperty("published_" + std::to_string(runs.size()), int(runs.back().size()));
  }
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_GT(runs[0].size(), 0u);
  EXPECT_TRUE(runs[0] == runs[1]) << "the two launches published different loop closures: " << runs[0].size()
                                  << " and " << runs[1].size();
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_relaunch");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
