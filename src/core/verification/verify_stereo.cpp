// GeometricVerifier's stereo path: PnP RANSAC of the match frame's 3D points against the query's keypoints,
// refined on the inliers: a metric T_match_query.
#include <opencv2/calib3d.hpp>

#include "openable/verification/geometric_verifier.h"
#include "verification/pose_covariance.h"
#include "verification/verification_util.h"

namespace openable
{
void GeometricVerifier::verifyStereo(const FrameFeatures& match, const FrameFeatures& query,
                                     const std::vector<cv::DMatch>& matches, Verification& result) const
{
  using verification::describe;
  result.metric = true;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const auto& m : matches)
  {
    object.push_back(match.points[m.trainIdx]);
    image.push_back(query.keypoints[m.queryIdx].pt);
  }
  const cv::Matx33d k = verification::intrinsics(camera_);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  bool ok = false;
  try
  {
    ok = cv::solvePnPRansac(object, image, k, cv::noArray(), rvec, tvec, false, params_.ransac_iterations,
                            static_cast<float>(params_.ransac_threshold_px), params_.ransac_confidence, inliers,
                            cv::SOLVEPNP_AP3P);
  }
  catch (const cv::Exception& e)
  {
    result.status = VerificationStatus::Failed;
    result.reason = std::string("PnP RANSAC failed: ") + e.what();
    return;
  }
  if (!ok || static_cast<int>(inliers.size()) < params_.min_inliers)
  {
    result.inliers = static_cast<int>(inliers.size());
    result.status = VerificationStatus::TooFewInliers;
    result.reason = describe("PnP RANSAC inliers:", result.inliers, "<", params_.min_inliers);
    return;
  }

  // Refine on the inliers, re-select inliers with the refined pose, refine once more: the RANSAC pose
  // comes from 4 points only.
  for (int pass = 0; pass < 2; ++pass)
  {
    std::vector<cv::Point3f> obj_in;
    std::vector<cv::Point2f> img_in;
    for (int i : inliers)
    {
      obj_in.push_back(object[i]);
      img_in.push_back(image[i]);
    }
    cv::solvePnPRefineLM(obj_in, img_in, k, cv::noArray(), rvec, tvec);
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object, rvec, tvec, k, cv::noArray(), projected);
    inliers.clear();
    for (size_t i = 0; i < object.size(); ++i)
      if (cv::norm(projected[i] - image[i]) <= params_.ransac_threshold_px)
        inliers.push_back(static_cast<int>(i));
    if (static_cast<int>(inliers.size()) < params_.min_inliers)
      break;
  }
  result.inliers = static_cast<int>(inliers.size());
  if (result.inliers < params_.min_inliers)
  {
    result.status = VerificationStatus::TooFewInliers;
    result.reason = describe("PnP inliers after refinement:", result.inliers, "<", params_.min_inliers);
    return;
  }

  // T_query_match: p_query = r_qm * p_match + t_qm.
  cv::Matx33d r_qm;
  cv::Rodrigues(rvec, r_qm);
  const cv::Vec3d t_qm(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  result.covariance = verification::pnpCovariance(object, image, inliers, r_qm, t_qm, camera_, result.rms_error_px);
  result.rotation = r_qm.t();
  result.translation = -(r_qm.t() * t_qm);
  result.status = VerificationStatus::Accepted;
}

}  // namespace openable
