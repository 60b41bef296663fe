// The camera_info a calibrated EuRoC stereo rig publishes with its raw images: intrinsics and distortion
// from the dataset's sensor yaml files (sensorLeft.yaml / sensorRight.yaml, cam0|1/sensor.yaml), with the
// rectification (R, P) computed from their body-to-camera extrinsics, as camera_calibration would store it.
// This is what stereo_image_proc needs to rectify and compute disparity.
#pragma once

#include <gtest/gtest.h>
#include <sensor_msgs/CameraInfo.h>

#include <array>
#include <fstream>
#include <iterator>
#include <opencv2/calib3d.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace openable_ros_test
{
/// The numbers of the `key: [a, b, ...]` list in a EuRoC sensor yaml, in order (empty if missing).
inline std::vector<double> eurocList(const std::string& text, const std::string& key)
{
  std::vector<double> values;
  const size_t at = text.find(key + ":");
  const size_t open = at == std::string::npos ? at : text.find('[', at);
  const size_t close = open == std::string::npos ? open : text.find(']', open);
  if (close == std::string::npos)
  {
    return values;
  }
  std::string list = text.substr(open + 1, close - open - 1);
  for (char& c : list)
  {
    c = (c == ',') ? ' ' : c;
  }
  std::istringstream in(list);
  for (double v; in >> v;)
  {
    values.push_back(v);
  }
  return values;
}

struct EurocCamera
{
  cv::Matx33d k = cv::Matx33d::eye();
  std::array<double, 4> distortion{};  // radial-tangential k1, k2, p1, p2
  cv::Matx44d body_T_camera = cv::Matx44d::eye();
};

/// Adds a gtest failure (and returns an identity camera) when the file does not hold a pinhole camera.
inline EurocCamera loadEurocCamera(const std::string& path)
{
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::vector<double> intrinsics = eurocList(text, "intrinsics");
  const std::vector<double> distortion = eurocList(text, "distortion_coefficients");
  const std::vector<double> extrinsics = eurocList(text, "data");
  EurocCamera camera;
  if (intrinsics.size() != 4 || distortion.size() != 4 || extrinsics.size() != 16)
  {
    ADD_FAILURE() << path << ": expected intrinsics (4), distortion_coefficients (4) and T_BS data (16)";
    return camera;
  }
  camera.k = cv::Matx33d(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
  for (size_t i = 0; i < 4; ++i)
  {
    camera.distortion[i] = distortion[i];
  }
  for (int i = 0; i < 16; ++i)
  {
    camera.body_T_camera(i / 4, i % 4) = extrinsics[size_t(i)];
  }
  return camera;
}

/// camera_info of the left and right raw cameras of a rectified stereo pair (plumb_bob distortion, R and
/// P from cv::stereoRectify; the right P carries -fx * baseline as ROS expects).
inline std::array<sensor_msgs::CameraInfo, 2> eurocStereoInfo(const EurocCamera& left, const EurocCamera& right,
                                                              const cv::Size& size)
{
  // stereoRectify wants p_right = R p_left + T.
  const cv::Matx44d right_T_left = right.body_T_camera.inv() * left.body_T_camera;
  const cv::Matx33d rotation = right_T_left.get_minor<3, 3>(0, 0);
  const cv::Vec3d translation(right_T_left(0, 3), right_T_left(1, 3), right_T_left(2, 3));
  const cv::Vec4d left_d(left.distortion[0], left.distortion[1], left.distortion[2], left.distortion[3]);
  const cv::Vec4d right_d(right.distortion[0], right.distortion[1], right.distortion[2], right.distortion[3]);
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(left.k, left_d, right.k, right_d, size, rotation, translation, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0.0);
  std::array<sensor_msgs::CameraInfo, 2> infos;
  const EurocCamera* cameras[2] = {&left, &right};
  const cv::Mat* rectifications[2] = {&r1, &r2};
  const cv::Mat* projections[2] = {&p1, &p2};
  for (size_t c = 0; c < 2; ++c)
  {
    sensor_msgs::CameraInfo& info = infos[c];
    info.width = uint32_t(size.width);
    info.height = uint32_t(size.height);
    info.distortion_model = "plumb_bob";
    info.D = {cameras[c]->distortion[0], cameras[c]->distortion[1], cameras[c]->distortion[2],
              cameras[c]->distortion[3], 0.0};
    for (int i = 0; i < 9; ++i)
    {
      info.K[size_t(i)] = cameras[c]->k(i / 3, i % 3);
      info.R[size_t(i)] = rectifications[c]->at<double>(i / 3, i % 3);
    }
    for (int i = 0; i < 12; ++i)
    {
      info.P[size_t(i)] = projections[c]->at<double>(i / 4, i % 4);
    }
  }
  return infos;
}

}  // namespace openable_ros_test
