// Checker for geometric verification (~verify) in the stereo nodelet: the 40 EuRoC V1_01 pairs, rectified
// here as stereo_image_proc would (calibration from the dataset's sensor.yaml files), with their
// camera_info. With no exclusion window every pair matches the previous one, 50 ms earlier. The MAV stands
// still for the first pairs: those are rejected as identical images (no geometry) and not published; the
// others must carry a verified metric relative pose (stereo PnP) of a few centimetres and a covariance.
// Measured: 6 verified, 33 rejected as identical (doc/ros_api.md quotes the recorded properties).
#include <gtest/gtest.h>
#include <openable_ros/LoopClosure.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>

#include <cmath>
#include <fstream>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "test_helpers.h"

using openable_ros_test::DiagnosticsWatcher;
using openable_ros_test::waitFor;
namespace enc = sensor_msgs::image_encodings;

namespace
{
std::mutex mutex;
std::vector<openable_ros::LoopClosureConstPtr> loops;

void loopCallback(const openable_ros::LoopClosureConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex);
  loops.push_back(msg);
}

/// The numbers after "<key>:" up to the closing bracket (EuRoC sensor.yaml lists), in order.
std::vector<double> numbersAfter(const std::string& text, const std::string& key)
{
  std::vector<double> out;
  size_t at = text.find(key + ":");
  if (at == std::string::npos)
  {
    return out;
  }
  at = text.find('[', at);
  const size_t end = text.find(']', at);
  std::string list = text.substr(at + 1, end - at - 1);
  for (char& c : list)
  {
    c = c == ',' ? ' ' : c;
  }
  std::istringstream in(list);
  double v;
  while (in >> v)
  {
    out.push_back(v);
  }
  return out;
}

struct Camera
{
  cv::Matx33d k;
  cv::Vec4d distortion;
  cv::Matx44d body_T_camera;
};

Camera loadCamera(const std::string& path)
{
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Camera camera;
  const auto intrinsics = numbersAfter(text, "intrinsics");
  const auto distortion = numbersAfter(text, "distortion_coefficients");
  const auto t = numbersAfter(text, "data");
  if (intrinsics.size() != 4 || distortion.size() != 4 || t.size() != 16)
  {
    ADD_FAILURE() << "cannot read the calibration in " << path;
    return camera;
  }
  camera.k = cv::Matx33d(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
  camera.distortion = cv::Vec4d(distortion[0], distortion[1], distortion[2], distortion[3]);
  for (int i = 0; i < 16; ++i)
  {
    camera.body_T_camera(i / 4, i % 4) = t[size_t(i)];
  }
  return camera;
}

sensor_msgs::CameraInfo toInfo(const cv::Mat& p, const cv::Size& size, const ros::Time& stamp, const std::string& frame)
{
  sensor_msgs::CameraInfo info;
  info.header.stamp = stamp;
  info.header.frame_id = frame;
  info.width = uint32_t(size.width);
  info.height = uint32_t(size.height);
  for (int i = 0; i < 12; ++i)
  {
    info.P[size_t(i)] = p.at<double>(i / 4, i % 4);
  }
  info.K = {p.at<double>(0, 0), 0, p.at<double>(0, 2), 0, p.at<double>(1, 1), p.at<double>(1, 2), 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  return info;
}
}  // namespace

TEST(StereoVerification, LoopsCarryAVerifiedMetricRelativePose)
{
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  const std::string dir =
      pnh.param<std::string>("data_dir", OPENABLE_SOURCE_DIR "/../shared/data/stereo/euroc_v101_micro");
  const int min_verified = pnh.param("min_verified", 10);
  DiagnosticsWatcher diagnostics(nh);
  ros::Publisher left_pub = nh.advertise<sensor_msgs::Image>("left/image_rect", 50);
  ros::Publisher right_pub = nh.advertise<sensor_msgs::Image>("right/image_rect", 50);
  ros::Publisher left_info_pub = nh.advertise<sensor_msgs::CameraInfo>("left/camera_info", 50);
  ros::Publisher right_info_pub = nh.advertise<sensor_msgs::CameraInfo>("right/camera_info", 50);
  ros::Subscriber sub = nh.subscribe("loop_closures", 100, loopCallback);
  ASSERT_TRUE(waitFor(
      [&]
      {
        return left_pub.getNumSubscribers() > 0 && right_pub.getNumSubscribers() > 0 &&
               left_info_pub.getNumSubscribers() > 0 && right_info_pub.getNumSubscribers() > 0;
      },
      30.0));

  const Camera left = loadCamera(dir + "/cam0/sensor.yaml");
  const Camera right = loadCamera(dir + "/cam1/sensor.yaml");
  const cv::Size size(752, 480);
  // stereoRectify wants p_right = R p_left + T.
  const cv::Matx44d right_T_left = right.body_T_camera.inv() * left.body_T_camera;
  const cv::Matx33d r = right_T_left.get_minor<3, 3>(0, 0);
  const cv::Vec3d t(right_T_left(0, 3), right_T_left(1, 3), right_T_left(2, 3));
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(left.k, left.distortion, right.k, right.distortion, size, r, t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0.0);
  cv::Mat lx, ly, rx, ry;
  cv::initUndistortRectifyMap(left.k, left.distortion, r1, p1, size, CV_32FC1, lx, ly);
  cv::initUndistortRectifyMap(right.k, right.distortion, r2, p2, size, CV_32FC1, rx, ry);

  // The calibration first: the verifier is built from it, so that every pair gets features.
  ASSERT_TRUE(waitFor(
      [&]
      {
        left_info_pub.publish(toInfo(p1, size, ros::Time(1.0), "cam0_rect"));
        right_info_pub.publish(toInfo(p2, size, ros::Time(1.0), "cam1_rect"));
        ros::WallDuration(0.2).sleep();
        return diagnostics.value("verification") == "on";
      },
      20.0))
      << "the detector did not build its verifier from camera_info";

  std::ifstream csv(dir + "/cam0/data.csv");
  std::string line;
  int pairs = 0;
  ros::WallRate rate(10.0);
  while (std::getline(csv, line))
  {
    if (line.empty() || line[0] == '#')
    {
      continue;
    }
    const size_t comma = line.find(',');
    ros::Time stamp;
    stamp.fromNSec(std::stoull(line.substr(0, comma)));
    std::string file = line.substr(comma + 1);
    while (!file.empty() && (file.back() == '\r' || file.back() == ' '))
    {
      file.pop_back();
    }
    cv::Mat l, rr;
    cv::remap(cv::imread(dir + "/cam0/data/" + file, cv::IMREAD_GRAYSCALE), l, lx, ly, cv::INTER_LINEAR);
    cv::remap(cv::imread(dir + "/cam1/data/" + file, cv::IMREAD_GRAYSCALE), rr, rx, ry, cv::INTER_LINEAR);
    left_info_pub.publish(toInfo(p1, size, stamp, "cam0_rect"));
    right_info_pub.publish(toInfo(p2, size, stamp, "cam1_rect"));
    left_pub.publish(openable_ros_test::toMsg(l, enc::MONO8, stamp, "cam0_rect"));
    right_pub.publish(openable_ros_test::toMsg(rr, enc::MONO8, stamp, "cam1_rect"));
    ++pairs;
    rate.sleep();
  }
  ASSERT_EQ(pairs, 40);
  ASSERT_TRUE(waitFor([&] { return diagnostics.number("frames received") == 40; }, 30.0));
  ASSERT_TRUE(waitFor([&] { return diagnostics.value("verification") == "on"; }, 5.0));
  ASSERT_TRUE(waitFor(
      [&]
      {
        std::lock_guard<std::mutex> lock(mutex);
        return diagnostics.number("loop closures") == long(loops.size());
      },
      10.0));
  std::lock_guard<std::mutex> lock(mutex);
  int verified = 0;
  int unverified = 0;
  for (const auto& loop : loops)
  {
    // ~verify_required: a loop that fails verification is not published; one that could not be verified
    // (its match arrived before the first camera_info built the verifier) goes out without relative pose.
    if (!loop->has_relative_pose)
    {
      ++unverified;
      continue;
    }
    ++verified;
    const auto& p = loop->relative_pose.pose.position;
    const double metres = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    // A MAV at walking speed moves a few centimetres per 50 ms: metric, small, not zero.
    EXPECT_LT(metres, 0.3) << "query " << loop->query_id << " -> " << loop->match_id;
    EXPECT_GT(loop->relative_pose.covariance[0], 0.0);
    EXPECT_GT(loop->relative_pose.covariance[35], 0.0);
  }
  std::printf(
      "stereo verification: %d verified and %d unverified loop closures of 39 possible; rejected as "
      "identical images %ld, accepted %ld\n",
      verified, unverified, diagnostics.number("verification: identical images"),
      diagnostics.number("verification: accepted"));
  // Quoted in doc/ros_api.md; test/docs/check_doc_numbers.py compares the docs with these.
  RecordProperty("verified", verified);
  RecordProperty("unverified", unverified);
  RecordProperty("identical_images", std::to_string(diagnostics.number("verification: identical images")));
  EXPECT_EQ(unverified, 0);
  EXPECT_GE(verified, min_verified);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_stereo_verification");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
