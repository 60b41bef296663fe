#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

#include "openable/pose_graph/pose_graph.h"

namespace openable
{
/// How odometry and loop closures become a pose graph (everything a backend does besides messages).
struct PoseGraphBuilderOptions
{
  double keyframe_distance = 1.0;               ///< m travelled before a new keyframe
  double keyframe_angle = 0.2;                  ///< rad turned before a new keyframe
  double odometry_sigma_translation = 0.02;     ///< fraction of the distance between keyframes (+ 1 cm)
  double odometry_sigma_rotation = 0.002;       ///< rad per metre between keyframes (+ 0.002 rad)
  double default_loop_sigma_translation = 0.2;  ///< m, for a verified loop without usable covariance
  double default_loop_sigma_rotation = 0.05;    ///< rad, same
  double unverified_sigma_translation = 3.0;    ///< m, "same place" constraint of an unverified loop
  double max_interpolation_gap = 0.5;           ///< s; larger odometry gaps are not interpolated
  size_t odometry_history = 100000;             ///< odometry samples kept to place image stamps
  PoseGraphOptions graph;
};

/// One loop closure as the detector publishes it: two image stamps, and (when verified) the relative pose
/// between the cameras, match_T_query, with its covariance over a right perturbation in the query camera.
struct LoopMeasurement
{
  double query_stamp = 0.0;
  double match_stamp = 0.0;
  bool has_relative_pose = false;
  Eigen::Isometry3d match_T_query = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();
  /// The camera in the odometry's child frame (usually static; identity when they are the same frame).
  Eigen::Isometry3d child_T_camera = Eigen::Isometry3d::Identity();
};

/// Keyframes from odometry (a node every keyframe_distance / keyframe_angle, an odometry edge between
/// consecutive ones), loop closures anchored by stamp: each image stamp goes to the keyframe nearest in
/// time, plus the odometry motion from it to the stamp (interpolated); a verified loop's covariance is moved
/// from the query camera to the query keyframe through the SE(3) adjoint. ROS-free: the node only converts.
class PoseGraphBuilder
{
public:
  enum class Odometry
  {
    Keyframe,  ///< stored and made a new keyframe
    Stored,    ///< stored (between keyframes)
    Late,      ///< out of order: kept for placing stamps, not for keyframes
    Restarted  ///< before the first keyframe (a bag restarted): the graph was cleared and starts again
  };
  enum class Loop
  {
    Added,
    AddedWithDefaultCovariance,  ///< its covariance was unusable: default sigmas
    Wait,                        ///< a stamp is newer than the odometry: try again later
    Unplaced,                    ///< a stamp falls outside the odometry (or in a gap): never
    SameKeyframe                 ///< both stamps belong to one keyframe: ignored
  };

  explicit PoseGraphBuilder(const PoseGraphBuilderOptions& options = PoseGraphBuilderOptions());

  Odometry addOdometry(double stamp, const Eigen::Isometry3d& odom_T_child);
  Loop addLoop(const LoopMeasurement& loop);
  /// Optimises when loops were added since the last time (`dirty`); the summary says whether it worked.
  PoseGraphSummary optimize();
  bool dirty() const
  {
    return dirty_;
  }
  void clear();

  const PoseGraph& graph() const
  {
    return graph_;
  }
  size_t keyframes() const
  {
    return keyframes_.size();
  }
  double keyframeStamp(size_t i) const
  {
    return keyframes_[i].stamp;
  }
  /// The keyframe's pose as odometry measured it (before correction).
  const Eigen::Isometry3d& keyframeOdometry(size_t i) const
  {
    return keyframes_[i].odom_pose;
  }
  /// (match keyframe, query keyframe) of every loop, in the graph's loop order.
  const std::vector<std::pair<size_t, size_t>>& loops() const
  {
    return loops_;
  }
  /// The odometry's time span (0, 0 when empty).
  std::pair<double, double> odometrySpan() const;
  /// map_T_odom: the correction that makes the newest keyframe's odometry pose its optimised one.
  Eigen::Isometry3d mapFromOdometry() const;

  /// SE(3) adjoint for perturbations ordered (translation, rotation): Exp(Ad_T e) = T Exp(e) T^-1.
  static Matrix6d adjoint(const Eigen::Isometry3d& t);
  static Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s);

private:
  struct Keyframe
  {
    double stamp;
    Eigen::Isometry3d odom_pose;
  };
  struct Sample
  {
    double stamp;
    Eigen::Isometry3d pose;
  };
  struct Anchor
  {
    size_t node = 0;
    Eigen::Isometry3d node_T_frame = Eigen::Isometry3d::Identity();
  };
  enum class Place
  {
    Ok,
    NotYet,
    Never
  };

  bool movedEnough(const Eigen::Isometry3d& last, const Eigen::Isometry3d& now) const;
  void addKeyframe(double stamp, const Eigen::Isometry3d& odom_pose);
  Place place(double stamp, Anchor& anchor) const;
  bool odometryAt(double stamp, Eigen::Isometry3d& pose) const;
  static Matrix6d diagonal(double sigma_t, double sigma_r);

  PoseGraphBuilderOptions options_;
  PoseGraph graph_;
  std::vector<Keyframe> keyframes_;  ///< node i of graph_ is keyframes_[i]
  std::deque<Sample> history_;
  std::vector<std::pair<size_t, size_t>> loops_;
  bool dirty_ = false;
};

}  // namespace openable
