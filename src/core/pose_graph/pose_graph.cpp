#include "openable/pose_graph/pose_graph.h"

#include <ceres/ceres.h>

#include <cmath>
#include <memory>

#include "openable/error.h"

namespace openable
{
namespace
{
// Residual of one relative-pose edge (see PoseGraph): the error transform Z^-1 T_from^-1 T_to as
// (translation, 2 * quaternion vector part), whitened. Templated for Ceres' automatic differentiation.
class RelativePoseError
{
public:
  RelativePoseError(const Eigen::Vector3d& t, const Eigen::Quaterniond& q, const Matrix6d& sqrt_information)
    : t_(t), q_inverse_(q.conjugate()), sqrt_information_(sqrt_information)
  {
  }

  template <typename T>
  bool operator()(const T* t_from_ptr, const T* q_from_ptr, const T* t_to_ptr, const T* q_to_ptr, T* residual_ptr) const
  {
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_from(t_from_ptr);
    Eigen::Map<const Eigen::Quaternion<T>> q_from(q_from_ptr);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_to(t_to_ptr);
    Eigen::Map<const Eigen::Quaternion<T>> q_to(q_to_ptr);
    // Estimated from_T_to.
    const Eigen::Quaternion<T> q_from_inverse = q_from.conjugate();
    const Eigen::Quaternion<T> q_estimate = q_from_inverse * q_to;
    const Eigen::Matrix<T, 3, 1> t_estimate = q_from_inverse * (t_to - t_from);
    // Z^-1 * estimate.
    const Eigen::Quaternion<T> q_error = q_inverse_.template cast<T>() * q_estimate;
    const Eigen::Matrix<T, 3, 1> t_error = q_inverse_.template cast<T>() * (t_estimate - t_.template cast<T>());
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual.template head<3>() = t_error;
    // 2 * vec(q) is the rotation vector to first order; the sign keeps the short way round (q and -q are
    // the same rotation).
    const T sign = q_error.w() < T(0) ? T(-1) : T(1);
    residual.template tail<3>() = T(2) * sign * q_error.vec();
    residual.applyOnTheLeft(sqrt_information_.template cast<T>());
    return true;
  }

  static ceres::CostFunction* create(const Eigen::Vector3d& t, const Eigen::Quaterniond& q,
                                     const Matrix6d& sqrt_information)
  {
    return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 3, 4, 3, 4>(
        new RelativePoseError(t, q, sqrt_information));
  }

  EIGEN_MAKE_ALIGNED_OPERATOR_NEW

private:
  Eigen::Vector3d t_;
  Eigen::Quaterniond q_inverse_;
  Matrix6d sqrt_information_;
};

bool finite(const Eigen::Isometry3d& pose)
{
  return pose.matrix().allFinite();
}

// Weight the robust loss gives a squared whitened residual s: rho'(s).
double lossWeight(RobustLoss loss, double scale, double s)
{
  const double a2 = scale * scale;
  switch (loss)
  {
    case RobustLoss::None:
      return 1.0;
    case RobustLoss::Huber:
      return s <= a2 ? 1.0 : std::sqrt(a2 / s);
    case RobustLoss::Cauchy:
      return 1.0 / (1.0 + s / a2);
  }
  return 1.0;
}
}  // namespace

PoseGraph::PoseGraph(const PoseGraphOptions& options) : options_(options)
{
  if (!(options_.loop_loss_scale > 0.0))
    throw Error("PoseGraph: loop_loss_scale " + std::to_string(options_.loop_loss_scale) + ", expected > 0");
  if (options_.max_iterations < 1 || options_.threads < 1)
    throw Error("PoseGraph: max_iterations and threads must be >= 1");
}

size_t PoseGraph::addNode(const Eigen::Isometry3d& world_T_node)
{
  if (!finite(world_T_node))
    throw Error("PoseGraph::addNode: non-finite pose");
  nodes_.push_back(Node{world_T_node.translation(), Eigen::Quaterniond(world_T_node.rotation()).normalized()});
  return nodes_.size() - 1;
}

void PoseGraph::addOdometry(size_t from, size_t to, const Eigen::Isometry3d& from_T_to, const Matrix6d& information)
{
  addEdge(from, to, from_T_to, information, false);
}

void PoseGraph::addLoop(size_t match, size_t query, const Eigen::Isometry3d& match_T_query, const Matrix6d& information)
{
  addEdge(match, query, match_T_query, information, true);
}

void PoseGraph::addEdge(size_t from, size_t to, const Eigen::Isometry3d& measurement, const Matrix6d& information,
                        bool loop)
{
  const char* kind = loop ? "PoseGraph::addLoop" : "PoseGraph::addOdometry";
  if (from >= nodes_.size() || to >= nodes_.size())
    throw Error(std::string(kind) + ": node " + std::to_string(std::max(from, to)) + " does not exist (" +
                std::to_string(nodes_.size()) + " nodes)");
  if (from == to)
    throw Error(std::string(kind) + ": edge from node " + std::to_string(from) + " to itself");
  if (!finite(measurement) || !information.allFinite())
    throw Error(std::string(kind) + ": non-finite measurement or information");
  if (!information.isApprox(information.transpose(), 1e-9))
    throw Error(std::string(kind) + ": information matrix is not symmetric");
  const Eigen::LLT<Matrix6d> llt(information);
  if (llt.info() != Eigen::Success)
    throw Error(std::string(kind) + ": information matrix is not positive definite");
  Edge edge;
  edge.from = from;
  edge.to = to;
  edge.t = measurement.translation();
  edge.q = Eigen::Quaterniond(measurement.rotation()).normalized();
  edge.sqrt_information = llt.matrixU();
  edge.loop = loop;
  edges_.push_back(edge);
}

PoseGraphSummary PoseGraph::optimize()
{
  PoseGraphSummary summary;
  if (nodes_.size() < 2 || edges_.empty())
  {
    summary.usable = true;
    summary.message = "nothing to optimise";
    return summary;
  }
  ceres::Problem problem;
  ceres::Manifold* quaternion_manifold = new ceres::EigenQuaternionManifold;  // owned by the problem
  for (const Edge& edge : edges_)
  {
    ceres::LossFunction* loss = nullptr;
    if (edge.loop && options_.loop_loss == RobustLoss::Huber)
      loss = new ceres::HuberLoss(options_.loop_loss_scale);
    else if (edge.loop && options_.loop_loss == RobustLoss::Cauchy)
      loss = new ceres::CauchyLoss(options_.loop_loss_scale);
    Node& a = nodes_[edge.from];
    Node& b = nodes_[edge.to];
    problem.AddResidualBlock(RelativePoseError::create(edge.t, edge.q, edge.sqrt_information), loss, a.t.data(),
                             a.q.coeffs().data(), b.t.data(), b.q.coeffs().data());
  }
  bool manifold_used = false;
  for (Node& node : nodes_)
    if (problem.HasParameterBlock(node.q.coeffs().data()))
    {
      problem.SetManifold(node.q.coeffs().data(), quaternion_manifold);
      manifold_used = true;
    }
  // Gauge: the first node anchors the graph (the map frame coincides with it).
  if (problem.HasParameterBlock(nodes_[0].t.data()))
  {
    problem.SetParameterBlockConstant(nodes_[0].t.data());
    problem.SetParameterBlockConstant(nodes_[0].q.coeffs().data());
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options_.max_iterations;
  solver_options.num_threads = options_.threads;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem, &ceres_summary);
  summary.usable = ceres_summary.IsSolutionUsable();
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.seconds = ceres_summary.total_time_in_seconds;
  summary.message = ceres_summary.BriefReport();
  for (Node& node : nodes_)
    node.q.normalize();
  // The problem owns the manifold only if some block uses it.
  if (!manifold_used)
    delete quaternion_manifold;
  return summary;
}

Eigen::Isometry3d PoseGraph::pose(size_t node) const
{
  if (node >= nodes_.size())
    throw Error("PoseGraph::pose: node " + std::to_string(node) + " does not exist (" + std::to_string(nodes_.size()) +
                " nodes)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = nodes_[node].q.toRotationMatrix();
  pose.translation() = nodes_[node].t;
  return pose;
}

void PoseGraph::setPose(size_t node, const Eigen::Isometry3d& world_T_node)
{
  if (node >= nodes_.size())
    throw Error("PoseGraph::setPose: node " + std::to_string(node) + " does not exist");
  if (!finite(world_T_node))
    throw Error("PoseGraph::setPose: non-finite pose");
  nodes_[node].t = world_T_node.translation();
  nodes_[node].q = Eigen::Quaterniond(world_T_node.rotation()).normalized();
}

size_t PoseGraph::odometryCount() const
{
  size_t count = 0;
  for (const Edge& e : edges_)
    count += e.loop ? 0 : 1;
  return count;
}

size_t PoseGraph::loopCount() const
{
  return edges_.size() - odometryCount();
}

std::vector<double> PoseGraph::loopWeights() const
{
  std::vector<double> weights;
  for (const Edge& edge : edges_)
  {
    if (!edge.loop)
      continue;
    const Node& a = nodes_[edge.from];
    const Node& b = nodes_[edge.to];
    RelativePoseError error(edge.t, edge.q, edge.sqrt_information);
    Eigen::Matrix<double, 6, 1> r;
    error(a.t.data(), a.q.coeffs().data(), b.t.data(), b.q.coeffs().data(), r.data());
    weights.push_back(lossWeight(options_.loop_loss, options_.loop_loss_scale, r.squaredNorm()));
  }
  return weights;
}

void PoseGraph::clear()
{
  nodes_.clear();
  edges_.clear();
}

Matrix6d PoseGraph::informationFromCovariance(const Matrix6d& covariance)
{
  if (!covariance.allFinite())
    throw Error("PoseGraph::informationFromCovariance: non-finite covariance");
  if (!covariance.isApprox(covariance.transpose(), 1e-6))
    throw Error("PoseGraph::informationFromCovariance: covariance is not symmetric");
  const Matrix6d symmetric = 0.5 * (covariance + covariance.transpose());
  const Eigen::LLT<Matrix6d> llt(symmetric);
  if (llt.info() != Eigen::Success)
    throw Error("PoseGraph::informationFromCovariance: covariance is not positive definite (all-zero?)");
  Matrix6d information = llt.solve(Matrix6d::Identity());
  return 0.5 * (information + information.transpose());
}

}  // namespace openable
