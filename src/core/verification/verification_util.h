#pragma once
// Small helpers shared by the parts of GeometricVerifier (src/core/geometric_verifier.cpp and
// src/core/verification/*.cpp). Not part of the library's interface.

#include <algorithm>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "openable/verification/geometric_verifier.h"

namespace openable
{
namespace verification
{
inline double median(std::vector<double> values)
{
  if (values.empty())
    return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

/// "what value rule limit", the shape of every rejection reason.
inline std::string describe(const char* what, double value, const char* rule, double limit)
{
  std::ostringstream out;
  out << what << " " << value << " " << rule << " " << limit;
  return out.str();
}

/// The ray of pixel p in normalised image coordinates (z = 1).
inline cv::Vec3d normalisedRay(const PinholeCamera& camera, const cv::Point2f& p)
{
  return cv::Vec3d((p.x - camera.cx) / camera.fx, (p.y - camera.cy) / camera.fy, 1.0);
}

inline cv::Matx33d intrinsics(const PinholeCamera& camera)
{
  return cv::Matx33d(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
}

}  // namespace verification
}  // namespace openable
