#pragma once
// The relative pose's covariance (see Verification): Gauss-Newton s^2 (J^T J)^-1 at the solution, for the
// stereo PnP pose (reprojection errors) and the mono essential-matrix pose (Sampson errors, after a
// Levenberg-Marquardt refinement on all inliers). Internal to GeometricVerifier.

#include <opencv2/core.hpp>
#include <vector>

#include "openable/verification/geometric_verifier.h"

namespace openable
{
namespace verification
{
/// Covariance of T_match_query from the PnP inliers (object = match-frame points, image = query pixels),
/// at T_query_match = (r_qm, t_qm). Also returns the inliers' RMS reprojection error.
cv::Matx66d pnpCovariance(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                          const std::vector<int>& inliers, const cv::Matx33d& r_qm, const cv::Vec3d& t_qm,
                          const PinholeCamera& camera, double& rms_error_px);

/// A mono relative pose refined on its inliers, with its covariance.
struct EssentialRefinement
{
  cv::Matx33d rotation;     ///< R_match_query
  cv::Vec3d translation;    ///< unit direction of t_match_query
  double rms_error_px = 0;  ///< inliers' RMS Sampson error, pixels
  cv::Matx66d covariance;
};

/// Refines T_match_query = (r_mq, t_mq) over the Sampson errors of the inlier rays (normalised image
/// coordinates xm, xq; `focal` turns them into pixels) and computes the covariance at the optimum.
EssentialRefinement refineEssential(const std::vector<cv::Vec3d>& xm, const std::vector<cv::Vec3d>& xq,
                                    const cv::Matx33d& r_mq, const cv::Vec3d& t_mq, double focal);

}  // namespace verification
}  // namespace openable
