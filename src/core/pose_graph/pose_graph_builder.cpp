#include "openable/pose_graph/pose_graph_builder.h"

#include <algorithm>

#include "openable/error.h"

namespace openable
{
PoseGraphBuilder::PoseGraphBuilder(const PoseGraphBuilderOptions& options) : options_(options), graph_(options.graph) {}

Matrix6d PoseGraphBuilder::adjoint(const Eigen::Isometry3d& t)
{
  Matrix6d ad = Matrix6d::Zero();
  const Eigen::Matrix3d r = t.rotation();
  const Eigen::Vector3d p = t.translation();
  Eigen::Matrix3d p_hat;
  p_hat << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  ad.block<3, 3>(0, 0) = r;
  ad.block<3, 3>(0, 3) = p_hat * r;
  ad.block<3, 3>(3, 3) = r;
  return ad;
}

Eigen::Isometry3d PoseGraphBuilder::interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = (1.0 - s) * a.translation() + s * b.translation();
  t.linear() = Eigen::Quaterniond(a.rotation()).slerp(s, Eigen::Quaterniond(b.rotation())).toRotationMatrix();
  return t;
}

Matrix6d PoseGraphBuilder::diagonal(double sigma_t, double sigma_r)
{
  Matrix6d information = Matrix6d::Zero();
  information.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)),
      Eigen::Vector3d::Constant(1.0 / (sigma_r * sigma_r));
  return information;
}

PoseGraphBuilder::Odometry PoseGraphBuilder::addOdometry(double stamp, const Eigen::Isometry3d& pose)
{
  Odometry result = Odometry::Stored;
  if (!history_.empty())
  {
    if (stamp <= keyframes_.front().stamp)
    {
      // Before the very first keyframe: time jumped back (a bag restarted), the graph belongs to another run.
      clear();
      result = Odometry::Restarted;
    }
    else if (stamp <= history_.back().stamp)
    {
      // Late: keep it for placing image stamps, but keyframes only follow the newest sample.
      auto it = std::upper_bound(history_.begin(), history_.end(), stamp,
                                 [](double t, const Sample& s) { return t < s.stamp; });
      if (it == history_.begin() || std::prev(it)->stamp != stamp)
        history_.insert(it, Sample{stamp, pose});
      return Odometry::Late;
    }
  }
  history_.push_back(Sample{stamp, pose});
  while (history_.size() > options_.odometry_history)
    history_.pop_front();
  if (keyframes_.empty() || movedEnough(keyframes_.back().odom_pose, pose))
  {
    addKeyframe(stamp, pose);
    return result == Odometry::Restarted ? result : Odometry::Keyframe;
  }
  return result;
}

bool PoseGraphBuilder::movedEnough(const Eigen::Isometry3d& last, const Eigen::Isometry3d& now) const
{
  const Eigen::Isometry3d delta = last.inverse() * now;
  return delta.translation().norm() >= options_.keyframe_distance ||
         Eigen::AngleAxisd(delta.rotation()).angle() >= options_.keyframe_angle;
}

void PoseGraphBuilder::addKeyframe(double stamp, const Eigen::Isometry3d& odom_pose)
{
  if (keyframes_.empty())
    graph_.addNode(odom_pose);  // map and odom coincide at the first keyframe
  else
  {
    // Initial estimate: the previous keyframe's corrected pose chained with the odometry since.
    const Eigen::Isometry3d delta = keyframes_.back().odom_pose.inverse() * odom_pose;
    const size_t node = graph_.addNode(graph_.pose(keyframes_.size() - 1) * delta);
    const double d = delta.translation().norm();
    graph_.addOdometry(
        node - 1, node, delta,
        diagonal(options_.odometry_sigma_translation * d + 0.01, options_.odometry_sigma_rotation * d + 0.002));
  }
  keyframes_.push_back(Keyframe{stamp, odom_pose});
}

PoseGraphBuilder::Place PoseGraphBuilder::place(double stamp, Anchor& anchor) const
{
  if (history_.empty() || keyframes_.empty() || stamp > history_.back().stamp)
    return Place::NotYet;
  Eigen::Isometry3d odom_at_stamp;
  if (!odometryAt(stamp, odom_at_stamp))
    return Place::Never;
  auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), stamp,
                             [](const Keyframe& k, double t) { return k.stamp < t; });
  if (it == keyframes_.end())
    --it;
  else if (it != keyframes_.begin() && (stamp - std::prev(it)->stamp) < (it->stamp - stamp))
    --it;
  anchor.node = static_cast<size_t>(it - keyframes_.begin());
  anchor.node_T_frame = it->odom_pose.inverse() * odom_at_stamp;
  return Place::Ok;
}

bool PoseGraphBuilder::odometryAt(double stamp, Eigen::Isometry3d& pose) const
{
  auto it =
      std::lower_bound(history_.begin(), history_.end(), stamp, [](const Sample& s, double t) { return s.stamp < t; });
  if (it == history_.end())
    return false;
  if (it->stamp == stamp)
  {
    pose = it->pose;
    return true;
  }
  if (it == history_.begin())
    return false;  // older than the history
  const Sample& before = *std::prev(it);
  const double gap = it->stamp - before.stamp;
  if (gap > options_.max_interpolation_gap)
    return false;
  pose = interpolate(before.pose, it->pose, (stamp - before.stamp) / gap);
  return true;
}

PoseGraphBuilder::Loop PoseGraphBuilder::addLoop(const LoopMeasurement& loop)
{
  Anchor query, match;
  const Place pq = place(loop.query_stamp, query);
  const Place pm = place(loop.match_stamp, match);
  if (pq == Place::NotYet || pm == Place::NotYet)
  {
    // Dropped when odometry has moved well past the stamp without covering it.
    const bool passed =
        !history_.empty() && history_.back().stamp > loop.query_stamp + 5.0 * options_.max_interpolation_gap;
    return passed ? Loop::Unplaced : Loop::Wait;
  }
  if (pq == Place::Never || pm == Place::Never)
    return Loop::Unplaced;
  if (query.node == match.node)
    return Loop::SameKeyframe;

  // match_T_query between cameras -> between the odometry child frames -> between the keyframes.
  const Eigen::Isometry3d a = match.node_T_frame * loop.child_T_camera;
  const Eigen::Isometry3d b = query.node_T_frame * loop.child_T_camera;
  const Eigen::Isometry3d measurement =
      a * (loop.has_relative_pose ? loop.match_T_query : Eigen::Isometry3d::Identity()) * b.inverse();
  Loop result = Loop::Added;
  Matrix6d information;
  if (loop.has_relative_pose)
  {
    try
    {
      // The covariance is over a right perturbation in the query camera; move it to the query keyframe.
      const Matrix6d ad = adjoint(b);
      information = PoseGraph::informationFromCovariance(ad * loop.covariance * ad.transpose());
    }
    catch (const Error&)
    {
      information = diagonal(options_.default_loop_sigma_translation, options_.default_loop_sigma_rotation);
      result = Loop::AddedWithDefaultCovariance;
    }
  }
  else
  {
    // "Same place" without geometry: the positions agree within a few metres; rotation free (a tiny
    // weight keeps the information positive definite).
    information = diagonal(options_.unverified_sigma_translation, 1e3);
  }
  graph_.addLoop(match.node, query.node, measurement, information);
  loops_.emplace_back(match.node, query.node);
  dirty_ = true;
  return result;
}

PoseGraphSummary PoseGraphBuilder::optimize()
{
  dirty_ = false;
  return graph_.optimize();
}

void PoseGraphBuilder::clear()
{
  graph_.clear();
  keyframes_.clear();
  history_.clear();
  loops_.clear();
  dirty_ = false;
}

std::pair<double, double> PoseGraphBuilder::odometrySpan() const
{
  if (history_.empty())
    return {0.0, 0.0};
  return {history_.front().stamp, history_.back().stamp};
}

Eigen::Isometry3d PoseGraphBuilder::mapFromOdometry() const
{
  if (keyframes_.empty())
    return Eigen::Isometry3d::Identity();
  return graph_.pose(keyframes_.size() - 1) * keyframes_.back().odom_pose.inverse();
}

}  // namespace openable
