#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "openable/config.h"

namespace openable
{
/// A rectified pinhole camera (no distortion: images must be rectified, e.g. `image_rect`). A positive
/// baseline makes it a stereo rig whose right camera sits `baseline` metres along the left camera's +x.
struct PinholeCamera
{
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double baseline = 0.0;  ///< metres; 0 = mono
  /// The image size the intrinsics belong to (camera_info width x height); empty = whatever comes. A frame
  /// of another size with the same aspect ratio (a resized copy: one traversal recorded at a lower
  /// resolution) is resized to it before extraction, so one K holds for every frame; another aspect
  /// ratio is refused.
  cv::Size image_size;

  bool valid() const
  {
    return fx > 0.0 && fy > 0.0;
  }
  bool stereo() const
  {
    return baseline > 0.0;
  }
  /// From a rectified 3x4 projection matrix P = K [I | t] (ROS CameraInfo.P, KITTI's P0..P3). For the
  /// right camera of a rectified pair P(0,3) = -fx * baseline, so baseline = -P(0,3) / fx.
  static PinholeCamera fromProjection(const cv::Matx34d& left, const cv::Matx34d& right = cv::Matx34d::zeros());
};

/// Every tunable of the verification. The defaults are those of Config's verify_* keys (tested), which is
/// how the nodelets and openable_offline set them.
struct VerifierParams
{
  int max_features = 1000;           ///< ORB features per frame (the bound on per-frame memory)
  double ratio = 0.8;                ///< Lowe ratio test: best / second-best Hamming distance must be below this
  int max_hamming = 64;              ///< a match with more differing bits (of 256) is discarded
  /// Fewer RANSAC inliers (or ratio-test matches, or keypoints) -> rejected. Chosen on real pairs
  /// (test_verification_real_pairs, doc/results.md): non-revisits reach 10 inliers (Gardens Point far
  /// apart, EuRoC, KITTI; 36 ratio-test matches, so the matches alone cannot tell), true revisits by day
  /// have a median of 22. 15 keeps a 50 % margin over the worst non-revisit; 30 lost 40 % of the true
  /// day/day pairs it accepts.
  int min_inliers = 15;
  double ransac_threshold_px = 2.0;  ///< inlier threshold: reprojection (PnP) or Sampson (mono) error, pixels
  double ransac_confidence = 0.999;
  int ransac_iterations = 2000;  ///< PnP RANSAC iterations
  double min_parallax_deg =
      2.0;  ///< mono: median parallax after derotation below this -> pure rotation / too little baseline
  double identical_max_flow_px = 0.5;  ///< median inlier motion below this -> identical images (rejected)
  // Stereo depth of the keypoints (left/right ORB matched along the rectified row).
  double stereo_max_row_diff_px = 2.0;   ///< |y_left - y_right| allowed at octave 0 (scaled with the octave)
  double stereo_min_disparity_px = 1.0;  ///< smaller disparity (too far, depth unreliable) -> no depth
  double stereo_max_disparity_px = 160.0;
  int stereo_max_hamming = 50;  ///< left/right descriptor distance allowed
  int min_stereo_points = 30;   ///< stereo: fewer match-frame keypoints with depth -> rejected

  /// Human-readable errors ("name: value x, expected ..."); empty when valid.
  std::vector<std::string> validate() const;
};

/// The configuration's verify_* keys as the verifier's parameters (verify_min_inliers -> min_inliers, ...).
/// The one way from YAML, --set or a ROS parameter to the verifier.
VerifierParams verifierParams(const Config& config);

/// The features of one frame, as kept for history frames.
struct FrameFeatures
{
  uint64_t id = 0;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< ORB, CV_8U, one 32-byte row per keypoint
  /// Stereo: per keypoint, the 3D point in this (left, rectified) camera's frame, metres; z = NaN without depth.
  /// Empty for mono frames.
  std::vector<cv::Point3f> points;
  cv::Size image_size;

  size_t depthCount() const;
  /// Heap bytes held (what FeatureStore bounds).
  size_t bytes() const;
};

/// History frames' features under a memory bound: inserting beyond the bound evicts the oldest frames
/// first (the oldest places are the least likely to be revisited by the next few queries, and a loop
/// closure whose match frame was evicted is simply not verified).
class FeatureStore
{
public:
  explicit FeatureStore(size_t max_bytes = 256u << 20);

  /// Stores (or replaces) the features of frame `features.id`, then evicts the oldest until within bound.
  /// A single frame larger than the bound is not stored.
  void insert(FrameFeatures features);
  /// nullptr when the frame was never stored or has been evicted.
  const FrameFeatures* find(uint64_t id) const;
  void clear();

  size_t size() const
  {
    return frames_.size();
  }
  size_t bytes() const
  {
    return bytes_;
  }
  size_t maxBytes() const
  {
    return max_bytes_;
  }
  size_t evicted() const
  {
    return evicted_;
  }

private:
  void evict();

  size_t max_bytes_;
  size_t bytes_ = 0;
  size_t evicted_ = 0;
  std::deque<uint64_t> order_;  // insertion order, oldest first (may hold ids already replaced)
  std::unordered_map<uint64_t, FrameFeatures> frames_;
};

/// Why a candidate was accepted or rejected.
enum class VerificationStatus
{
  Accepted,
  TooFewFeatures,      ///< a frame has fewer keypoints than min_inliers
  TooFewStereoPoints,  ///< stereo: the match frame has too few keypoints with depth
  TooFewMatches,       ///< fewer ratio-test matches than min_inliers
  TooFewInliers,       ///< RANSAC found fewer than min_inliers consistent matches
  IdenticalImages,     ///< inliers barely move: the same image twice, geometry is meaningless
  PureRotation,        ///< mono: no parallax, the translation direction is undefined
  Failed               ///< the estimator returned no model
};
const char* toString(VerificationStatus status);

/// The outcome of verifying a (match, query) pair.
///
/// Pose convention (the one LoopClosure.relative_pose carries): T_match_query, the pose of the query
/// camera expressed in the match camera's frame, so p_match = rotation * p_query + translation and
/// T_world_query = T_world_match * T_match_query. Cameras are the left rectified cameras (x right,
/// y down, z forward).
///
/// Covariance: 6x6 over a right perturbation T_true = T_est * Exp(e), e = (x y z rx ry rz) in the query
/// camera frame (metres, radians). It is the Gauss-Newton covariance s^2 (J^T J)^-1 of the inliers'
/// errors at the solution (reprojection error for PnP, Sampson error for the essential matrix), with the
/// pixel variance s^2 estimated from those same residuals (a posteriori variance factor), so it grows
/// with few or badly spread inliers. It ignores the uncertainty of the stereo depths themselves except
/// through s^2 and is therefore optimistic: backends should treat it as relative weighting.
/// Mono (`metric` false): the translation is a unit direction; the variance along that direction is
/// set to kScaleFreeVariance (scale unknown), the two perpendicular directions carry the direction's
/// uncertainty (at unit length).
struct Verification
{
  static constexpr double kScaleFreeVariance = 1e6;

  VerificationStatus status = VerificationStatus::Failed;
  std::string reason;   ///< empty when accepted; else what failed with the numbers
  bool metric = false;  ///< true: stereo PnP (metres); false: mono, unit translation
  int query_features = 0;
  int match_features = 0;
  int matches = 0;  ///< after the ratio test
  int inliers = 0;
  double rms_error_px = 0.0;  ///< inliers' RMS error at the solution
  double median_flow_px = 0.0;
  double median_parallax_deg = 0.0;  ///< mono only
  cv::Matx33d rotation = cv::Matx33d::eye();
  cv::Vec3d translation = cv::Vec3d(0, 0, 0);
  cv::Matx66d covariance = cv::Matx66d::eye();

  bool accepted() const
  {
    return status == VerificationStatus::Accepted;
  }
};

/// Geometric verification of loop-closure candidates: ORB features, ratio test, then
/// - stereo (camera.stereo() and the match frame has depth): PnP RANSAC of the match frame's 3D points
///   against the query's keypoints, refined by Levenberg-Marquardt on the inliers: metric pose;
/// - mono: RANSAC 5-point essential matrix, cheirality (recoverPose): rotation + translation direction.
/// A candidate is accepted only with enough inliers and non-degenerate geometry.
/// Thread-compatible: const methods may run concurrently.
class GeometricVerifier
{
public:
  /// Throws Error when the camera or the parameters are invalid.
  GeometricVerifier(const PinholeCamera& camera, const VerifierParams& params = VerifierParams());

  const PinholeCamera& camera() const
  {
    return camera_;
  }
  const VerifierParams& params() const
  {
    return params_;
  }

  /// ORB features of a rectified grey (or BGR) left image; with a right image (stereo camera), their
  /// depth. Throws Error on an empty image or a left/right size mismatch.
  FrameFeatures extract(const cv::Mat& left, const cv::Mat& right = cv::Mat(), uint64_t id = 0) const;

  /// Verifies that `query` sees the place of `match`. Never throws on data; see Verification.
  Verification verify(const FrameFeatures& match, const FrameFeatures& query) const;

private:
  void stereoDepth(const cv::Mat& left_grey, const cv::Mat& right_grey, FrameFeatures& features) const;
  void verifyStereo(const FrameFeatures& match, const FrameFeatures& query, const std::vector<cv::DMatch>& matches,
                    Verification& result) const;
  void verifyMono(const FrameFeatures& match, const FrameFeatures& query, const std::vector<cv::DMatch>& matches,
                  Verification& result) const;

  PinholeCamera camera_;
  VerifierParams params_;
};

}  // namespace openable
