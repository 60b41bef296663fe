// The ROS adapters' helpers, without a ROS master: the ROS-only parameter table against config/ros.yaml
// and doc/ros_api.md, image conversions for every encoding, and dynamic_reconfigure <-> core keys.
#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <boost/make_shared.hpp>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <fstream>
#include <regex>
#include <string>

#include "openable/config.h"
#include "openable/description/input_contract.h"
#include "openable/detection/online_detector.h"
#include "openable/node_support/refusal_log.h"
#include "openable_ros/DetectorConfig.h"
#include "openable_ros/conversions.h"
#include "openable_ros/params.h"
#include "openable_ros/live_reconfigure.h"
#include "openable_ros/ros_parameters.h"

namespace enc = sensor_msgs::image_encodings;
using openable_ros::rosParameterTable;

namespace
{
std::string readFile(const std::string& relative)
{
  std::ifstream in(std::string(OPENABLE_SOURCE_DIR) + "/" + relative);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string unquoted(std::string s)
{
  s.erase(std::remove(s.begin(), s.end(), '"'), s.end());
  return s;
}

/// "5.0" and "5" are the same default; words compare as words.
bool sameValue(const std::string& a, const std::string& b)
{
  try
  {
    size_t used_a = 0, used_b = 0;
    const double x = std::stod(a, &used_a), y = std::stod(b, &used_b);
    if (used_a == a.size() && used_b == b.size())
      return x == y;
  }
  catch (const std::exception&)
  {
  }
  return unquoted(a) == unquoted(b);
}

sensor_msgs::ImagePtr image(const std::string& encoding, int cv_type, int channels_bytes)
{
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->encoding = encoding;
  msg->width = 8;
  msg->height = 4;
  msg->step = 8 * uint32_t(channels_bytes);
  msg->data.assign(msg->step * msg->height, 100);
  (void)cv_type;
  return msg;
}
}  // namespace

TEST(RosParameters, RosYamlListsEveryParameterWithItsDefault)
{
  const std::string yaml = readFile("config/ros.yaml");
  for (const auto& p : rosParameterTable())
  {
    // "name: value" at the start of a line, or commented for one nodelet kind ("#   name: value").
    const std::regex line("(^|\\n)(#\\s+)?" + p.name + ":\\s*([^#\\n]*?)\\s*(#|\\n)");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(yaml, m, line)) << p.name << " is missing from config/ros.yaml";
    EXPECT_TRUE(sameValue(m[3], p.default_value))
        << p.name << ": ros.yaml says " << m[3] << ", the table " << p.default_value;
  }
}

TEST(RosParameters, DocTableHoldsEveryCommonParameterWithItsDefault)
{
  const std::string doc = readFile("doc/ros_api.md");
  for (const auto& p : rosParameterTable())
  {
    if (p.nodelets != "all")
    {
      EXPECT_NE(doc.find("`~" + p.name + "`"), std::string::npos) << p.name << " is not documented";
      continue;
    }
    const std::regex row("\\| `~" + p.name + "` \\| (\\w+) \\| ([^|]*?) \\|");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(doc, m, row)) << p.name << " has no row in doc/ros_api.md";
    EXPECT_EQ(m[1], p.type) << p.name;
    EXPECT_TRUE(sameValue(m[2], p.default_value))
        << p.name << ": doc says " << m[2] << ", the table " << p.default_value;
  }
}

TEST(RosParameters, NoNameInBothTables)
{
  for (const auto& p : rosParameterTable())
    for (const auto& key : openable::Config::keys())
      EXPECT_NE(p.name, key.name) << "a ROS-only parameter shadows a core key";
}

TEST(Conversions, EveryEncodingIsConvertedOrRefusedWithAReason)
{
  struct Case
  {
    std::string encoding;
    int bytes_per_pixel;
    bool accepted;
    int channels;
  };
  const std::vector<Case> cases = {
      {enc::MONO8, 1, true, 1},       {enc::TYPE_8UC1, 1, true, 1},   {enc::BGR8, 3, true, 3},
      {enc::RGB8, 3, true, 3},        {enc::TYPE_8UC3, 3, true, 3},   {enc::BGRA8, 4, true, 3},
      {enc::RGBA8, 4, true, 3},       {enc::TYPE_8UC4, 4, true, 3},   {enc::MONO16, 2, true, 1},
      {enc::TYPE_16UC1, 2, false, 0}, {enc::TYPE_32FC1, 4, false, 0}, {"yuv422", 2, false, 0},
  };
  for (const auto& c : cases)
  {
    cv::Mat out;
    openable::InputProblem problem;
    const bool ok = openable_ros::toCoreImage(image(c.encoding, 0, c.bytes_per_pixel), out, problem);
    const std::string& error = problem.what;
    EXPECT_EQ(ok, c.accepted) << c.encoding << ": " << error;
    EXPECT_EQ(ok, problem.ok()) << c.encoding;
    if (ok)
    {
      EXPECT_EQ(out.channels(), c.channels) << c.encoding;
      EXPECT_EQ(out.depth(), CV_8U) << c.encoding;
      EXPECT_EQ(out.size(), cv::Size(8, 4)) << c.encoding;
    }
    else
    {
      EXPECT_NE(error.find(c.encoding), std::string::npos) << "the reason names the encoding: " << error;
      EXPECT_EQ(problem.reason, "unsupported encoding");
    }
  }
  // Too little data for the stated size.
  auto short_msg = image(enc::MONO8, 0, 1);
  short_msg->data.resize(3);
  cv::Mat out;
  openable::InputProblem problem;
  EXPECT_FALSE(openable_ros::toCoreImage(short_msg, out, problem));
  EXPECT_EQ(problem.reason, "image data too short");
  EXPECT_FALSE(problem.what.empty());
}

/// A real Gardens Point frame (data/sample) as a sensor_msgs/Image of `encoding` (mono8 or 16UC1).
sensor_msgs::ImagePtr realImage(const std::string& encoding)
{
  const cv::Mat frame = cv::imread(std::string(OPENABLE_SOURCE_DIR) + "/data/sample/day_right/Image010.jpg",
                                   cv::IMREAD_GRAYSCALE);
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->encoding = encoding;
  msg->width = uint32_t(frame.cols);
  msg->height = uint32_t(frame.rows);
  const size_t bytes = encoding == enc::TYPE_16UC1 ? 2 : 1;
  msg->step = uint32_t(frame.cols * bytes);
  msg->data.assign(msg->step * msg->height, 0);
  for (int r = 0; r < frame.rows; ++r)
    for (int c = 0; c < frame.cols; ++c)
      msg->data[size_t(r) * msg->step + size_t(c) * bytes] = frame.at<uint8_t>(r, c);
  return msg;
}

/// The reason the core refuses `input` with, "" when it does not.
std::string coreRefusal(openable::OnlineDetector& detector, const openable::FrameInput& input)
{
  try
  {
    const openable::FrameOutcome outcome = detector.process(input);
    // A stamp before the previous frame's is an outcome, refused by the nodelet (Detector::acceptStamp).
    return outcome.status == openable::FrameStatus::TimeJump ? "stamp went backwards" : "";
  }
  catch (const openable::FrameRefused& e)
  {
    return e.reason();
  }
}

// Issue 22 finding 6: "all bad-image reasons share one warning throttle: 11 refusals in a few seconds gave 3
// log lines". The same kind of burst on real frames: 11 refusals of 9 reasons within 3.3 s, from the ROS
// conversion (toCoreImage) and from the core (OnlineDetector with the nodelets' options), go through the
// RefusalLog the Detector keeps: one warning per reason, one count per reason. Before, toCoreImage gave a
// text only and the nodelets counted and throttled all of its refusals as one "bad image".
TEST(Refusals, EachReasonHasItsOwnWarningAndCount)
{
  std::vector<std::string> reasons;
  auto converted = [&reasons](const sensor_msgs::ImageConstPtr& msg)
  {
    cv::Mat out;
    openable::InputProblem problem;
    EXPECT_FALSE(openable_ros::toCoreImage(msg, out, problem)) << msg->encoding;
    reasons.push_back(problem.reason);
  };
  auto empty = realImage(enc::MONO8);
  empty->width = 0;
  empty->height = 0;
  empty->data.clear();
  converted(empty);
  converted(realImage(enc::TYPE_16UC1));  // a depth image on the camera topic
  auto float_image = realImage(enc::TYPE_16UC1);
  float_image->encoding = enc::TYPE_32FC1;
  converted(float_image);
  auto truncated = realImage(enc::MONO8);
  truncated->data.resize(truncated->data.size() / 2);
  converted(truncated);

  openable::OnlineOptions options;
  options.require_stamps = true;  // as the nodelets run it
  openable::OnlineDetector detector(
      openable::Config::fromYamlFile(std::string(OPENABLE_SOURCE_DIR) + "/config/default.yaml"), options);
  cv::Mat frame;
  openable::InputProblem problem;
  ASSERT_TRUE(openable_ros::toCoreImage(realImage(enc::MONO8), frame, problem)) << problem.what;
  auto input = [&frame](double stamp)
  {
    openable::FrameInput in;
    in.image = frame;
    in.stamp = stamp;
    return in;
  };
  ASSERT_EQ(coreRefusal(detector, input(100.0)), "");  // a good frame first
  reasons.push_back(coreRefusal(detector, input(0.0)));
  reasons.push_back(coreRefusal(detector, input(50.0)));
  openable::FrameInput strip = input(101.0);
  strip.image = cv::Mat(1, 100000, CV_8UC1, cv::Scalar(128));
  reasons.push_back(coreRefusal(detector, strip));
  strip.image = cv::Mat(1, 1, CV_8UC1, cv::Scalar(128));
  reasons.push_back(coreRefusal(detector, strip));
  openable::FrameInput black = input(102.0);
  black.image = cv::Mat::zeros(frame.size(), CV_8UC1);
  reasons.push_back(coreRefusal(detector, black));
  openable::FrameInput posed = input(103.0);
  posed.has_pose = true;
  posed.pose[0] = std::numeric_limits<double>::quiet_NaN();
  reasons.push_back(coreRefusal(detector, posed));
  posed.pose = {{0, 0, 0, 0, 0, 0, 0}};
  reasons.push_back(coreRefusal(detector, posed));

  ASSERT_EQ(reasons.size(), 11u);
  const std::vector<std::string> expected = {
      "empty image",          "unsupported encoding", "unsupported encoding", "image data too short",
      "stamp 0",              "stamp went backwards", "image too small",      "image too small",
      "no texture",           "pose not finite",      "zero quaternion"};
  EXPECT_EQ(reasons, expected);

  openable::RefusalLog log(5.0);
  std::set<std::string> warned;
  size_t lines = 0;
  for (size_t i = 0; i < reasons.size(); ++i)
  {
    uint64_t held_back = 0;
    if (log.note(reasons[i], 0.3 * double(i), held_back))
    {
      ++lines;
      EXPECT_TRUE(warned.insert(reasons[i]).second) << "warned twice within the period: " << reasons[i];
      EXPECT_EQ(held_back, 0u);
    }
  }
  EXPECT_EQ(lines, 9u) << "one warning per reason, none hidden by another reason's";
  EXPECT_EQ(warned, std::set<std::string>(expected.begin(), expected.end()));
  EXPECT_EQ(log.total(), 11u);
  EXPECT_EQ(log.counts().size(), 9u);
  EXPECT_EQ(log.counts().at("unsupported encoding"), 2u);
  EXPECT_EQ(log.counts().at("image too small"), 2u);
  EXPECT_EQ(log.counts().at("no texture"), 1u);

  // A reason that keeps coming back is warned again after the period, with what it held back.
  uint64_t held_back = 0;
  EXPECT_FALSE(log.note("unsupported encoding", 4.0, held_back));
  EXPECT_TRUE(log.note("unsupported encoding", 6.0, held_back));
  EXPECT_EQ(held_back, 2u);  // the one at 0.6 s and the one at 4.0 s
  EXPECT_EQ(log.counts().at("unsupported encoding"), 4u);
}

TEST(LiveReconfigure, LiveCoreKeysGoBothWaysByName)
{
  openable_ros::DetectorConfig start;
  dynamic_reconfigure::Config message;
  start.__toMessage__(message);
  openable::Config config;
  config.threshold = 0.25;
  config.sequence_length = 7;
  config.min_candidates = 12;
  config.bidirectional = true;
  openable_ros::LiveReconfigure::fromCore(config, message);
  openable::Config back;
  openable_ros::LiveReconfigure::toCore(message, back);
  for (const auto& key : openable::Config::liveKeys())
    EXPECT_EQ(back.get(key), config.get(key)) << key;
  EXPECT_TRUE(start.__fromMessage__(message));
  EXPECT_DOUBLE_EQ(start.threshold, 0.25);
  EXPECT_EQ(start.min_candidates, 12);
}

TEST(Conversions, Mono16InEitherByteOrderKeepsItsTopByte)
{
  for (const bool big_endian : {false, true})
  {
    auto msg = image(enc::MONO16, 0, 2);
    msg->is_bigendian = big_endian;
    for (size_t i = 0; i + 1 < msg->data.size(); i += 2)
    {
      // 0x1234 in the message's byte order.
      msg->data[i] = big_endian ? 0x12 : 0x34;
      msg->data[i + 1] = big_endian ? 0x34 : 0x12;
    }
    cv::Mat out;
    openable::InputProblem problem;
    ASSERT_TRUE(openable_ros::toCoreImage(msg, out, problem)) << problem.what;
    EXPECT_EQ(out.at<uint8_t>(2, 3), 0x12) << (big_endian ? "big" : "little") << "-endian";
  }
}

TEST(RosParameters, ValuesFromOutsideTheParameterServerAreCheckedAgainstTheTable)
{
  EXPECT_EQ(openable_ros::rosParameterProblem("matrix_size", "512"), "");
  EXPECT_EQ(openable_ros::rosParameterProblem("matrix_size", "5"),
            "~matrix_size: value '5' is not allowed; expected an integer in [16, 4096] (pixels)");
  EXPECT_NE(openable_ros::rosParameterProblem("matrix_rate", "nan"), "");
  EXPECT_NE(openable_ros::rosParameterProblem("matrix_mode", "bogus"), "");
  EXPECT_EQ(openable_ros::rosParameterProblem("matrix_mode", "rolling_window"), "");
}

TEST(LiveReconfigure, OutOfRangeKeysFallBackOneByOne)
{
  openable::Config in_force;
  in_force.threshold = 0.05;
  openable::Config requested = in_force;
  requested.threshold = 5.0;
  requested.sequence_length = 4;
  std::vector<std::string> messages;
  ASSERT_TRUE(openable_ros::fallBackKeyByKey(requested, in_force, "keeping", "the previous values", messages));
  EXPECT_EQ(requested.threshold, 0.05);
  EXPECT_EQ(requested.sequence_length, 4);
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_EQ(messages[0], "~threshold: value '5' is not allowed; expected -1 (off) or a number in [0, 1]; keeping "
                         "threshold = 0.05");
}

TEST(LaunchFiles, OnlyTrulyRequiredArgumentsAreListedAsRequired)
{
  // roslaunch --ros-args lists an argument whose default is "" under "Required Arguments", so a newcomer
  // believed fixed_frame, map_file and manager had to be given. Only replay.launch's bag has no default.
  for (const std::string name : {"mono", "stereo", "panoramic", "kitti", "replay"})
  {
    // The package found at its source, whether or not a workspace's setup was sourced.
    const std::string source = OPENABLE_SOURCE_DIR;
    const std::string command = "ROS_PACKAGE_PATH=" + source + ":$ROS_PACKAGE_PATH roslaunch --ros-args " + source +
                                "/launch/" + name + ".launch 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string out;
    char buffer[4096];
    for (size_t n; (n = fread(buffer, 1, sizeof(buffer), pipe)) > 0;)
      out.append(buffer, n);
    ASSERT_EQ(pclose(pipe), 0) << command << "\n" << out;
    ASSERT_NE(out.find("Optional Arguments:"), std::string::npos) << out;
    const size_t required = out.find("Required Arguments:");
    if (name != "replay")
    {
      EXPECT_EQ(required, std::string::npos) << name << ".launch:\n" << out;
      continue;
    }
    ASSERT_NE(required, std::string::npos) << out;
    const std::string listed = out.substr(required, out.find("Optional Arguments:") - required);
    EXPECT_EQ(listed, "Required Arguments:\n  bag: absolute path of the bag\n") << out;
  }
}
