// GeometricVerifier: its parameters, and the policy of verify() shared by the stereo and mono paths
// (enough features, ratio test, identical images). Its parts live in src/core/verification/: features
// (feature_extraction.cpp, feature_store.cpp), the two estimators (verify_mono.cpp, verify_stereo.cpp)
// and the covariance (pose_covariance.cpp).
#include "openable/verification/geometric_verifier.h"

#include <cmath>
#include <opencv2/features2d.hpp>

#include "openable/error.h"
#include "verification/verification_util.h"

namespace openable
{
using verification::describe;
using verification::median;

namespace
{
// Ratio test, then one query keypoint per match keypoint (the closest), so RANSAC sees no duplicates.
std::vector<cv::DMatch> ratioTestMatches(const FrameFeatures& match, const FrameFeatures& query,
                                         const VerifierParams& params)
{
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query.descriptors, match.descriptors, knn, 2);
  std::vector<int> best_for_train(match.keypoints.size(), -1);
  std::vector<cv::DMatch> candidates;
  for (const auto& pair : knn)
  {
    if (pair.empty() || pair[0].distance > params.max_hamming)
      continue;
    if (pair.size() > 1 && pair[0].distance >= params.ratio * pair[1].distance)
      continue;
    const cv::DMatch& m = pair[0];
    int& slot = best_for_train[m.trainIdx];
    if (slot < 0)
    {
      slot = static_cast<int>(candidates.size());
      candidates.push_back(m);
    }
    else if (m.distance < candidates[slot].distance)
    {
      candidates[slot] = m;
    }
  }
  return candidates;
}
}  // namespace

PinholeCamera PinholeCamera::fromProjection(const cv::Matx34d& left, const cv::Matx34d& right)
{
  PinholeCamera camera;
  camera.fx = left(0, 0);
  camera.fy = left(1, 1);
  camera.cx = left(0, 2);
  camera.cy = left(1, 2);
  // P_right(0,3) = -fx * baseline (+ the left camera's own offset, zero for the reference camera).
  if (right(0, 0) > 0.0)
    camera.baseline = (left(0, 3) - right(0, 3)) / right(0, 0);
  return camera;
}

std::vector<std::string> VerifierParams::validate() const
{
  std::vector<std::string> errors;
  auto check = [&errors](bool ok, const std::string& text)
  {
    if (!ok)
      errors.push_back(text);
  };
  check(max_features >= 50, "max_features: " + std::to_string(max_features) + ", expected >= 50");
  check(ratio > 0.0 && ratio <= 1.0, "ratio: " + std::to_string(ratio) + ", expected in (0, 1]");
  check(max_hamming > 0 && max_hamming <= 256,
        "max_hamming: " + std::to_string(max_hamming) + ", expected in [1, 256]");
  check(min_inliers >= 8,
        "min_inliers: " + std::to_string(min_inliers) + ", expected >= 8 (a pose needs more than the minimal set)");
  check(ransac_threshold_px > 0.0, "ransac_threshold_px: " + std::to_string(ransac_threshold_px) + ", expected > 0");
  check(ransac_confidence > 0.0 && ransac_confidence < 1.0,
        "ransac_confidence: " + std::to_string(ransac_confidence) + ", expected in (0, 1)");
  check(ransac_iterations >= 10, "ransac_iterations: " + std::to_string(ransac_iterations) + ", expected >= 10");
  check(min_parallax_deg >= 0.0, "min_parallax_deg: " + std::to_string(min_parallax_deg) + ", expected >= 0");
  check(identical_max_flow_px >= 0.0,
        "identical_max_flow_px: " + std::to_string(identical_max_flow_px) + ", expected >= 0");
  check(stereo_max_row_diff_px > 0.0,
        "stereo_max_row_diff_px: " + std::to_string(stereo_max_row_diff_px) + ", expected > 0");
  check(stereo_min_disparity_px > 0.0 && stereo_min_disparity_px < stereo_max_disparity_px,
        "stereo_min_disparity_px / stereo_max_disparity_px: " + std::to_string(stereo_min_disparity_px) + " / " +
            std::to_string(stereo_max_disparity_px) + ", expected 0 < min < max");
  check(stereo_max_hamming > 0 && stereo_max_hamming <= 256,
        "stereo_max_hamming: " + std::to_string(stereo_max_hamming) + ", expected in [1, 256]");
  check(min_stereo_points >= 4, "min_stereo_points: " + std::to_string(min_stereo_points) + ", expected >= 4");
  return errors;
}

VerifierParams verifierParams(const Config& config)
{
  VerifierParams params;
  params.max_features = config.verify_max_features;
  params.ratio = config.verify_ratio;
  params.max_hamming = config.verify_max_hamming;
  params.min_inliers = config.verify_min_inliers;
  params.ransac_threshold_px = config.verify_ransac_threshold_px;
  params.ransac_confidence = config.verify_ransac_confidence;
  params.ransac_iterations = config.verify_ransac_iterations;
  params.min_parallax_deg = config.verify_min_parallax_deg;
  params.identical_max_flow_px = config.verify_identical_max_flow_px;
  params.stereo_max_row_diff_px = config.verify_stereo_max_row_diff_px;
  params.stereo_min_disparity_px = config.verify_stereo_min_disparity_px;
  params.stereo_max_disparity_px = config.verify_stereo_max_disparity_px;
  params.stereo_max_hamming = config.verify_stereo_max_hamming;
  params.min_stereo_points = config.verify_min_stereo_points;
  return params;
}

const char* toString(VerificationStatus status)
{
  switch (status)
  {
    case VerificationStatus::Accepted:
      return "accepted";
    case VerificationStatus::TooFewFeatures:
      return "too few features";
    case VerificationStatus::TooFewStereoPoints:
      return "too few stereo points";
    case VerificationStatus::TooFewMatches:
      return "too few matches";
    case VerificationStatus::TooFewInliers:
      return "too few inliers";
    case VerificationStatus::IdenticalImages:
      return "identical images";
    case VerificationStatus::PureRotation:
      return "pure rotation";
    case VerificationStatus::Failed:
      return "failed";
  }
  return "unknown";
}

GeometricVerifier::GeometricVerifier(const PinholeCamera& camera, const VerifierParams& params)
  : camera_(camera), params_(params)
{
  if (!camera_.valid())
    throw Error("GeometricVerifier: camera focal lengths fx=" + std::to_string(camera_.fx) +
                " fy=" + std::to_string(camera_.fy) + ", expected > 0 (is the camera calibrated?)");
  if (camera_.baseline < 0.0)
    throw Error("GeometricVerifier: stereo baseline " + std::to_string(camera_.baseline) +
                " m, expected >= 0 (right camera's P(0,3) must be -fx * baseline)");
  if (camera_.image_size.width < 0 || camera_.image_size.height < 0)
    throw Error("GeometricVerifier: camera image size " + std::to_string(camera_.image_size.width) + "x" +
                std::to_string(camera_.image_size.height) + ", expected positive (or 0x0 for any)");
  const auto errors = params_.validate();
  if (!errors.empty())
  {
    std::string text = "GeometricVerifier: invalid parameters:";
    for (const auto& e : errors)
      text += "\n  " + e;
    throw Error(text);
  }
}

Verification GeometricVerifier::verify(const FrameFeatures& match, const FrameFeatures& query) const
{
  Verification result;
  result.query_features = static_cast<int>(query.keypoints.size());
  result.match_features = static_cast<int>(match.keypoints.size());
  result.covariance = cv::Matx66d::zeros();
  if (result.query_features < params_.min_inliers || result.match_features < params_.min_inliers ||
      query.descriptors.empty() || match.descriptors.empty())
  {
    result.status = VerificationStatus::TooFewFeatures;
    result.reason = "features: match " + std::to_string(result.match_features) + ", query " +
                    std::to_string(result.query_features) + ", need >= min_inliers " +
                    std::to_string(params_.min_inliers) + " in each (textureless or dark image?)";
    return result;
  }
  const bool stereo = camera_.stereo() && !match.points.empty();
  if (stereo && static_cast<int>(match.depthCount()) < params_.min_stereo_points)
  {
    result.status = VerificationStatus::TooFewStereoPoints;
    result.reason = describe("match frame keypoints with stereo depth:", static_cast<double>(match.depthCount()), "<",
                             params_.min_stereo_points);
    return result;
  }

  std::vector<cv::DMatch> matches;
  std::vector<double> flow;
  for (const auto& m : ratioTestMatches(match, query, params_))
  {
    if (stereo && !std::isfinite(match.points[m.trainIdx].z))
      continue;  // PnP needs the match frame's depth
    matches.push_back(m);
    flow.push_back(cv::norm(query.keypoints[m.queryIdx].pt - match.keypoints[m.trainIdx].pt));
  }
  result.matches = static_cast<int>(matches.size());
  if (result.matches < params_.min_inliers)
  {
    result.status = VerificationStatus::TooFewMatches;
    result.reason = describe(stereo ? "ratio-test matches with depth:" : "ratio-test matches:", result.matches, "<",
                             params_.min_inliers);
    return result;
  }
  // The same image twice: every match has zero motion. Nothing can be estimated (mono) and nothing is
  // learnt (stereo: a duplicated frame is not a revisit). Checked before RANSAC, over all matches.
  result.median_flow_px = median(flow);
  if (result.median_flow_px < params_.identical_max_flow_px)
  {
    result.status = VerificationStatus::IdenticalImages;
    result.reason =
        describe("median keypoint motion (px):", result.median_flow_px, "<", params_.identical_max_flow_px) +
        ": identical images (the same frame twice?)";
    return result;
  }
  if (stereo)
    verifyStereo(match, query, matches, result);
  else
    verifyMono(match, query, matches, result);
  return result;
}

}  // namespace openable
