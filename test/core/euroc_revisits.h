#pragma once
// The EuRoC MAV V1_01 revisits of ../shared/data/stereo/euroc_v101_revisits (ETH ASL), rectified once as
// stereo_image_proc would, with Vicon poses: shared by the verifier's tests.

#include <cmath>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "openable/verification/geometric_verifier.h"

namespace openable_test
{
namespace euroc
{
inline const std::string kDir = std::string(OPENABLE_SOURCE_DIR) + "/../shared/data/stereo/euroc_v101_revisits/";

struct SensorCalibration
{
  cv::Matx44d body_T_sensor;  // EuRoC T_BS: sensor points into the body (IMU) frame
  cv::Matx33d k;
  std::vector<double> distortion;
  cv::Size size;
};

inline SensorCalibration loadSensor(const std::string& file)
{
  cv::FileStorage fs(kDir + file, cv::FileStorage::READ);
  if (!fs.isOpened())
    throw std::runtime_error("cannot open " + kDir + file);
  SensorCalibration s;
  std::vector<double> data, intrinsics;
  std::vector<int> resolution;
  fs["T_BS"]["data"] >> data;
  fs["intrinsics"] >> intrinsics;
  fs["distortion_coefficients"] >> s.distortion;
  fs["resolution"] >> resolution;
  for (int i = 0; i < 16; ++i)
    s.body_T_sensor.val[i] = data.at(i);
  s.k = cv::Matx33d(intrinsics.at(0), 0, intrinsics.at(2), 0, intrinsics.at(1), intrinsics.at(3), 0, 0, 1);
  s.size = cv::Size(resolution.at(0), resolution.at(1));
  return s;
}

inline cv::Matx44d inverse(const cv::Matx44d& t)
{
  const cv::Matx33d r = t.get_minor<3, 3>(0, 0);
  const cv::Vec3d p(t(0, 3), t(1, 3), t(2, 3));
  const cv::Matx33d rt = r.t();
  const cv::Vec3d q = -(rt * p);
  return cv::Matx44d(rt(0, 0), rt(0, 1), rt(0, 2), q[0], rt(1, 0), rt(1, 1), rt(1, 2), q[1], rt(2, 0), rt(2, 1),
                     rt(2, 2), q[2], 0, 0, 0, 1);
}

inline cv::Matx44d fromRotationTranslation(const cv::Matx33d& r, const cv::Vec3d& t)
{
  return cv::Matx44d(r(0, 0), r(0, 1), r(0, 2), t[0], r(1, 0), r(1, 1), r(1, 2), t[1], r(2, 0), r(2, 1), r(2, 2), t[2],
                     0, 0, 0, 1);
}

// Vicon world_T_body of each pair, from gt_poses.txt (qw qx qy qz tx ty tz).
inline std::vector<cv::Matx44d> loadGroundTruth()
{
  std::ifstream in(kDir + "gt_poses.txt");
  std::vector<cv::Matx44d> poses;
  std::string line;
  while (std::getline(in, line))
  {
    if (line.empty() || line[0] == '#')
      continue;
    std::istringstream fields(line);
    std::string name, stamp;
    double qw, qx, qy, qz, tx, ty, tz;
    fields >> name >> stamp >> qw >> qx >> qy >> qz >> tx >> ty >> tz;
    const double n = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
    qw /= n, qx /= n, qy /= n, qz /= n;
    const cv::Matx33d r(1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw),
                        2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw),
                        2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy));
    poses.push_back(fromRotationTranslation(r, cv::Vec3d(tx, ty, tz)));
  }
  return poses;
}

/// The four pairs rectified, their camera (baseline from the right projection) and Vicon camera poses.
struct Revisits
{
  cv::Mat left[4];
  cv::Mat right[4];
  cv::Matx44d world_T_camera[4];
  openable::PinholeCamera camera;

  /// Ground truth T_match_query (the convention of Verification).
  cv::Matx44d truth(int match, int query) const
  {
    return inverse(world_T_camera[match]) * world_T_camera[query];
  }
};

/// Throws std::runtime_error when a file is missing.
inline Revisits loadRevisits()
{
  Revisits out;
  const SensorCalibration left = loadSensor("sensorLeft.yaml");
  const SensorCalibration right = loadSensor("sensorRight.yaml");
  // stereoRectify wants p_right = R p_left + T.
  const cv::Matx44d right_T_left = inverse(right.body_T_sensor) * left.body_T_sensor;
  const cv::Matx33d r = right_T_left.get_minor<3, 3>(0, 0);
  const cv::Vec3d t(right_T_left(0, 3), right_T_left(1, 3), right_T_left(2, 3));
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(left.k, left.distortion, right.k, right.distortion, left.size, r, t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0.0);
  cv::Mat lx, ly, rx, ry;
  cv::initUndistortRectifyMap(left.k, left.distortion, r1, p1, left.size, CV_32FC1, lx, ly);
  cv::initUndistortRectifyMap(right.k, right.distortion, r2, p2, right.size, CV_32FC1, rx, ry);
  for (int i = 0; i < 4; ++i)
  {
    const cv::Mat l = cv::imread(kDir + "left_img_" + std::to_string(i) + ".png", cv::IMREAD_GRAYSCALE);
    const cv::Mat rr = cv::imread(kDir + "right_img_" + std::to_string(i) + ".png", cv::IMREAD_GRAYSCALE);
    if (l.empty() || rr.empty())
      throw std::runtime_error("cannot read EuRoC pair " + std::to_string(i) + " in " + kDir);
    cv::remap(l, out.left[i], lx, ly, cv::INTER_LINEAR);
    cv::remap(rr, out.right[i], rx, ry, cv::INTER_LINEAR);
  }
  out.camera = openable::PinholeCamera::fromProjection(cv::Matx34d(p1), cv::Matx34d(p2));
  // world_T_rectified = world_T_body * body_T_left * left_T_rectified, with p_rect = R1 p_left.
  const cv::Matx44d left_T_rect = fromRotationTranslation(cv::Matx33d(r1).t(), cv::Vec3d(0, 0, 0));
  const auto body = loadGroundTruth();
  if (body.size() != 4u)
    throw std::runtime_error("expected 4 poses in " + kDir + "gt_poses.txt");
  for (int i = 0; i < 4; ++i)
    out.world_T_camera[i] = body[i] * left.body_T_sensor * left_T_rect;
  return out;
}

}  // namespace euroc
}  // namespace openable_test
