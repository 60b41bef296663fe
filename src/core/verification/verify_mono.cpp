// GeometricVerifier's mono path: RANSAC 5-point essential matrix, a parallax check against pure rotation,
// cheirality (recoverPose), then a refinement with covariance: rotation and translation direction.
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include "openable/verification/geometric_verifier.h"
#include "verification/pose_covariance.h"
#include "verification/verification_util.h"

namespace openable
{
namespace
{
using verification::describe;

// Parallax of the inlier correspondences under rotation r_qm: the angle between the two rays once the
// rotation is removed. Zero for every point under a pure rotation, whatever the scene: then the translation
// of the essential matrix is noise (and cheirality fails at random).
double medianParallaxDeg(const PinholeCamera& camera, const std::vector<cv::Point2f>& pm,
                         const std::vector<cv::Point2f>& pq, const cv::Matx33d& r_qm, const cv::Mat& inlier_mask)
{
  std::vector<double> parallax;
  for (size_t i = 0; i < pm.size(); ++i)
  {
    if (!inlier_mask.at<uchar>(static_cast<int>(i)))
      continue;
    const cv::Vec3d ray_q_in_m = r_qm.t() * cv::normalize(verification::normalisedRay(camera, pq[i]));
    const double c =
        std::max(-1.0, std::min(1.0, cv::normalize(verification::normalisedRay(camera, pm[i])).dot(ray_q_in_m)));
    parallax.push_back(std::acos(c) * 180.0 / CV_PI);
  }
  return verification::median(parallax);
}

// RANSAC essential matrix, degeneracy, cheirality: T_query_match (|t_qm| = 1) and the inlier mask, or false
// with `result` saying why.
bool essentialPose(const PinholeCamera& camera, const VerifierParams& params, const std::vector<cv::Point2f>& pm,
                   const std::vector<cv::Point2f>& pq, Verification& result, cv::Mat& mask, cv::Matx33d& r_qm,
                   cv::Vec3d& t_qm)
{
  const cv::Mat k(verification::intrinsics(camera));
  cv::Mat r_mat, t_mat;
  int good = 0;
  try
  {
    const cv::Mat e_all =
        cv::findEssentialMat(pm, pq, k, cv::RANSAC, params.ransac_confidence, params.ransac_threshold_px, mask);
    if (e_all.rows < 3 || e_all.cols != 3 || cv::countNonZero(mask) < params.min_inliers)
    {
      result.inliers = mask.empty() ? 0 : cv::countNonZero(mask);
      result.status = VerificationStatus::TooFewInliers;
      result.reason = describe("essential-matrix RANSAC inliers:", result.inliers, "<", params.min_inliers);
      return false;
    }
    const cv::Mat e = e_all.rowRange(0, 3);
    // Degeneracy before cheirality: E decomposes into two rotations (a twisted pair); under a pure
    // rotation one of them is the true rotation and leaves no parallax.
    cv::Mat r1, r2, t_dir;
    cv::decomposeEssentialMat(e, r1, r2, t_dir);
    result.median_parallax_deg = std::min(medianParallaxDeg(camera, pm, pq, cv::Matx33d(r1), mask),
                                          medianParallaxDeg(camera, pm, pq, cv::Matx33d(r2), mask));
    if (result.median_parallax_deg < params.min_parallax_deg)
    {
      result.inliers = cv::countNonZero(mask);
      result.status = VerificationStatus::PureRotation;
      result.reason = describe("median parallax (deg):", result.median_parallax_deg, "<", params.min_parallax_deg) +
                      ": pure rotation or too short a baseline, translation direction undefined";
      return false;
    }
    good = cv::recoverPose(e, pm, pq, k, r_mat, t_mat, mask);
  }
  catch (const cv::Exception& e)
  {
    result.status = VerificationStatus::Failed;
    result.reason = std::string("essential matrix RANSAC failed: ") + e.what();
    return false;
  }
  result.inliers = good;
  if (good < params.min_inliers)
  {
    result.status = VerificationStatus::TooFewInliers;
    result.reason = describe("essential-matrix inliers in front of both cameras:", good, "<", params.min_inliers);
    return false;
  }
  // recoverPose: p_query = r_qm * p_match + t_qm, |t_qm| = 1.
  r_qm = cv::Matx33d(r_mat);
  t_qm = cv::Vec3d(t_mat.at<double>(0), t_mat.at<double>(1), t_mat.at<double>(2));
  return true;
}
}  // namespace

void GeometricVerifier::verifyMono(const FrameFeatures& match, const FrameFeatures& query,
                                   const std::vector<cv::DMatch>& matches, Verification& result) const
{
  result.metric = false;
  std::vector<cv::Point2f> pm, pq;
  for (const auto& m : matches)
  {
    pm.push_back(match.keypoints[m.trainIdx].pt);
    pq.push_back(query.keypoints[m.queryIdx].pt);
  }
  cv::Mat mask;
  cv::Matx33d r_qm;
  cv::Vec3d t_qm;
  if (!essentialPose(camera_, params_, pm, pq, result, mask, r_qm, t_qm))
    return;
  result.median_parallax_deg = medianParallaxDeg(camera_, pm, pq, r_qm, mask);

  // The RANSAC model comes from 5 points; the refinement uses every inlier in front of both cameras.
  std::vector<cv::Vec3d> xm, xq;
  for (size_t i = 0; i < pm.size(); ++i)
  {
    if (!mask.at<uchar>(static_cast<int>(i)))
      continue;
    xm.push_back(verification::normalisedRay(camera_, pm[i]));
    xq.push_back(verification::normalisedRay(camera_, pq[i]));
  }
  const verification::EssentialRefinement refined =
      verification::refineEssential(xm, xq, r_qm.t(), -(r_qm.t() * t_qm), 0.5 * (camera_.fx + camera_.fy));
  result.rms_error_px = refined.rms_error_px;
  result.covariance = refined.covariance;
  result.rotation = refined.rotation;
  result.translation = refined.translation;
  result.status = VerificationStatus::Accepted;
}

}  // namespace openable
