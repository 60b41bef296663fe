#include "verification/pose_covariance.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

namespace openable
{
namespace verification
{
namespace
{
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

double squaredSum(const std::vector<double>& values)
{
  double sum = 0.0;
  for (double v : values)
    sum += v * v;
  return sum;
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

// Least squares over the Sampson errors of T_match_query, parametrised around the current estimate by a
// right perturbation e = (B a, phi): a in the plane perpendicular to the translation direction (its length
// is not observable), phi a rotation. Five parameters: the Jacobian by central differences is cheap.
class SampsonProblem
{
public:
  using Step = cv::Vec<double, 5>;

  SampsonProblem(const std::vector<cv::Vec3d>& xm, const std::vector<cv::Vec3d>& xq, const cv::Matx33d& r_mq,
                 const cv::Vec3d& t_mq, double focal)
    : xm_(xm), xq_(xq), focal_(focal), r_mq_(r_mq), t_mq_(t_mq), jacobian_(static_cast<int>(xm.size()), 5, CV_64F)
  {
    linearise();
  }

  /// Levenberg-Marquardt from the RANSAC model (5 points only) on all inliers.
  void refine()
  {
    double lambda = 1e-3;
    for (int iteration = 0; iteration < 20; ++iteration)
    {
      const int outcome = tryStep(lambda);
      if (outcome < 0)
        break;  // no step could be taken
      if (outcome == 0)
      {
        lambda *= 10.0;
        if (lambda > 1e6)
          break;
        continue;
      }
      lambda = std::max(1e-7, lambda * 0.1);
      if (outcome == 2)
        break;  // converged
    }
  }

  EssentialRefinement result() const
  {
    const int n = static_cast<int>(xm_.size());
    EssentialRefinement out;
    out.rotation = r_mq_;
    out.translation = t_mq_;
    out.rms_error_px = std::sqrt(cost_ / n);
    // Back to the 6-dof perturbation; along the direction the scale is unknown (kScaleFreeVariance).
    const cv::Mat cov5 = gaussNewtonCovariance(jacobian_, cost_ / std::max(1, n - 5));
    cv::Mat g = cv::Mat::zeros(6, 5, CV_64F);
    for (int r = 0; r < 3; ++r)
    {
      g.at<double>(r, 0) = b1_[r];
      g.at<double>(r, 1) = b2_[r];
      g.at<double>(3 + r, 2 + r) = 1.0;
    }
    cv::Mat cov6 = g * cov5 * g.t();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        cov6.at<double>(r, c) += Verification::kScaleFreeVariance * u_[r] * u_[c];
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c)
        out.covariance(r, c) = cov6.at<double>(r, c);
    return out;
  }

private:
  // Sampson errors in pixels (normalised error times the mean focal length) at (r_base, t_base) moved by a.
  void residuals(const cv::Matx33d& r_base, const cv::Vec3d& t_base, const Step& a, std::vector<double>& out) const
  {
    const cv::Vec3d dt = b1_ * a[0] + b2_ * a[1];
    const cv::Matx33d r = r_base * expSo3(cv::Vec3d(a[2], a[3], a[4]));
    const cv::Vec3d t = t_base + r_base * dt;
    const cv::Matx33d e = skew(-(r.t() * t)) * r.t();  // E of T_query_match = inverse(T_match_query)
    out.resize(xm_.size());
    for (size_t i = 0; i < xm_.size(); ++i)
      out[i] = focal_ * sampson(e, xm_[i], xq_[i]);
  }

  // Residuals and Jacobian at the current estimate, in the tangent basis of its translation direction.
  void linearise()
  {
    u_ = cv::normalize(r_mq_.t() * t_mq_);  // direction in the query frame (the perturbation's frame)
    tangentBasis(u_, b1_, b2_);
    residuals(r_mq_, t_mq_, Step::all(0.0), r0_);
    cost_ = squaredSum(r0_);
    constexpr double kStep = 1e-6;
    std::vector<double> rp, rn;
    for (int c = 0; c < 5; ++c)
    {
      Step a = Step::all(0.0);
      a[c] = kStep;
      residuals(r_mq_, t_mq_, a, rp);
      a[c] = -kStep;
      residuals(r_mq_, t_mq_, a, rn);
      for (int i = 0; i < jacobian_.rows; ++i)
        jacobian_.at<double>(i, c) = (rp[i] - rn[i]) / (2.0 * kStep);
    }
  }

  // One damped Gauss-Newton step: -1 when the system cannot be solved, 0 when it did not lower the cost,
  // 1 when it was taken, 2 when it was taken and the cost barely moved (converged).
  int tryStep(double lambda)
  {
    const cv::Mat jtj = jacobian_.t() * jacobian_;
    const cv::Mat jtr = jacobian_.t() * cv::Mat(r0_);
    cv::Mat damped = jtj.clone();
    for (int d = 0; d < 5; ++d)
      damped.at<double>(d, d) *= 1.0 + lambda;
    cv::Mat step;
    if (!cv::solve(damped, -jtr, step, cv::DECOMP_CHOLESKY))
      return -1;
    const Step a(step.ptr<double>());
    const cv::Matx33d r_new = r_mq_ * expSo3(cv::Vec3d(a[2], a[3], a[4]));
    const cv::Vec3d t_new = cv::normalize(t_mq_ + r_mq_ * (b1_ * a[0] + b2_ * a[1]));
    std::vector<double> trial;
    residuals(r_new, t_new, Step::all(0.0), trial);
    const double trial_cost = squaredSum(trial);
    if (trial_cost >= cost_)
      return 0;
    const bool converged = cost_ - trial_cost < 1e-9 * cost_;
    r_mq_ = r_new;
    t_mq_ = t_new;
    linearise();
    return converged ? 2 : 1;
  }

  const std::vector<cv::Vec3d>& xm_;
  const std::vector<cv::Vec3d>& xq_;
  const double focal_;
  cv::Matx33d r_mq_;
  cv::Vec3d t_mq_;
  cv::Vec3d u_, b1_, b2_;
  std::vector<double> r0_;
  double cost_ = 0.0;
  cv::Mat jacobian_;
};
}  // namespace

cv::Matx66d pnpCovariance(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                          const std::vector<int>& inliers, const cv::Matx33d& r_qm, const cv::Vec3d& t_qm,
                          const PinholeCamera& camera, double& rms_error_px)
{
  // Left perturbation of T_query_match, T' = Exp(d) T: p_q' = p_q + d_t + d_phi x p_q, so
  // d p_q / d(d_t, d_phi) = [I, -[p_q]x], chained with the projection's Jacobian. Inverting,
  // T_match_query' = T_match_query Exp(-d): the same covariance holds for the right perturbation of
  // T_match_query that Verification documents.
  const int n = static_cast<int>(inliers.size());
  cv::Mat jacobian(2 * n, 6, CV_64F);
  double sum_sq = 0.0;
  for (int idx = 0; idx < n; ++idx)
  {
    const int i = inliers[idx];
    const cv::Vec3d pm(object[i].x, object[i].y, object[i].z);
    const cv::Vec3d pq = r_qm * pm + t_qm;
    const double iz = 1.0 / pq[2];
    const double u = camera.fx * pq[0] * iz + camera.cx;
    const double v = camera.fy * pq[1] * iz + camera.cy;
    sum_sq += (u - image[i].x) * (u - image[i].x) + (v - image[i].y) * (v - image[i].y);
    const cv::Matx23d dproj(camera.fx * iz, 0, -camera.fx * pq[0] * iz * iz, 0, camera.fy * iz,
                            -camera.fy * pq[1] * iz * iz);
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
  rms_error_px = std::sqrt(sum_sq / n);
  const double variance = sum_sq / std::max(1, 2 * n - 6);
  const cv::Mat cov = gaussNewtonCovariance(jacobian, variance);
  cv::Matx66d out;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      out(r, c) = cov.at<double>(r, c);
  return out;
}

EssentialRefinement refineEssential(const std::vector<cv::Vec3d>& xm, const std::vector<cv::Vec3d>& xq,
                                    const cv::Matx33d& r_mq, const cv::Vec3d& t_mq, double focal)
{
  SampsonProblem problem(xm, xq, r_mq, t_mq, focal);
  problem.refine();
  return problem.result();
}

}  // namespace verification
}  // namespace openable
