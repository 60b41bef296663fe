#include "openable/geometric_verifier.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "openable/error.h"

namespace openable
{
namespace
{
// ORB's pyramid: the row tolerance of stereo matching and the keypoint position error grow with it.
constexpr float kOrbScaleFactor = 1.2f;
constexpr int kOrbLevels = 8;

cv::Mat toGrey(const cv::Mat& image)
{
  if (image.channels() == 1)
    return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

double median(std::vector<double> values)
{
  if (values.empty())
    return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  return values[mid];
}

cv::Matx33d skew(const cv::Vec3d& v)
{
  return cv::Matx33d(0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0);
}

cv::Matx33d expSo3(const cv::Vec3d& phi)
{
  cv::Matx33d r;
  cv::Rodrigues(phi, r);
  return r;
}

// Two unit vectors spanning the plane perpendicular to unit vector u.
void tangentBasis(const cv::Vec3d& u, cv::Vec3d& b1, cv::Vec3d& b2)
{
  const cv::Vec3d helper = std::abs(u[0]) < 0.9 ? cv::Vec3d(1, 0, 0) : cv::Vec3d(0, 1, 0);
  b1 = cv::normalize(u.cross(helper));
  b2 = u.cross(b1);
}

// Signed Sampson error of x_q^T E x_m = 0 (normalised image coordinates): the first-order distance of the
// correspondence to the epipolar constraint.
double sampson(const cv::Matx33d& e, const cv::Vec3d& xm, const cv::Vec3d& xq)
{
  const cv::Vec3d exm = e * xm;
  const cv::Vec3d etxq = e.t() * xq;
  const double denom = exm[0] * exm[0] + exm[1] * exm[1] + etxq[0] * etxq[0] + etxq[1] * etxq[1];
  if (denom <= 0.0)
    return 0.0;
  return xq.dot(exm) / std::sqrt(denom);
}

// (J^T J)^-1 scaled by s^2; falls back to the pseudo-inverse when J^T J is singular (then the unobservable
// directions get zero variance, which the caller avoids by rejecting degenerate geometry first).
cv::Mat gaussNewtonCovariance(const cv::Mat& jacobian, double variance)
{
  cv::Mat jtj = jacobian.t() * jacobian;
  cv::Mat inverse;
  if (cv::invert(jtj, inverse, cv::DECOMP_CHOLESKY) == 0.0)
    cv::invert(jtj, inverse, cv::DECOMP_SVD);
  return inverse * variance;
}

std::string describe(const char* what, double value, const char* rule, double limit)
{
  std::ostringstream out;
  out << what << " " << value << " " << rule << " " << limit;
  return out.str();
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

size_t FrameFeatures::depthCount() const
{
  size_t count = 0;
  for (const auto& p : points)
    count += std::isfinite(p.z) ? 1 : 0;
  return count;
}

size_t FrameFeatures::bytes() const
{
  return sizeof(FrameFeatures) + keypoints.capacity() * sizeof(cv::KeyPoint) +
         descriptors.total() * descriptors.elemSize() + points.capacity() * sizeof(cv::Point3f);
}

FeatureStore::FeatureStore(size_t max_bytes) : max_bytes_(max_bytes) {}

void FeatureStore::insert(FrameFeatures features)
{
  const size_t size = features.bytes();
  if (size > max_bytes_)
    return;
  const uint64_t id = features.id;
  auto it = frames_.find(id);
  if (it != frames_.end())
  {
    bytes_ -= it->second.bytes();
    it->second = std::move(features);
  }
  else
  {
    frames_.emplace(id, std::move(features));
  }
  order_.push_back(id);
  bytes_ += size;
  evict();
}

void FeatureStore::evict()
{
  while (bytes_ > max_bytes_ && !order_.empty())
  {
    const uint64_t id = order_.front();
    order_.pop_front();
    // A replaced frame appears twice in order_; only its last occurrence owns it.
    if (std::find(order_.begin(), order_.end(), id) != order_.end())
      continue;
    auto it = frames_.find(id);
    if (it == frames_.end())
      continue;
    bytes_ -= it->second.bytes();
    frames_.erase(it);
    ++evicted_;
  }
}

const FrameFeatures* FeatureStore::find(uint64_t id) const
{
  auto it = frames_.find(id);
  return it == frames_.end() ? nullptr : &it->second;
}

void FeatureStore::clear()
{
  frames_.clear();
  order_.clear();
  bytes_ = 0;
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
  const auto errors = params_.validate();
  if (!errors.empty())
  {
    std::string text = "GeometricVerifier: invalid parameters:";
    for (const auto& e : errors)
      text += "\n  " + e;
    throw Error(text);
  }
}

FrameFeatures GeometricVerifier::extract(const cv::Mat& left, const cv::Mat& right, uint64_t id) const
{
  if (left.empty())
    throw Error("GeometricVerifier::extract: empty left image");
  if (!right.empty() && right.size() != left.size())
    throw Error("GeometricVerifier::extract: right image " + std::to_string(right.cols) + "x" +
                std::to_string(right.rows) + " differs from left " + std::to_string(left.cols) + "x" +
                std::to_string(left.rows) + ", expected a rectified pair of equal size");
  FrameFeatures features;
  features.id = id;
  features.image_size = left.size();
  const cv::Mat grey = toGrey(left);
  auto orb = cv::ORB::create(params_.max_features, kOrbScaleFactor, kOrbLevels);
  orb->detectAndCompute(grey, cv::noArray(), features.keypoints, features.descriptors);
  if (camera_.stereo() && !right.empty())
    stereoDepth(grey, toGrey(right), features);
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
        const double c0 = cost[k - 1], c1 = cost[k], c2 = cost[k + 1];
        const double denom = c0 - 2.0 * c1 + c2;
        const double offset = denom > 0.0 ? 0.5 * (c0 - c2) / denom : 0.0;
        const double xr = xr0 + (k - kSearch - 1) + offset;
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

  // Ratio test, then one query keypoint per match keypoint (the closest), so RANSAC sees no duplicates.
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(query.descriptors, match.descriptors, knn, 2);
  std::vector<int> best_for_train(match.keypoints.size(), -1);
  std::vector<cv::DMatch> candidates;
  for (const auto& pair : knn)
  {
    if (pair.empty() || pair[0].distance > params_.max_hamming)
      continue;
    if (pair.size() > 1 && pair[0].distance >= params_.ratio * pair[1].distance)
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
  std::vector<cv::DMatch> matches;
  std::vector<double> flow;
  for (const auto& m : candidates)
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

void GeometricVerifier::verifyStereo(const FrameFeatures& match, const FrameFeatures& query,
                                     const std::vector<cv::DMatch>& matches, Verification& result) const
{
  result.metric = true;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (const auto& m : matches)
  {
    object.push_back(match.points[m.trainIdx]);
    image.push_back(query.keypoints[m.queryIdx].pt);
  }
  const cv::Matx33d k(camera_.fx, 0, camera_.cx, 0, camera_.fy, camera_.cy, 0, 0, 1);
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

  // Covariance. Left perturbation of T_query_match, T' = Exp(d) T: p_q' = p_q + d_t + d_phi x p_q, so
  // d p_q / d(d_t, d_phi) = [I, -[p_q]x], chained with the projection's Jacobian. Inverting,
  // T_match_query' = T_match_query Exp(-d): the same covariance holds for the right perturbation of
  // T_match_query that Verification documents.
  const int n = result.inliers;
  cv::Mat jacobian(2 * n, 6, CV_64F);
  double sum_sq = 0.0;
  for (int idx = 0; idx < n; ++idx)
  {
    const int i = inliers[idx];
    const cv::Vec3d pm(object[i].x, object[i].y, object[i].z);
    const cv::Vec3d pq = r_qm * pm + t_qm;
    const double iz = 1.0 / pq[2];
    const double u = camera_.fx * pq[0] * iz + camera_.cx;
    const double v = camera_.fy * pq[1] * iz + camera_.cy;
    sum_sq += (u - image[i].x) * (u - image[i].x) + (v - image[i].y) * (v - image[i].y);
    const cv::Matx23d dproj(camera_.fx * iz, 0, -camera_.fx * pq[0] * iz * iz, 0, camera_.fy * iz,
                            -camera_.fy * pq[1] * iz * iz);
    const cv::Matx23d dt = dproj;
    const cv::Matx23d dphi = dproj * (-skew(pq));
    for (int c = 0; c < 3; ++c)
    {
      jacobian.at<double>(2 * idx, c) = dt(0, c);
      jacobian.at<double>(2 * idx + 1, c) = dt(1, c);
      jacobian.at<double>(2 * idx, 3 + c) = dphi(0, c);
      jacobian.at<double>(2 * idx + 1, 3 + c) = dphi(1, c);
    }
  }
  result.rms_error_px = std::sqrt(sum_sq / n);
  const double variance = sum_sq / std::max(1, 2 * n - 6);
  const cv::Mat cov = gaussNewtonCovariance(jacobian, variance);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      result.covariance(r, c) = cov.at<double>(r, c);

  result.rotation = r_qm.t();
  result.translation = -(r_qm.t() * t_qm);
  result.status = VerificationStatus::Accepted;
  (void)match;
}

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
  const cv::Mat k = (cv::Mat_<double>(3, 3) << camera_.fx, 0, camera_.cx, 0, camera_.fy, camera_.cy, 0, 0, 1);
  const auto normalised = [this](const cv::Point2f& p)
  { return cv::Vec3d((p.x - camera_.cx) / camera_.fx, (p.y - camera_.cy) / camera_.fy, 1.0); };
  // Parallax of a correspondence under rotation r_qm: the angle between the two rays once the rotation is
  // removed. Zero for every point under a pure rotation, whatever the scene: then the translation of the
  // essential matrix is noise (and cheirality fails at random).
  const auto medianParallax = [&](const cv::Matx33d& r_qm, const cv::Mat& inlier_mask)
  {
    std::vector<double> parallax;
    for (size_t i = 0; i < pm.size(); ++i)
    {
      if (!inlier_mask.at<uchar>(static_cast<int>(i)))
        continue;
      const cv::Vec3d ray_q_in_m = r_qm.t() * cv::normalize(normalised(pq[i]));
      const double c = std::max(-1.0, std::min(1.0, cv::normalize(normalised(pm[i])).dot(ray_q_in_m)));
      parallax.push_back(std::acos(c) * 180.0 / CV_PI);
    }
    return median(parallax);
  };

  cv::Mat mask, e_all, r_mat, t_mat;
  int good = 0;
  try
  {
    e_all = cv::findEssentialMat(pm, pq, k, cv::RANSAC, params_.ransac_confidence, params_.ransac_threshold_px, mask);
    if (e_all.rows < 3 || e_all.cols != 3 || cv::countNonZero(mask) < params_.min_inliers)
    {
      result.inliers = mask.empty() ? 0 : cv::countNonZero(mask);
      result.status = VerificationStatus::TooFewInliers;
      result.reason = describe("essential-matrix RANSAC inliers:", result.inliers, "<", params_.min_inliers);
      return;
    }
    const cv::Mat e = e_all.rowRange(0, 3);
    // Degeneracy before cheirality: E decomposes into two rotations (a twisted pair); under a pure
    // rotation one of them is the true rotation and leaves no parallax.
    cv::Mat r1, r2, t_dir;
    cv::decomposeEssentialMat(e, r1, r2, t_dir);
    result.median_parallax_deg = std::min(medianParallax(cv::Matx33d(r1), mask), medianParallax(cv::Matx33d(r2), mask));
    if (result.median_parallax_deg < params_.min_parallax_deg)
    {
      result.inliers = cv::countNonZero(mask);
      result.status = VerificationStatus::PureRotation;
      result.reason = describe("median parallax (deg):", result.median_parallax_deg, "<", params_.min_parallax_deg) +
                      ": pure rotation or too short a baseline, translation direction undefined";
      return;
    }
    good = cv::recoverPose(e, pm, pq, k, r_mat, t_mat, mask);
  }
  catch (const cv::Exception& e)
  {
    result.status = VerificationStatus::Failed;
    result.reason = std::string("essential matrix RANSAC failed: ") + e.what();
    return;
  }
  result.inliers = good;
  if (good < params_.min_inliers)
  {
    result.status = VerificationStatus::TooFewInliers;
    result.reason = describe("essential-matrix inliers in front of both cameras:", good, "<", params_.min_inliers);
    return;
  }
  // recoverPose: p_query = r_qm * p_match + t_qm, |t_qm| = 1.
  const cv::Matx33d r_qm(r_mat);
  const cv::Vec3d t_qm(t_mat.at<double>(0), t_mat.at<double>(1), t_mat.at<double>(2));
  result.median_parallax_deg = medianParallax(r_qm, mask);
  std::vector<cv::Vec3d> xm, xq;
  for (size_t i = 0; i < pm.size(); ++i)
  {
    if (!mask.at<uchar>(static_cast<int>(i)))
      continue;
    xm.push_back(normalised(pm[i]));
    xq.push_back(normalised(pq[i]));
  }

  // T_match_query and its right perturbation e = (B a, phi), a in the plane perpendicular to the
  // translation direction (its length is not observable). Residual: Sampson error in pixels (normalised
  // error times the mean focal length). Jacobian by central differences: 5 parameters, cheap. The RANSAC
  // model comes from 5 points; Levenberg-Marquardt on all inliers refines it, and the Gauss-Newton
  // Hessian at the optimum gives the covariance.
  cv::Matx33d r_mq = r_qm.t();
  cv::Vec3d t_mq = -(r_qm.t() * t_qm);
  const double focal = 0.5 * (camera_.fx + camera_.fy);
  cv::Vec3d u, b1, b2;
  const auto residuals =
      [&](const cv::Matx33d& r_base, const cv::Vec3d& t_base, const cv::Vec<double, 5>& a, std::vector<double>& out)
  {
    const cv::Vec3d dt = b1 * a[0] + b2 * a[1];
    const cv::Matx33d r = r_base * expSo3(cv::Vec3d(a[2], a[3], a[4]));
    const cv::Vec3d t = t_base + r_base * dt;
    const cv::Matx33d e = skew(-(r.t() * t)) * r.t();  // E of T_query_match = inverse(T_match_query)
    out.resize(xm.size());
    for (size_t i = 0; i < xm.size(); ++i)
      out[i] = focal * sampson(e, xm[i], xq[i]);
  };
  const auto squaredSum = [](const std::vector<double>& r)
  {
    double sum = 0.0;
    for (double v : r)
      sum += v * v;
    return sum;
  };
  const int n = static_cast<int>(xm.size());
  std::vector<double> r0, rp, rn;
  cv::Mat jacobian(n, 5, CV_64F);
  const auto linearise = [&]()
  {
    u = cv::normalize(r_mq.t() * t_mq);  // direction in the query frame (the perturbation's frame)
    tangentBasis(u, b1, b2);
    residuals(r_mq, t_mq, cv::Vec<double, 5>::all(0.0), r0);
    constexpr double kStep = 1e-6;
    for (int c = 0; c < 5; ++c)
    {
      cv::Vec<double, 5> a = cv::Vec<double, 5>::all(0.0);
      a[c] = kStep;
      residuals(r_mq, t_mq, a, rp);
      a[c] = -kStep;
      residuals(r_mq, t_mq, a, rn);
      for (int i = 0; i < n; ++i)
        jacobian.at<double>(i, c) = (rp[i] - rn[i]) / (2.0 * kStep);
    }
  };
  linearise();
  double cost = squaredSum(r0);
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 20; ++iteration)
  {
    const cv::Mat jtj = jacobian.t() * jacobian;
    const cv::Mat jtr = jacobian.t() * cv::Mat(r0);
    cv::Mat damped = jtj.clone();
    for (int d = 0; d < 5; ++d)
      damped.at<double>(d, d) *= 1.0 + lambda;
    cv::Mat step;
    if (!cv::solve(damped, -jtr, step, cv::DECOMP_CHOLESKY))
      break;
    const cv::Vec<double, 5> a(step.ptr<double>());
    const cv::Matx33d r_new = r_mq * expSo3(cv::Vec3d(a[2], a[3], a[4]));
    const cv::Vec3d t_new = cv::normalize(t_mq + r_mq * (b1 * a[0] + b2 * a[1]));
    std::vector<double> trial;
    residuals(r_new, t_new, cv::Vec<double, 5>::all(0.0), trial);
    const double trial_cost = squaredSum(trial);
    if (trial_cost < cost)
    {
      const bool converged = cost - trial_cost < 1e-9 * cost;
      r_mq = r_new;
      t_mq = t_new;
      cost = trial_cost;
      lambda = std::max(1e-7, lambda * 0.1);
      linearise();
      if (converged)
        break;
    }
    else
    {
      lambda *= 10.0;
      if (lambda > 1e6)
        break;
    }
  }
  result.rms_error_px = std::sqrt(cost / n);
  const cv::Mat cov5 = gaussNewtonCovariance(jacobian, cost / std::max(1, n - 5));
  cv::Mat g = cv::Mat::zeros(6, 5, CV_64F);
  for (int r = 0; r < 3; ++r)
  {
    g.at<double>(r, 0) = b1[r];
    g.at<double>(r, 1) = b2[r];
    g.at<double>(3 + r, 2 + r) = 1.0;
  }
  cv::Mat cov6 = g * cov5 * g.t();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      cov6.at<double>(r, c) += Verification::kScaleFreeVariance * u[r] * u[c];
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      result.covariance(r, c) = cov6.at<double>(r, c);

  result.rotation = r_mq;
  result.translation = t_mq;
  result.status = VerificationStatus::Accepted;
}

}  // namespace openable
