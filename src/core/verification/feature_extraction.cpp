// GeometricVerifier's features: ORB keypoints of the left image and, for a stereo rig, their depth from the
// right image (row-constrained ORB matching, sub-pixel SAD refinement).
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"
#include "openable/parabola.h"
#include "openable/verification/geometric_verifier.h"

namespace openable
{
namespace
{
// ORB's pyramid: the row tolerance of stereo matching and the keypoint position error grow with it.
constexpr float kOrbScaleFactor = 1.2f;
constexpr int kOrbLevels = 8;
// How far a frame's aspect ratio may differ from the calibration's and still count as a resized copy
// (rounding of odd sizes: 640x360 from 1280x720 is exact, 752x480 halved to 376x240 too).
constexpr double kAspectTolerance = 0.01;

cv::Mat toGrey(const cv::Mat& image)
{
  if (image.channels() == 1)
    return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

std::string sizeText(const cv::Size& size)
{
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

// The image at the calibrated size, so that the one set of intrinsics holds for it.
cv::Mat toCalibratedSize(const cv::Mat& image, const cv::Size& calibrated)
{
  if (calibrated.empty() || image.size() == calibrated)
    return image;
  const double aspect = static_cast<double>(image.cols) / image.rows;
  const double expected = static_cast<double>(calibrated.width) / calibrated.height;
  if (std::abs(aspect / expected - 1.0) > kAspectTolerance)
    throw Error("GeometricVerifier::extract: image " + sizeText(image.size()) + " is not a resized copy of the " +
                sizeText(calibrated) + " the camera was calibrated for (aspect ratio differs)");
  cv::Mat resized;
  cv::resize(image, resized, calibrated, 0, 0, image.cols > calibrated.width ? cv::INTER_AREA : cv::INTER_LINEAR);
  return resized;
}
}  // namespace

FrameFeatures GeometricVerifier::extract(const cv::Mat& left_image, const cv::Mat& right_image, uint64_t id) const
{
  if (left_image.empty())
    throw Error("GeometricVerifier::extract: empty left image");
  if (!right_image.empty() && right_image.size() != left_image.size())
    throw Error("GeometricVerifier::extract: right image " + sizeText(right_image.size()) + " differs from left " +
                sizeText(left_image.size()) + ", expected a rectified pair of equal size");
  const cv::Mat left = toCalibratedSize(left_image, camera_.image_size);
  FrameFeatures features;
  features.id = id;
  features.image_size = left.size();
  const cv::Mat grey = toGrey(left);
  auto orb = cv::ORB::create(params_.max_features, kOrbScaleFactor, kOrbLevels);
  orb->detectAndCompute(grey, cv::noArray(), features.keypoints, features.descriptors);
  if (camera_.stereo() && !right_image.empty())
    stereoDepth(grey, toGrey(toCalibratedSize(right_image, camera_.image_size)), features);
  return features;
}

void GeometricVerifier::stereoDepth(const cv::Mat& left_grey, const cv::Mat& right_grey, FrameFeatures& features) const
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  features.points.assign(features.keypoints.size(), cv::Point3f(nan, nan, nan));
  std::vector<cv::KeyPoint> right_keypoints;
  cv::Mat right_descriptors;
  auto orb = cv::ORB::create(params_.max_features, kOrbScaleFactor, kOrbLevels);
  orb->detectAndCompute(right_grey, cv::noArray(), right_keypoints, right_descriptors);
  if (right_keypoints.empty() || features.keypoints.empty())
    return;

  // Rectified: a left keypoint's partner lies on the same row. Index right keypoints by every row they
  // may match, the tolerance growing with the pyramid level (coarser levels localise worse).
  const int rows = left_grey.rows;
  std::vector<std::vector<int>> by_row(rows);
  for (size_t j = 0; j < right_keypoints.size(); ++j)
  {
    const auto& kp = right_keypoints[j];
    const double tolerance = params_.stereo_max_row_diff_px * std::pow(kOrbScaleFactor, kp.octave);
    const int lo = std::max(0, static_cast<int>(std::floor(kp.pt.y - tolerance)));
    const int hi = std::min(rows - 1, static_cast<int>(std::ceil(kp.pt.y + tolerance)));
    for (int r = lo; r <= hi; ++r)
      by_row[r].push_back(static_cast<int>(j));
  }

  constexpr int kHalf = 5;    // SAD window half size for the sub-pixel refinement
  constexpr int kSearch = 2;  // pixels searched either side of the ORB disparity
  for (size_t i = 0; i < features.keypoints.size(); ++i)
  {
    const auto& kl = features.keypoints[i];
    const int row = std::min(rows - 1, std::max(0, static_cast<int>(std::lround(kl.pt.y))));
    int best = std::numeric_limits<int>::max();
    int second = std::numeric_limits<int>::max();
    int best_j = -1;
    for (int j : by_row[row])
    {
      const auto& kr = right_keypoints[j];
      if (std::abs(kr.octave - kl.octave) > 1)
        continue;
      const double disparity = kl.pt.x - kr.pt.x;
      if (disparity < params_.stereo_min_disparity_px || disparity > params_.stereo_max_disparity_px)
        continue;
      const int d = static_cast<int>(
          cv::norm(features.descriptors.row(static_cast<int>(i)), right_descriptors.row(j), cv::NORM_HAMMING));
      if (d < best)
      {
        second = best;
        best = d;
        best_j = j;
      }
      else if (d < second)
      {
        second = d;
      }
    }
    // Unique and close enough: repeated texture along a row (railings, windows) gives wrong depths.
    if (best_j < 0 || best > params_.stereo_max_hamming ||
        (second != std::numeric_limits<int>::max() && best > 0.9 * second))
      continue;

    // Sub-pixel disparity: SAD of a window around the left keypoint along the right row, parabola through
    // the minimum. ORB positions are integer (and coarser at higher octaves): without this, far points'
    // depths are quantised.
    double disparity = kl.pt.x - right_keypoints[best_j].pt.x;
    const int xl = static_cast<int>(std::lround(kl.pt.x));
    const int yl = row;
    const int xr0 = static_cast<int>(std::lround(right_keypoints[best_j].pt.x));
    if (yl - kHalf >= 0 && yl + kHalf < rows && xl - kHalf >= 0 && xl + kHalf < left_grey.cols &&
        xr0 - kHalf - kSearch - 1 >= 0 && xr0 + kHalf + kSearch + 1 < right_grey.cols)
    {
      const cv::Mat patch = left_grey(cv::Rect(xl - kHalf, yl - kHalf, 2 * kHalf + 1, 2 * kHalf + 1));
      std::vector<double> cost;
      for (int dx = -kSearch - 1; dx <= kSearch + 1; ++dx)
      {
        const cv::Mat other = right_grey(cv::Rect(xr0 + dx - kHalf, yl - kHalf, 2 * kHalf + 1, 2 * kHalf + 1));
        cost.push_back(cv::norm(patch, other, cv::NORM_L1));
      }
      const auto min_it = std::min_element(cost.begin(), cost.end());
      const int k = static_cast<int>(min_it - cost.begin());
      if (k > 0 && k + 1 < static_cast<int>(cost.size()))
      {
        const double xr = xr0 + (k - kSearch - 1) + parabolaMinimum(cost[k - 1], cost[k], cost[k + 1]);
        disparity = xl - xr;
      }
      else
      {
        continue;  // the minimum sits on the search border: the ORB match disagrees with the patch
      }
    }
    if (disparity < params_.stereo_min_disparity_px || disparity > params_.stereo_max_disparity_px)
      continue;
    const double z = camera_.fx * camera_.baseline / disparity;
    features.points[i] =
        cv::Point3f(static_cast<float>((kl.pt.x - camera_.cx) * z / camera_.fx),
                    static_cast<float>((kl.pt.y - camera_.cy) * z / camera_.fy), static_cast<float>(z));
  }
}

}  // namespace openable
