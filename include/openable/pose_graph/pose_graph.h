#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

namespace openable
{
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// The loss applied to loop-closure edges (odometry edges are always least squares: they are trusted).
enum class RobustLoss
{
  None,   ///< plain least squares: one wrong loop bends the whole trajectory
  Huber,  ///< quadratic near zero, linear beyond the scale: bounded influence, never zero
  Cauchy  ///< influence falls off as 1/r: a wrong loop far from the rest is effectively ignored
};

struct PoseGraphOptions
{
  RobustLoss loop_loss = RobustLoss::Cauchy;
  /// Scale of the robust loss, in whitened residual units (standard deviations of the loop's own
  /// covariance): residuals well beyond it are treated as outliers.
  double loop_loss_scale = 1.0;
  int max_iterations = 100;
  int threads = 1;
};

struct PoseGraphSummary
{
  bool usable = false;  ///< Ceres returned a solution (converged or hit the iteration limit)
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double seconds = 0.0;
  std::string message;  ///< Ceres' one-line report
};

/// A 3D pose graph (ROS-free; Ceres + Eigen). Nodes are keyframe poses T_world_node; edges are relative
/// poses measured between two nodes, from_T_to = T_world_from^-1 * T_world_to (the pose of `to` in the
/// frame of `from`), with a 6x6 information matrix (inverse covariance) over the right perturbation
/// e = (x y z rx ry rz) in the `to` frame: from_T_to_true = from_T_to * Exp(e).
/// That is exactly LoopClosure.relative_pose (match_T_query) with its covariance.
///
/// Edge residual: r = (t, 2 * vec(q)) of Z^-1 * T_from^-1 * T_to, which is e to first order, whitened by
/// the square root of the information. The first node is held fixed (the gauge). Loop edges get the
/// robust loss of the options, odometry edges plain least squares.
class PoseGraph
{
public:
  explicit PoseGraph(const PoseGraphOptions& options = PoseGraphOptions());

  /// Adds a node with its initial estimate (e.g. the previous optimised node chained with odometry);
  /// returns its index (0, 1, ...). Throws Error on a non-finite pose.
  size_t addNode(const Eigen::Isometry3d& world_T_node);
  /// Throws Error on an unknown node, a self edge, a non-finite measurement or an information matrix that
  /// is not symmetric positive definite.
  void addOdometry(size_t from, size_t to, const Eigen::Isometry3d& from_T_to, const Matrix6d& information);
  void addLoop(size_t match, size_t query, const Eigen::Isometry3d& match_T_query, const Matrix6d& information);

  /// Optimises every node but the first from the current estimates.
  PoseGraphSummary optimize();

  Eigen::Isometry3d pose(size_t node) const;
  /// Overwrites a node's estimate (e.g. to re-initialise). Throws Error on an unknown node.
  void setPose(size_t node, const Eigen::Isometry3d& world_T_node);
  size_t nodeCount() const
  {
    return nodes_.size();
  }
  size_t odometryCount() const;
  size_t loopCount() const;

  /// Per loop edge (in the order added), the robust loss's weight at the current estimate: rho'(s), 1 for
  /// a perfectly consistent loop, near 0 for one the loss treats as an outlier (always 1 without a loss).
  std::vector<double> loopWeights() const;

  const PoseGraphOptions& options() const
  {
    return options_;
  }
  void clear();

  /// Information from a covariance (LoopClosure.relative_pose.covariance): the inverse, after checking
  /// symmetry and positive definiteness; throws Error otherwise.
  static Matrix6d informationFromCovariance(const Matrix6d& covariance);

private:
  struct Node
  {
    Eigen::Vector3d t;
    Eigen::Quaterniond q;
  };
  struct Edge
  {
    size_t from;
    size_t to;
    Eigen::Vector3d t;
    Eigen::Quaterniond q;
    Matrix6d sqrt_information;  // upper-triangular U with U^T U = information
    bool loop;
  };
  void addEdge(size_t from, size_t to, const Eigen::Isometry3d& measurement, const Matrix6d& information, bool loop);

  PoseGraphOptions options_;
  std::vector<Node> nodes_;
  std::vector<Edge> edges_;
};

}  // namespace openable
