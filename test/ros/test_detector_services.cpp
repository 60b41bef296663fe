// Checker for the services and for bad input, against the mono nodelet: ~save_map / ~load_map / ~reset
// round trip, corrupt and incompatible maps refused with the node still serving, unsupported encodings,
// empty images and stamps going backwards skipped without losing the history, each counted and warned
// under its own reason (read back from /diagnostics and /rosout).
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <openable_ros/LoadMap.h>
#include <openable_ros/LoopClosure.h>
#include <openable_ros/SaveMap.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <std_srvs/Trigger.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <vector>

#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/map/place_database.h"
#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
// Stamps keep increasing across the tests of this process (the detector remembers the last one).
ros::Time next_stamp(100.0);

class DetectorServices : public testing::Test
{
protected:
  void SetUp() override
  {
    ros::NodeHandle pnh("~");
    data_dir_ = pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/gardens_point");
    detector_ = pnh.param<std::string>("detector", "mono_detector");
    tmp_dir_ = pnh.param<std::string>("tmp_dir", "/tmp");
    diagnostics_ = std::make_unique<DiagnosticsWatcher>(nh_);
    image_pub_ = nh_.advertise<sensor_msgs::Image>("image", 50);
    loop_sub_ = nh_.subscribe("loop_closures", 1000, &DetectorServices::loopCallback, this);
    rosout_sub_ = nh_.subscribe("/rosout", 1000, &DetectorServices::logCallback, this);
    ASSERT_TRUE(waitFor([&] { return image_pub_.getNumSubscribers() > 0 && loop_sub_.getNumPublishers() > 0; }, 30.0))
        << "the detector did not connect within 30 s";
    ASSERT_TRUE(ros::service::waitForService(detector_ + "/save_map", ros::Duration(30.0)));
    ASSERT_TRUE(ros::service::waitForService(detector_ + "/load_map", ros::Duration(5.0)));
    ASSERT_TRUE(ros::service::waitForService(detector_ + "/reset", ros::Duration(5.0)));
  }

  void loopCallback(const openable_ros::LoopClosureConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    loops_.push_back(msg);
  }
  /// The detector's refusal warnings ("... (frame skipped: <reason>)..."), counted by reason.
  void logCallback(const rosgraph_msgs::LogConstPtr& msg)
  {
    const std::string tag = "(frame skipped: ";
    const size_t at = msg->msg.find(tag);
    if (msg->level != rosgraph_msgs::Log::WARN || at == std::string::npos)
      return;
    const size_t end = msg->msg.find(')', at);
    std::lock_guard<std::mutex> lock(mutex_);
    ++warned_[msg->msg.substr(at + tag.size(), end - at - tag.size())];
  }
  std::map<std::string, int> warned()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return warned_;
  }
  size_t loopCount()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return loops_.size();
  }

  cv::Mat dayImage(int index)
  {
    char path[1024];
    std::snprintf(path, sizeof(path), "%s/day_right/Image%03d.jpg", data_dir_.c_str(), index);
    return cv::imread(path, cv::IMREAD_COLOR);
  }

  /// Publishes day images [first, first + count) with stamps from next_stamp_ on and waits until the
  /// detector has received them all.
  void publishDay(int first, int count, std::vector<ros::Time>* stamps = nullptr)
  {
    const long before = diagnostics_->number("frames received");
    for (int i = first; i < first + count; ++i)
    {
      const cv::Mat image = dayImage(i);
      ASSERT_FALSE(image.empty());
      const ros::Time stamp = nextStamp();
      if (stamps)
      {
        stamps->push_back(stamp);
      }
      publish(openable_ros_test::toMsg(image, enc::BGR8, stamp));
    }
    ASSERT_TRUE(waitFor([&] { return diagnostics_->number("frames received") >= before + count; }, 20.0))
        << "frames received " << diagnostics_->number("frames received") << ", expected " << before + count;
  }
  void publish(const sensor_msgs::ImagePtr& msg)
  {
    image_pub_.publish(msg);
    ros::WallDuration(0.02).sleep();
  }
  ros::Time nextStamp()
  {
    next_stamp += ros::Duration(0.1);
    return next_stamp;
  }
  /// Waits for a diagnostics report in which `key` equals `value`.
  bool waitForValue(const std::string& key, long value, double seconds = 10.0)
  {
    return waitFor([&] { return diagnostics_->number(key) == value; }, seconds);
  }

  ros::NodeHandle nh_;
  std::string data_dir_;
  std::string detector_;
  std::string tmp_dir_;
  std::unique_ptr<DiagnosticsWatcher> diagnostics_;
  ros::Publisher image_pub_;
  ros::Subscriber loop_sub_;
  ros::Subscriber rosout_sub_;
  std::mutex mutex_;
  std::vector<openable_ros::LoopClosureConstPtr> loops_;
  std::map<std::string, int> warned_;
};
}  // namespace

TEST_F(DetectorServices, BadInputIsSkippedAndTheNodeKeepsRunning)
{
  publishDay(0, 10);
  ASSERT_TRUE(waitForValue("history size", 10));

  // Depth and float images on the mono input, and an empty image.
  publish(openable_ros_test::toMsg(cv::Mat(48, 64, CV_16UC1, cv::Scalar(1000)), enc::TYPE_16UC1, nextStamp()));
  publish(openable_ros_test::toMsg(cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.5f)), enc::TYPE_32FC1, nextStamp()));
  auto empty = boost::make_shared<sensor_msgs::Image>();
  empty->header.stamp = nextStamp();
  empty->encoding = enc::BGR8;
  publish(empty);
  // Issue 22 finding 6: each reason its own count and its own warning (they shared one "bad image" before).
  ASSERT_TRUE(waitForValue("rejected: unsupported encoding", 2))
      << "rejected: " << diagnostics_->value("rejected: unsupported encoding");
  ASSERT_TRUE(waitForValue("rejected: empty image", 1)) << diagnostics_->value("rejected: empty image");

  // A stamp going backwards: skipped, history kept (~reset_on_time_jump false by default).
  const cv::Mat image = dayImage(10);
  publish(openable_ros_test::toMsg(image, enc::BGR8, ros::Time(50.0)));
  ASSERT_TRUE(waitForValue("rejected: stamp went backwards", 1));
  EXPECT_EQ(diagnostics_->number("history size"), 10);
  EXPECT_EQ(diagnostics_->number("frames rejected"), 4);
  // One warning per reason within the throttle's 5 s: the second unsupported encoding is held back, no
  // reason hides another.
  const std::map<std::string, int> expected = {
      {"unsupported encoding", 1}, {"empty image", 1}, {"stamp went backwards", 1}};
  EXPECT_TRUE(waitFor([&] { return warned() == expected; }, 5.0)) << [&]
  {
    std::string seen;
    for (const auto& w : warned())
      seen += w.first + " x" + std::to_string(w.second) + "; ";
    return "warnings seen: " + seen;
  }();

  // Still running: the next good frames are stored.
  publishDay(10, 5);
  EXPECT_TRUE(waitForValue("history size", 15));
  EXPECT_EQ(diagnostics_->number("frames stored"), 15);
  // Issue 9 item 8: rejected frames are received frames too (10 + 3 bad + 1 backwards + 5).
  EXPECT_TRUE(waitForValue("frames received", 19)) << diagnostics_->value("frames received");
}

TEST_F(DetectorServices, SaveLoadResetRoundTripAndBadMapsAreRefused)
{
  ros::ServiceClient save = nh_.serviceClient<openable_ros::SaveMap>(detector_ + "/save_map");
  ros::ServiceClient load = nh_.serviceClient<openable_ros::LoadMap>(detector_ + "/load_map");
  ros::ServiceClient reset = nh_.serviceClient<std_srvs::Trigger>(detector_ + "/reset");

  std_srvs::Trigger trigger;
  ASSERT_TRUE(reset.call(trigger));
  EXPECT_TRUE(trigger.response.success);
  ASSERT_TRUE(waitForValue("history size", 0));

  // Record a map of 40 frames.
  std::vector<ros::Time> map_stamps;
  publishDay(0, 40, &map_stamps);
  ASSERT_TRUE(waitForValue("history size", 40));
  const std::string map_path = tmp_dir_ + "/openable_test_map_" + std::to_string(getpid()) + ".map";
  openable_ros::SaveMap save_request;
  save_request.request.path = map_path;
  ASSERT_TRUE(save.call(save_request));
  EXPECT_TRUE(save_request.response.success) << save_request.response.message;
  EXPECT_EQ(save_request.response.frames, 40u);

  // Reset: the history is gone.
  ASSERT_TRUE(reset.call(trigger));
  EXPECT_TRUE(trigger.response.success);
  ASSERT_TRUE(waitForValue("history size", 0));

  // A corrupt map (the saved one with bytes flipped in the middle) is refused; nothing changes.
  const std::string corrupt_path = map_path + ".corrupt";
  {
    std::ifstream in(map_path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 100u);
    for (size_t i = bytes.size() / 2; i < bytes.size() / 2 + 16; ++i)
    {
      bytes[i] = char(~bytes[i]);
    }
    std::ofstream out(corrupt_path, std::ios::binary);
    out << bytes;
  }
  openable_ros::LoadMap load_request;
  load_request.request.path = corrupt_path;
  ASSERT_TRUE(load.call(load_request));
  EXPECT_FALSE(load_request.response.success);
  EXPECT_NE(load_request.response.message.find("refused"), std::string::npos) << load_request.response.message;
  load_request.request.path = tmp_dir_ + "/does_not_exist.map";
  ASSERT_TRUE(load.call(load_request));
  EXPECT_FALSE(load_request.response.success);

  // An incompatible map (another patch size) is refused, naming the key.
  {
    openable::Config other = openable::Config::paper();
    other.patch_size = 32;
    openable::FrameDescriber describer(other);
    openable::PlaceDatabase database(describer.layout(), 0, other.toYaml());
    database.add(describer.describeImage(dayImage(0)));
    database.save(map_path + ".other");
  }
  load_request.request.path = map_path + ".other";
  ASSERT_TRUE(load.call(load_request));
  EXPECT_FALSE(load_request.response.success);
  EXPECT_NE(load_request.response.message.find("patch_size"), std::string::npos) << load_request.response.message;

  // Still serving after the refusals: frames are stored.
  publishDay(100, 3);
  ASSERT_TRUE(waitForValue("history size", 3));

  // Load the good map: localisation mode against its 40 frames, the same places close loops with it.
  load_request.request.path = map_path;
  ASSERT_TRUE(load.call(load_request));
  EXPECT_TRUE(load_request.response.success) << load_request.response.message;
  EXPECT_EQ(load_request.response.frames, 40u);
  ASSERT_TRUE(waitFor([&] { return diagnostics_->value("mode").find("localisation") == 0; }, 10.0));
  EXPECT_EQ(diagnostics_->number("history size"), 40);
  const size_t loops_before = loopCount();
  std::vector<ros::Time> replay_stamps;
  publishDay(0, 20, &replay_stamps);
  ASSERT_TRUE(waitFor([&] { return loopCount() > loops_before + 10; }, 10.0))
      << "only " << loopCount() - loops_before << " loop closures against the loaded map";
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (size_t i = loops_before; i < loops_.size(); ++i)
    {
      // Replay frame k shows the place of map frame k: compare through the stamps (ids are global ones).
      const auto query = std::find(replay_stamps.begin(), replay_stamps.end(), loops_[i]->header.stamp);
      const auto match = std::find(map_stamps.begin(), map_stamps.end(), loops_[i]->match_stamp);
      ASSERT_TRUE(query != replay_stamps.end() && match != map_stamps.end());
      EXPECT_LE(std::abs(int(query - replay_stamps.begin()) - int(match - map_stamps.begin())), 2)
          << "replay frame " << query - replay_stamps.begin() << " matched map frame " << match - map_stamps.begin();
    }
  }
  // The map is not modified by localising.
  EXPECT_EQ(diagnostics_->number("history size"), 40);
  // Issue 9 item 10: ~reset leaves the map: back to loop-closure mode with an empty history, no restart.
  ros::ServiceClient leave = nh_.serviceClient<std_srvs::Trigger>(detector_ + "/reset");
  std_srvs::Trigger unload;
  ASSERT_TRUE(leave.call(unload));
  EXPECT_TRUE(unload.response.success);
  EXPECT_NE(unload.response.message.find("unloaded"), std::string::npos) << unload.response.message;
  ASSERT_TRUE(waitFor([&] { return diagnostics_->value("mode").find("loop closure") == 0; }, 10.0))
      << diagnostics_->value("mode");
  EXPECT_TRUE(waitForValue("history size", 0));
  std::remove(map_path.c_str());
  std::remove(corrupt_path.c_str());
  std::remove((map_path + ".other").c_str());
}

TEST_F(DetectorServices, DynamicReconfigureChangesMatchingLiveAndRevertsRefusedValues)
{
  ASSERT_TRUE(ros::service::waitForService(detector_ + "/set_parameters", ros::Duration(10.0)));
  ros::ServiceClient client = nh_.serviceClient<dynamic_reconfigure::Reconfigure>(detector_ + "/set_parameters");
  auto setDouble = [&](const std::string& name, double value)
  {
    dynamic_reconfigure::Reconfigure srv;
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.doubles.push_back(p);
    EXPECT_TRUE(client.call(srv));
    return srv.response.config;
  };
  auto find = [](const dynamic_reconfigure::Config& config, const std::string& name)
  {
    for (const auto& d : config.doubles)
    {
      if (d.name == name)
      {
        return d.value;
      }
    }
    return -100.0;
  };

  // A live change reaches the detector.
  EXPECT_DOUBLE_EQ(find(setDouble("threshold", 0.05), "threshold"), 0.05);
  EXPECT_TRUE(waitFor([&] { return diagnostics_->value("threshold") == "0.05"; }, 10.0))
      << "threshold in diagnostics: " << diagnostics_->value("threshold");
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::IntParameter length;
  length.name = "sequence_length";
  length.value = 4;
  srv.request.config.ints.push_back(length);
  ASSERT_TRUE(client.call(srv));
  EXPECT_TRUE(waitFor([&] { return diagnostics_->number("sequence length") == 4; }, 10.0));

  // Inside the .cfg range but refused by the core (a threshold is -1 or in [0, 1]): reverted, and the
  // server reports the value in force.
  EXPECT_DOUBLE_EQ(find(setDouble("threshold", -0.5), "threshold"), 0.05);
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(diagnostics_->value("threshold"), "0.05");

  // Outside the table's range: refused, never clamped (dynamic_reconfigure used to turn 5 into 1.0, which
  // accepts everything), and the server reports the value in force.
  EXPECT_DOUBLE_EQ(find(setDouble("threshold", 5.0), "threshold"), 0.05);
  EXPECT_DOUBLE_EQ(find(setDouble("exclusion_seconds", -3.0), "exclusion_seconds"), 0.0);
  EXPECT_DOUBLE_EQ(find(setDouble("matrix_rate", 1000.0), "matrix_rate"), 2.0);
  {
    // One refused key in a request does not hold back the others.
    dynamic_reconfigure::Reconfigure both;
    dynamic_reconfigure::DoubleParameter threshold;
    threshold.name = "threshold";
    threshold.value = 5.0;
    both.request.config.doubles.push_back(threshold);
    dynamic_reconfigure::IntParameter size;
    size.name = "matrix_size";
    size.value = 5;  // below 16
    both.request.config.ints.push_back(size);
    length.value = 5;
    both.request.config.ints.push_back(length);
    ASSERT_TRUE(client.call(both));
    EXPECT_DOUBLE_EQ(find(both.response.config, "threshold"), 0.05);
    int shown_length = -1, shown_size = -1;
    for (const auto& i : both.response.config.ints)
    {
      shown_length = i.name == "sequence_length" ? i.value : shown_length;
      shown_size = i.name == "matrix_size" ? i.value : shown_size;
    }
    EXPECT_EQ(shown_length, 5);
    EXPECT_EQ(shown_size, 512);
    EXPECT_TRUE(waitFor([&] { return diagnostics_->number("sequence length") == 5; }, 10.0));
    EXPECT_EQ(diagnostics_->value("threshold"), "0.05");
  }

  // Back to the test configuration.
  setDouble("threshold", 0.1);
  length.value = 3;
  srv.request.config.ints.assign(1, length);
  ASSERT_TRUE(client.call(srv));
  EXPECT_TRUE(waitFor([&] { return diagnostics_->number("sequence length") == 3; }, 10.0));
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_detector_services");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
