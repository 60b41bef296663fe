// pose_graph_node: the reference backend for openable_ros loop closures.
//
// It shows how to wire the detector into any pose-graph backend:
//   1. keyframes come from odometry (nav_msgs/Odometry on `odom`): a node every ~keyframe_distance metres
//      or ~keyframe_angle radians, an odometry edge between consecutive keyframes;
//   2. a LoopClosure (on `loop_closures`) names two *image stamps*: header.stamp (query) and match_stamp.
//      Each stamp is matched to the keyframe nearest in time, and the small motion between that keyframe
//      and the image is taken from the odometry history (interpolated at the stamp);
//   3. trust relative_pose (and its covariance) only when has_relative_pose is true (geometric
//      verification passed). It is match_T_query between the *camera* frames (LoopClosure.header.frame_id);
//      it is moved to the odometry child frame through tf (camera -> base, usually static);
//   4. loop edges get a robust loss (Cauchy by default): a wrong loop that slipped through is down-weighted
//      instead of bending the map;
//   5. new loops are optimised in batches (a wall-clock timer, ~optimise_period) so that a slow optimisation
//      never makes the odometry queue overflow; the corrected keyframe path is published (`path`, in
//      ~map_frame), the uncorrected one (`odom_path`, in the odometry frame) for comparison, loop edges as
//      markers (`loop_edges`), and the map -> odom tf that makes map -> base equal to the corrected pose.
//
// Subscribed: odom (nav_msgs/Odometry), loop_closures (openable_ros/LoopClosure)
// Published:  path (nav_msgs/Path, latched), odom_path (nav_msgs/Path, latched),
//             loop_edges (visualization_msgs/MarkerArray, latched; green trusted, red down-weighted),
//             tf map -> odom
// Parameters (all private):
//   ~map_frame (string, "map")
//   ~keyframe_distance (double, 1.0 m), ~keyframe_angle (double, 0.2 rad)
//   ~odometry_sigma_translation (double, 0.02: fraction of the distance travelled between keyframes, plus 1 cm)
//   ~odometry_sigma_rotation (double, 0.002 rad per metre travelled, plus 0.002 rad)
//   ~loss (string, "cauchy": cauchy | huber | none), ~loss_scale (double, 1.0, standard deviations)
//   ~default_loop_sigma_translation (double, 0.2 m), ~default_loop_sigma_rotation (double, 0.05 rad):
//       used when a verified loop carries no usable covariance
//   ~use_unverified (bool, false): also add loops without relative_pose, as "same position" constraints
//       with ~unverified_sigma_translation (double, 3.0 m) and free rotation
//   ~odometry_history (int, 100000): odometry samples kept to place image stamps between keyframes
//   ~max_interpolation_gap (double, 0.5 s): larger gaps between odometry samples are not interpolated
//   ~optimise_period (double, 0.5 s): how often new loops are optimised (wall clock, works with a paused bag)
//   ~publish_tf (bool, true)
//   ~marker_width (double, 0.3 m): line width of loop_edges

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <deque>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/pose_graph.h"
#include "openable_ros/LoopClosure.h"

namespace openable_ros
{
using openable::Matrix6d;

namespace
{
Eigen::Isometry3d toEigen(const geometry_msgs::Pose& p)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

Eigen::Isometry3d toEigen(const geometry_msgs::Transform& p)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.translation.x, p.translation.y, p.translation.z);
  t.linear() =
      Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return t;
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& t)
{
  geometry_msgs::Pose p;
  p.position.x = t.translation().x();
  p.position.y = t.translation().y();
  p.position.z = t.translation().z();
  const Eigen::Quaterniond q(t.rotation());
  p.orientation.w = q.w();
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  return p;
}

bool finitePose(const geometry_msgs::Pose& p)
{
  const double q = p.orientation.w * p.orientation.w + p.orientation.x * p.orientation.x +
                   p.orientation.y * p.orientation.y + p.orientation.z * p.orientation.z;
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
         std::isfinite(q) && q > 1e-6;
}

// SE3 adjoint for perturbations ordered (translation, rotation): Exp(Ad_T e) = T Exp(e) T^-1.
Matrix6d adjoint(const Eigen::Isometry3d& t)
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

Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = (1.0 - s) * a.translation() + s * b.translation();
  t.linear() = Eigen::Quaterniond(a.rotation()).slerp(s, Eigen::Quaterniond(b.rotation())).toRotationMatrix();
  return t;
}
}  // namespace

class PoseGraphNode
{
public:
  PoseGraphNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : tf_listener_(tf_buffer_)
  {
    readParameters(pnh);
    path_pub_ = nh.advertise<nav_msgs::Path>("path", 1, true);
    odom_path_pub_ = nh.advertise<nav_msgs::Path>("odom_path", 1, true);
    // Not "loop_markers": that is the detector's topic, and both usually share a namespace.
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("loop_edges", 1, true);
    // Deep odometry queue: an optimisation may hold the (single) callback thread for a fraction of a second.
    odom_sub_ = nh.subscribe("odom", 1000, &PoseGraphNode::odometryCallback, this);
    loop_sub_ = nh.subscribe("loop_closures", 100, &PoseGraphNode::loopCallback, this);
    optimise_timer_ = nh.createWallTimer(ros::WallDuration(optimise_period_),
                                         [this](const ros::WallTimerEvent&)
                                         {
                                           if (dirty_)
                                             optimise();
                                         });
    ROS_INFO("pose_graph_node: keyframes every %.2f m / %.2f rad of %s, loops from %s, %s loss, map frame '%s'",
             keyframe_distance_, keyframe_angle_, odom_sub_.getTopic().c_str(), loop_sub_.getTopic().c_str(),
             loss_name_.c_str(), map_frame_.c_str());
  }

private:
  struct Keyframe
  {
    ros::Time stamp;
    Eigen::Isometry3d odom_pose;  // odom_T_child at the keyframe, as odometry measured it
  };
  struct OdometrySample
  {
    ros::Time stamp;
    Eigen::Isometry3d pose;
  };
  // Where an image stamp sits in the graph: a keyframe and the odometry motion from it to the image.
  struct Anchor
  {
    size_t node = 0;
    Eigen::Isometry3d node_T_frame = Eigen::Isometry3d::Identity();
  };
  enum class Resolve
  {
    Ok,
    NotYet,  // newer than the latest odometry: retry when odometry catches up
    Never
  };

  // Reads and checks every parameter; a bad value is logged with the rule and replaced by the default
  // (never throws, the node keeps running).
  void readParameters(ros::NodeHandle& pnh)
  {
    pnh.param<std::string>("map_frame", map_frame_, "map");
    positive(pnh, "keyframe_distance", keyframe_distance_, 1.0);
    positive(pnh, "keyframe_angle", keyframe_angle_, 0.2);
    positive(pnh, "odometry_sigma_translation", odometry_sigma_translation_, 0.02);
    positive(pnh, "odometry_sigma_rotation", odometry_sigma_rotation_, 0.002);
    positive(pnh, "default_loop_sigma_translation", default_loop_sigma_translation_, 0.2);
    positive(pnh, "default_loop_sigma_rotation", default_loop_sigma_rotation_, 0.05);
    positive(pnh, "unverified_sigma_translation", unverified_sigma_translation_, 3.0);
    positive(pnh, "max_interpolation_gap", max_interpolation_gap_, 0.5);
    positive(pnh, "optimise_period", optimise_period_, 0.5);
    positive(pnh, "marker_width", marker_width_, 0.3);
    pnh.param("use_unverified", use_unverified_, false);
    pnh.param("publish_tf", publish_tf_, true);
    int history = 100000;
    pnh.param("odometry_history", history, history);
    if (history < 100)
    {
      ROS_WARN("pose_graph_node: ~odometry_history %d is too small (expected >= 100); using 100000", history);
      history = 100000;
    }
    odometry_history_ = static_cast<size_t>(history);
    openable::PoseGraphOptions options;
    pnh.param<std::string>("loss", loss_name_, "cauchy");
    if (loss_name_ == "cauchy")
      options.loop_loss = openable::RobustLoss::Cauchy;
    else if (loss_name_ == "huber")
      options.loop_loss = openable::RobustLoss::Huber;
    else if (loss_name_ == "none")
      options.loop_loss = openable::RobustLoss::None;
    else
    {
      ROS_WARN("pose_graph_node: ~loss '%s' is unknown (expected cauchy, huber or none); using cauchy",
               loss_name_.c_str());
      loss_name_ = "cauchy";
    }
    positive(pnh, "loss_scale", options.loop_loss_scale, 1.0);
    graph_ = openable::PoseGraph(options);
  }

  static void positive(ros::NodeHandle& pnh, const std::string& name, double& value, double fallback)
  {
    pnh.param(name, value, fallback);
    if (!(value > 0.0) || !std::isfinite(value))
    {
      ROS_WARN("pose_graph_node: ~%s = %g, expected a finite value > 0; using %g", name.c_str(), value, fallback);
      value = fallback;
    }
  }

  void odometryCallback(const nav_msgs::Odometry::ConstPtr& msg)
  {
    if (!finitePose(msg->pose.pose))
    {
      ROS_WARN_THROTTLE(5.0,
                        "pose_graph_node: odometry on %s at %.3f has a non-finite pose or zero quaternion; ignored",
                        odom_sub_.getTopic().c_str(), msg->header.stamp.toSec());
      return;
    }
    const Eigen::Isometry3d pose = toEigen(msg->pose.pose);
    if (!history_.empty())
    {
      const ros::Time newest = history_.back().stamp;
      if (msg->header.stamp <= keyframes_.front().stamp)
      {
        // Before the very first keyframe: time jumped back (bag restarted with --loop, sim time reset), the
        // graph belongs to another run. A merely late sample lands inside the history instead.
        ROS_WARN(
            "pose_graph_node: odometry jumped back in time from %.3f to %.3f, before the first keyframe; "
            "clearing the graph",
            newest.toSec(), msg->header.stamp.toSec());
        reset();
      }
      else if (msg->header.stamp <= newest)
      {
        // Late / out of order: keep it for placing image stamps, but keyframes only follow the newest.
        ROS_WARN_THROTTLE(5.0,
                          "pose_graph_node: odometry out of order (stamp %.3f <= latest %.3f); kept in the "
                          "history, not used for keyframes",
                          msg->header.stamp.toSec(), newest.toSec());
        auto it = std::upper_bound(history_.begin(), history_.end(), msg->header.stamp,
                                   [](const ros::Time& t, const OdometrySample& s) { return t < s.stamp; });
        if (it == history_.begin() || std::prev(it)->stamp != msg->header.stamp)
          history_.insert(it, OdometrySample{msg->header.stamp, pose});
        return;
      }
    }
    odom_frame_ = msg->header.frame_id;
    child_frame_ = msg->child_frame_id;
    history_.push_back(OdometrySample{msg->header.stamp, pose});
    while (history_.size() > odometry_history_)
      history_.pop_front();

    if (keyframes_.empty() || movedEnough(keyframes_.back().odom_pose, pose))
      addKeyframe(msg->header.stamp, pose);
    retryPending();
    publishTf(msg->header.stamp);
  }

  bool movedEnough(const Eigen::Isometry3d& last, const Eigen::Isometry3d& now) const
  {
    const Eigen::Isometry3d delta = last.inverse() * now;
    return delta.translation().norm() >= keyframe_distance_ ||
           Eigen::AngleAxisd(delta.rotation()).angle() >= keyframe_angle_;
  }

  void addKeyframe(const ros::Time& stamp, const Eigen::Isometry3d& odom_pose)
  {
    if (keyframes_.empty())
    {
      graph_.addNode(odom_pose);  // map and odom coincide at the first keyframe
    }
    else
    {
      // Initial estimate: the previous keyframe's corrected pose chained with the odometry since.
      const Keyframe& last = keyframes_.back();
      const Eigen::Isometry3d delta = last.odom_pose.inverse() * odom_pose;
      const size_t node = graph_.addNode(graph_.pose(keyframes_.size() - 1) * delta);
      const double d = delta.translation().norm();
      const double sigma_t = odometry_sigma_translation_ * d + 0.01;
      const double sigma_r = odometry_sigma_rotation_ * d + 0.002;
      Matrix6d information = Matrix6d::Zero();
      information.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)),
          Eigen::Vector3d::Constant(1.0 / (sigma_r * sigma_r));
      graph_.addOdometry(node - 1, node, delta, information);
    }
    keyframes_.push_back(Keyframe{stamp, odom_pose});
    publishPath(stamp);
  }

  void loopCallback(const LoopClosure::ConstPtr& msg)
  {
    if (!msg->has_relative_pose && !use_unverified_)
    {
      ++ignored_unverified_;
      ROS_INFO_THROTTLE(10.0,
                        "pose_graph_node: %zu loop closure(s) without relative_pose ignored (turn on the "
                        "detector's ~verify, or set ~use_unverified to add them as position constraints)",
                        ignored_unverified_);
      return;
    }
    if (msg->has_relative_pose && !finitePose(msg->relative_pose.pose))
    {
      ROS_WARN_THROTTLE(5.0, "pose_graph_node: loop %u -> %u has a non-finite relative_pose; ignored", msg->query_id,
                        msg->match_id);
      return;
    }
    if (!tryAddLoop(*msg, false))
    {
      pending_.push_back(msg);
      if (pending_.size() > 100)
      {
        ROS_WARN_THROTTLE(5.0,
                          "pose_graph_node: more than 100 loop closures wait for odometry; dropping the oldest "
                          "(is %s being published?)",
                          odom_sub_.getTopic().c_str());
        pending_.pop_front();
      }
    }
  }

  void retryPending()
  {
    for (auto it = pending_.begin(); it != pending_.end();)
      it = tryAddLoop(**it, true) ? pending_.erase(it) : std::next(it);
  }

  // Returns false only when the loop must wait for odometry; true when it was added or dropped.
  bool tryAddLoop(const LoopClosure& msg, bool retry)
  {
    Anchor query, match;
    const Resolve rq = resolve(msg.header.stamp, query);
    const Resolve rm = resolve(msg.match_stamp, match);
    if (rq == Resolve::NotYet || rm == Resolve::NotYet)
    {
      // Drop when odometry has moved well past the stamp without covering it.
      return !history_.empty() &&
             history_.back().stamp > msg.header.stamp + ros::Duration(5.0 * max_interpolation_gap_) &&
             warnUnmatched(msg);
    }
    if (rq == Resolve::Never || rm == Resolve::Never)
      return warnUnmatched(msg);
    if (query.node == match.node)
    {
      ROS_WARN_THROTTLE(5.0,
                        "pose_graph_node: loop %u -> %u joins keyframe %zu to itself (stamps %.3f s apart); "
                        "ignored (raise the detector's exclusion window?)",
                        msg.query_id, msg.match_id, query.node, (msg.header.stamp - msg.match_stamp).toSec());
      return true;
    }
    // match_T_query between cameras -> between the odometry child frames -> between the keyframes.
    Eigen::Isometry3d child_T_camera = Eigen::Isometry3d::Identity();
    if (!msg.header.frame_id.empty() && msg.header.frame_id != child_frame_)
    {
      try
      {
        child_T_camera = toEigen(tf_buffer_.lookupTransform(child_frame_, msg.header.frame_id, ros::Time(0)).transform);
      }
      catch (const tf2::TransformException& e)
      {
        ROS_WARN_THROTTLE(5.0,
                          "pose_graph_node: no tf from odometry child frame '%s' to camera frame '%s' (%s); loop "
                          "%u -> %u ignored",
                          child_frame_.c_str(), msg.header.frame_id.c_str(), e.what(), msg.query_id, msg.match_id);
        return true;
      }
    }
    Eigen::Isometry3d camera_measurement = Eigen::Isometry3d::Identity();
    Matrix6d covariance = Matrix6d::Zero();
    if (msg.has_relative_pose)
    {
      camera_measurement = toEigen(msg.relative_pose.pose);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c)
          covariance(r, c) = msg.relative_pose.covariance[6 * r + c];
    }
    const Eigen::Isometry3d a = match.node_T_frame * child_T_camera;
    const Eigen::Isometry3d b = query.node_T_frame * child_T_camera;
    const Eigen::Isometry3d measurement = a * camera_measurement * b.inverse();
    Matrix6d information;
    if (msg.has_relative_pose)
    {
      try
      {
        // The covariance is over a right perturbation in the query camera; move it to the query keyframe.
        const Matrix6d ad = adjoint(b);
        information = openable::PoseGraph::informationFromCovariance(ad * covariance * ad.transpose());
      }
      catch (const openable::Error& e)
      {
        ROS_WARN_THROTTLE(10.0, "pose_graph_node: loop %u -> %u: %s; using ~default_loop_sigma_* (%.2f m, %.3f rad)",
                          msg.query_id, msg.match_id, e.what(), default_loop_sigma_translation_,
                          default_loop_sigma_rotation_);
        information = diagonal(default_loop_sigma_translation_, default_loop_sigma_rotation_);
      }
    }
    else
    {
      // "Same place" without geometry: the two keyframes' positions agree within a few metres; rotation free
      // (a tiny weight keeps the information positive definite).
      information = diagonal(unverified_sigma_translation_, 1e3);
    }
    graph_.addLoop(match.node, query.node, measurement, information);
    loops_.push_back(std::make_pair(match.node, query.node));
    dirty_ = true;
    if (retry)
      ROS_DEBUG("pose_graph_node: loop %u -> %u added after waiting for odometry", msg.query_id, msg.match_id);
    return true;
  }

  bool warnUnmatched(const LoopClosure& msg)
  {
    ++unmatched_;
    ROS_WARN_THROTTLE(5.0,
                      "pose_graph_node: loop %u -> %u (stamps %.3f, %.3f) matches no keyframe: odometry covers "
                      "%.3f .. %.3f (%zu keyframes); ignored (%zu so far). Loop stamps must be image stamps "
                      "within the odometry's time span",
                      msg.query_id, msg.match_id, msg.header.stamp.toSec(), msg.match_stamp.toSec(),
                      history_.empty() ? 0.0 : history_.front().stamp.toSec(),
                      history_.empty() ? 0.0 : history_.back().stamp.toSec(), keyframes_.size(), unmatched_);
    return true;
  }

  static Matrix6d diagonal(double sigma_t, double sigma_r)
  {
    Matrix6d information = Matrix6d::Zero();
    information.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)),
        Eigen::Vector3d::Constant(1.0 / (sigma_r * sigma_r));
    return information;
  }

  // Places an image stamp: the keyframe nearest in time and the odometry motion from it to the stamp.
  Resolve resolve(const ros::Time& stamp, Anchor& anchor) const
  {
    if (history_.empty() || keyframes_.empty())
      return Resolve::NotYet;
    if (stamp > history_.back().stamp)
      return Resolve::NotYet;
    Eigen::Isometry3d odom_at_stamp;
    if (!odometryAt(stamp, odom_at_stamp))
      return Resolve::Never;
    auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), stamp,
                               [](const Keyframe& k, const ros::Time& t) { return k.stamp < t; });
    if (it == keyframes_.end())
      --it;
    else if (it != keyframes_.begin() && (stamp - std::prev(it)->stamp) < (it->stamp - stamp))
      --it;
    anchor.node = static_cast<size_t>(it - keyframes_.begin());
    anchor.node_T_frame = it->odom_pose.inverse() * odom_at_stamp;
    return Resolve::Ok;
  }

  bool odometryAt(const ros::Time& stamp, Eigen::Isometry3d& pose) const
  {
    auto it = std::lower_bound(history_.begin(), history_.end(), stamp,
                               [](const OdometrySample& s, const ros::Time& t) { return s.stamp < t; });
    if (it == history_.end())
      return false;
    if (it->stamp == stamp)
    {
      pose = it->pose;
      return true;
    }
    if (it == history_.begin())
      return false;  // older than the history
    const OdometrySample& before = *std::prev(it);
    const double gap = (it->stamp - before.stamp).toSec();
    if (gap > max_interpolation_gap_)
      return false;
    pose = interpolate(before.pose, it->pose, (stamp - before.stamp).toSec() / gap);
    return true;
  }

  void optimise()
  {
    dirty_ = false;
    const openable::PoseGraphSummary summary = graph_.optimize();
    if (!summary.usable)
    {
      ROS_WARN("pose_graph_node: optimisation failed (%s); keeping the estimate", summary.message.c_str());
      return;
    }
    const std::vector<double> weights = graph_.loopWeights();
    const size_t outliers =
        static_cast<size_t>(std::count_if(weights.begin(), weights.end(), [](double w) { return w < 0.1; }));
    ROS_INFO("pose_graph_node: %zu keyframes, %zu loops (%zu down-weighted as outliers), cost %.3g -> %.3g in %.3f s",
             graph_.nodeCount(), graph_.loopCount(), outliers, summary.initial_cost, summary.final_cost,
             summary.seconds);
    publishPath(keyframes_.back().stamp);
    publishMarkers(weights);
  }

  void publishPath(const ros::Time& stamp)
  {
    nav_msgs::Path path;
    path.header.stamp = stamp;
    path.header.frame_id = map_frame_;
    path.poses.resize(keyframes_.size());
    for (size_t i = 0; i < keyframes_.size(); ++i)
    {
      path.poses[i].header.stamp = keyframes_[i].stamp;
      path.poses[i].header.frame_id = map_frame_;
      path.poses[i].pose = toPose(graph_.pose(i));
    }
    path_pub_.publish(path);
    if (odom_path_pub_.getNumSubscribers() == 0)
      return;
    nav_msgs::Path odom_path;
    odom_path.header.stamp = stamp;
    odom_path.header.frame_id = odom_frame_;
    odom_path.poses.resize(keyframes_.size());
    for (size_t i = 0; i < keyframes_.size(); ++i)
    {
      odom_path.poses[i].header.stamp = keyframes_[i].stamp;
      odom_path.poses[i].header.frame_id = odom_frame_;
      odom_path.poses[i].pose = toPose(keyframes_[i].odom_pose);
    }
    odom_path_pub_.publish(odom_path);
  }

  void publishMarkers(const std::vector<double>& weights)
  {
    visualization_msgs::MarkerArray markers;
    visualization_msgs::Marker lines;
    lines.header.frame_id = map_frame_;
    lines.header.stamp = keyframes_.back().stamp;
    lines.ns = "loops";
    lines.id = 0;
    lines.type = visualization_msgs::Marker::LINE_LIST;
    lines.action = visualization_msgs::Marker::ADD;
    lines.pose.orientation.w = 1.0;
    lines.scale.x = marker_width_;
    for (size_t i = 0; i < loops_.size(); ++i)
    {
      // Green: trusted loop; red: down-weighted by the robust loss (treated as wrong).
      std_msgs::ColorRGBA color;
      const bool trusted = i >= weights.size() || weights[i] >= 0.1;
      color.r = trusted ? 0.1f : 1.0f;
      color.g = trusted ? 0.9f : 0.1f;
      color.b = 0.1f;
      color.a = 1.0f;
      for (size_t end : {loops_[i].first, loops_[i].second})
      {
        lines.points.push_back(toPose(graph_.pose(end)).position);
        lines.colors.push_back(color);
      }
    }
    markers.markers.push_back(lines);
    marker_pub_.publish(markers);
  }

  // map -> odom such that map -> odom -> child equals the corrected pose of the newest keyframe.
  void publishTf(const ros::Time& stamp)
  {
    if (!publish_tf_ || keyframes_.empty() || odom_frame_.empty())
      return;
    const Eigen::Isometry3d map_T_odom = graph_.pose(keyframes_.size() - 1) * keyframes_.back().odom_pose.inverse();
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = map_frame_;
    t.child_frame_id = odom_frame_;
    const geometry_msgs::Pose p = toPose(map_T_odom);
    t.transform.translation.x = p.position.x;
    t.transform.translation.y = p.position.y;
    t.transform.translation.z = p.position.z;
    t.transform.rotation = p.orientation;
    tf_broadcaster_.sendTransform(t);
  }

  void reset()
  {
    graph_.clear();
    keyframes_.clear();
    history_.clear();
    pending_.clear();
    loops_.clear();
    dirty_ = false;
  }

  // Parameters.
  std::string map_frame_;
  double keyframe_distance_ = 1.0;
  double keyframe_angle_ = 0.2;
  double odometry_sigma_translation_ = 0.02;
  double odometry_sigma_rotation_ = 0.002;
  double default_loop_sigma_translation_ = 0.2;
  double default_loop_sigma_rotation_ = 0.05;
  double unverified_sigma_translation_ = 3.0;
  double max_interpolation_gap_ = 0.5;
  double optimise_period_ = 0.5;
  double marker_width_ = 0.3;
  bool use_unverified_ = false;
  bool publish_tf_ = true;
  size_t odometry_history_ = 100000;
  std::string loss_name_;

  // State.
  openable::PoseGraph graph_;
  std::vector<Keyframe> keyframes_;  // node i of graph_ is keyframes_[i]
  std::deque<OdometrySample> history_;
  std::deque<LoopClosure::ConstPtr> pending_;
  std::vector<std::pair<size_t, size_t>> loops_;  // (match node, query node), in graph_ order
  std::string odom_frame_;
  std::string child_frame_;
  size_t ignored_unverified_ = 0;
  size_t unmatched_ = 0;
  bool dirty_ = false;  // loops added since the last optimisation

  ros::Subscriber odom_sub_;
  ros::Subscriber loop_sub_;
  ros::Publisher path_pub_;
  ros::Publisher odom_path_pub_;
  ros::Publisher marker_pub_;
  ros::WallTimer optimise_timer_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
};

}  // namespace openable_ros

int main(int argc, char** argv)
{
  ros::init(argc, argv, "pose_graph_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  openable_ros::PoseGraphNode node(nh, pnh);
  ros::spin();
  return 0;
}
