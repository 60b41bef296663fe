// openable_ros/PoseGraph: the reference backend for openable_ros loop closures, as a nodelet (the
// pose_graph_node executable loads it). The graph logic is openable::PoseGraphBuilder (ROS-free, tested
// in test/core); this file converts messages, looks up tf and publishes.
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
// A figure of the wrong type or outside its range (readParameters) is reported, as the detectors' are, with
// the rule, and replaced by its default.

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <string>
#include <vector>

#include "openable/pose_graph/pose_graph_builder.h"
#include "openable_ros/LoopClosure.h"
#include "openable_ros/params.h"

namespace openable_ros
{
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
  geometry_msgs::Pose pose;
  pose.position.x = p.translation.x;
  pose.position.y = p.translation.y;
  pose.position.z = p.translation.z;
  pose.orientation = p.rotation;
  return toEigen(pose);
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& t)
{
  geometry_msgs::Pose p;
  p.position.x = t.translation().x();
  p.position.y = t.translation().y();
  p.position.z = t.translation().z();
  const Eigen::Quaterniond q(t.rotation());
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

bool finitePose(const geometry_msgs::Pose& p)
{
  const double q = p.orientation.w * p.orientation.w + p.orientation.x * p.orientation.x +
                   p.orientation.y * p.orientation.y + p.orientation.z * p.orientation.z;
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
         std::isfinite(q) && q > 1e-6;
}

}  // namespace

class PoseGraph : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    readParameters(pnh);
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_);
    path_pub_ = nh.advertise<nav_msgs::Path>("path", 1, true);
    odom_path_pub_ = nh.advertise<nav_msgs::Path>("odom_path", 1, true);
    // Not "loop_markers": that is the detector's topic, and both usually share a namespace.
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("loop_edges", 1, true);
    // Deep odometry queue: an optimisation may hold the callback thread for a fraction of a second.
    odom_sub_ = nh.subscribe("odom", 1000, &PoseGraph::odometryCallback, this);
    loop_sub_ = nh.subscribe("loop_closures", 100, &PoseGraph::loopCallback, this);
    optimise_timer_ = nh.createWallTimer(ros::WallDuration(optimise_period_),
                                         [this](const ros::WallTimerEvent&)
                                         {
                                           if (builder_.dirty())
                                             optimise();
                                         });
    NODELET_INFO("pose_graph: keyframes every %.2f m / %.2f rad of %s, loops from %s, %s loss, map frame '%s'",
                 options_.keyframe_distance, options_.keyframe_angle, odom_sub_.getTopic().c_str(),
                 loop_sub_.getTopic().c_str(), loss_name_.c_str(), map_frame_.c_str());
  }

  // Reads and checks every parameter; a bad value is logged with the rule and replaced by the default. The
  // figures go through the detectors' readers (src/ros/params.cpp), so both explain a bad value alike. Each
  // must be > 0 (a zero sigma or period breaks the graph or the timer): its range starts just above 0.
  void readParameters(ros::NodeHandle& pnh)
  {
    std::vector<std::string> warnings;
    pnh.param<std::string>("map_frame", map_frame_, "map");
    options_.keyframe_distance = readDouble(pnh, "keyframe_distance", 1.0, 1e-3, 1e6, "m", warnings);
    options_.keyframe_angle = readDouble(pnh, "keyframe_angle", 0.2, 1e-3, 10.0, "rad", warnings);
    options_.odometry_sigma_translation =
        readDouble(pnh, "odometry_sigma_translation", 0.02, 1e-6, 10.0, "(fraction of the distance)", warnings);
    options_.odometry_sigma_rotation =
        readDouble(pnh, "odometry_sigma_rotation", 0.002, 1e-6, 10.0, "rad per metre", warnings);
    options_.default_loop_sigma_translation =
        readDouble(pnh, "default_loop_sigma_translation", 0.2, 1e-6, 1e3, "m", warnings);
    options_.default_loop_sigma_rotation =
        readDouble(pnh, "default_loop_sigma_rotation", 0.05, 1e-6, 10.0, "rad", warnings);
    options_.unverified_sigma_translation =
        readDouble(pnh, "unverified_sigma_translation", 3.0, 1e-6, 1e3, "m", warnings);
    options_.max_interpolation_gap = readDouble(pnh, "max_interpolation_gap", 0.5, 1e-3, 3600.0, "s", warnings);
    optimise_period_ = readDouble(pnh, "optimise_period", 0.5, 1e-3, 3600.0, "s", warnings);
    marker_width_ = readDouble(pnh, "marker_width", 0.3, 1e-3, 1e3, "m", warnings);
    pnh.param("use_unverified", use_unverified_, false);
    pnh.param("publish_tf", publish_tf_, true);
    options_.odometry_history =
        static_cast<size_t>(readInt(pnh, "odometry_history", 100000, 100, 1000000000, warnings));
    pnh.param<std::string>("loss", loss_name_, "cauchy");
    if (loss_name_ == "cauchy")
      options_.graph.loop_loss = openable::RobustLoss::Cauchy;
    else if (loss_name_ == "huber")
      options_.graph.loop_loss = openable::RobustLoss::Huber;
    else if (loss_name_ == "none")
      options_.graph.loop_loss = openable::RobustLoss::None;
    else
    {
      NODELET_WARN("pose_graph: ~loss '%s' is unknown (expected cauchy, huber or none); using cauchy",
                   loss_name_.c_str());
      loss_name_ = "cauchy";
    }
    options_.graph.loop_loss_scale = readDouble(pnh, "loss_scale", 1.0, 1e-3, 1e3, "standard deviations", warnings);
    for (const auto& warning : warnings)
      NODELET_WARN("pose_graph: parameter %s", warning.c_str());
    builder_ = openable::PoseGraphBuilder(options_);
  }

  void odometryCallback(const nav_msgs::Odometry::ConstPtr& msg)
  {
    if (!finitePose(msg->pose.pose))
    {
      NODELET_WARN_THROTTLE(5.0, "pose_graph: odometry on %s at %.3f has a non-finite pose or zero quaternion; ignored",
                            odom_sub_.getTopic().c_str(), msg->header.stamp.toSec());
      return;
    }
    const auto span = builder_.odometrySpan();
    switch (builder_.addOdometry(msg->header.stamp.toSec(), toEigen(msg->pose.pose)))
    {
      case openable::PoseGraphBuilder::Odometry::Late:
        NODELET_WARN_THROTTLE(5.0,
                              "pose_graph: odometry out of order (stamp %.3f <= latest %.3f); kept in the "
                              "history, not used for keyframes",
                              msg->header.stamp.toSec(), span.second);
        return;
      case openable::PoseGraphBuilder::Odometry::Restarted:
        NODELET_WARN(
            "pose_graph: odometry jumped back in time from %.3f to %.3f, before the first keyframe; "
            "clearing the graph",
            span.second, msg->header.stamp.toSec());
        pending_.clear();
        publishPath(msg->header.stamp);
        break;
      case openable::PoseGraphBuilder::Odometry::Keyframe:
        publishPath(msg->header.stamp);
        break;
      case openable::PoseGraphBuilder::Odometry::Stored:
        break;
    }
    odom_frame_ = msg->header.frame_id;
    child_frame_ = msg->child_frame_id;
    retryPending();
    publishTf(msg->header.stamp);
  }

  void loopCallback(const LoopClosure::ConstPtr& msg)
  {
    if (!msg->has_relative_pose && !use_unverified_)
    {
      ++ignored_unverified_;
      NODELET_INFO_THROTTLE(10.0,
                            "pose_graph: %zu loop closure(s) without relative_pose ignored (turn on the "
                            "detector's ~verify, or set ~use_unverified to add them as position constraints)",
                            ignored_unverified_);
      return;
    }
    if (msg->has_relative_pose && !finitePose(msg->relative_pose.pose))
    {
      NODELET_WARN_THROTTLE(5.0, "pose_graph: loop %u -> %u has a non-finite relative_pose; ignored", msg->query_id,
                            msg->match_id);
      return;
    }
    if (!tryAddLoop(*msg))
    {
      pending_.push_back(msg);
      if (pending_.size() > 100)
      {
        NODELET_WARN_THROTTLE(5.0,
                              "pose_graph: more than 100 loop closures wait for odometry; dropping the oldest "
                              "(is %s being published?)",
                              odom_sub_.getTopic().c_str());
        pending_.pop_front();
      }
    }
  }

  void retryPending()
  {
    for (auto it = pending_.begin(); it != pending_.end();)
      it = tryAddLoop(**it) ? pending_.erase(it) : std::next(it);
  }

  // Returns false only when the loop must wait for odometry; true when it was added or dropped.
  bool tryAddLoop(const LoopClosure& msg)
  {
    openable::LoopMeasurement loop;
    loop.query_stamp = msg.header.stamp.toSec();
    loop.match_stamp = msg.match_stamp.toSec();
    loop.has_relative_pose = msg.has_relative_pose;
    if (msg.has_relative_pose)
    {
      loop.match_T_query = toEigen(msg.relative_pose.pose);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c)
          loop.covariance(r, c) = msg.relative_pose.covariance[size_t(6 * r + c)];
    }
    if (!msg.header.frame_id.empty() && !child_frame_.empty() && msg.header.frame_id != child_frame_)
    {
      try
      {
        loop.child_T_camera =
            toEigen(tf_buffer_.lookupTransform(child_frame_, msg.header.frame_id, ros::Time(0)).transform);
      }
      catch (const tf2::TransformException& e)
      {
        NODELET_WARN_THROTTLE(5.0,
                              "pose_graph: no tf from odometry child frame '%s' to camera frame '%s' (%s); loop "
                              "%u -> %u ignored",
                              child_frame_.c_str(), msg.header.frame_id.c_str(), e.what(), msg.query_id, msg.match_id);
        return true;
      }
    }
    using Loop = openable::PoseGraphBuilder::Loop;
    switch (builder_.addLoop(loop))
    {
      case Loop::Wait:
        return false;
      case Loop::Unplaced:
      {
        ++unmatched_;
        const auto span = builder_.odometrySpan();
        NODELET_WARN_THROTTLE(5.0,
                              "pose_graph: loop %u -> %u (stamps %.3f, %.3f) matches no keyframe: odometry covers "
                              "%.3f .. %.3f (%zu keyframes); ignored (%zu so far). Loop stamps must be image "
                              "stamps within the odometry's time span",
                              msg.query_id, msg.match_id, loop.query_stamp, loop.match_stamp, span.first, span.second,
                              builder_.keyframes(), unmatched_);
        return true;
      }
      case Loop::SameKeyframe:
        NODELET_WARN_THROTTLE(5.0,
                              "pose_graph: loop %u -> %u joins one keyframe to itself (stamps %.3f s apart); "
                              "ignored (raise the detector's exclusion window?)",
                              msg.query_id, msg.match_id, loop.query_stamp - loop.match_stamp);
        return true;
      case Loop::AddedWithDefaultCovariance:
        NODELET_WARN_THROTTLE(10.0,
                              "pose_graph: loop %u -> %u: unusable covariance; using ~default_loop_sigma_* "
                              "(%.2f m, %.3f rad)",
                              msg.query_id, msg.match_id, options_.default_loop_sigma_translation,
                              options_.default_loop_sigma_rotation);
        return true;
      case Loop::Added:
        return true;
    }
    return true;
  }

  void optimise()
  {
    const openable::PoseGraphSummary summary = builder_.optimize();
    if (!summary.usable)
    {
      NODELET_WARN("pose_graph: optimisation failed (%s); keeping the estimate", summary.message.c_str());
      return;
    }
    const std::vector<double> weights = builder_.graph().loopWeights();
    const size_t outliers =
        static_cast<size_t>(std::count_if(weights.begin(), weights.end(), [](double w) { return w < 0.1; }));
    NODELET_INFO("pose_graph: %zu keyframes, %zu loops (%zu down-weighted as outliers), cost %.3g -> %.3g in %.3f s",
                 builder_.graph().nodeCount(), builder_.graph().loopCount(), outliers, summary.initial_cost,
                 summary.final_cost, summary.seconds);
    const ros::Time stamp(builder_.keyframeStamp(builder_.keyframes() - 1));
    publishPath(stamp);
    publishMarkers(weights, stamp);
  }

  nav_msgs::Path path(const ros::Time& stamp, const std::string& frame, bool corrected) const
  {
    nav_msgs::Path path;
    path.header.stamp = stamp;
    path.header.frame_id = frame;
    path.poses.resize(builder_.keyframes());
    for (size_t i = 0; i < builder_.keyframes(); ++i)
    {
      path.poses[i].header.stamp = ros::Time(builder_.keyframeStamp(i));
      path.poses[i].header.frame_id = frame;
      path.poses[i].pose = toPose(corrected ? builder_.graph().pose(i) : builder_.keyframeOdometry(i));
    }
    return path;
  }

  void publishPath(const ros::Time& stamp)
  {
    path_pub_.publish(path(stamp, map_frame_, true));
    if (odom_path_pub_.getNumSubscribers() > 0)
      odom_path_pub_.publish(path(stamp, odom_frame_, false));
  }

  void publishMarkers(const std::vector<double>& weights, const ros::Time& stamp)
  {
    visualization_msgs::MarkerArray markers;
    visualization_msgs::Marker lines;
    lines.header.frame_id = map_frame_;
    lines.header.stamp = stamp;
    lines.ns = "loops";
    lines.type = visualization_msgs::Marker::LINE_LIST;
    lines.action = visualization_msgs::Marker::ADD;
    lines.pose.orientation.w = 1.0;
    lines.scale.x = marker_width_;
    const auto& loops = builder_.loops();
    for (size_t i = 0; i < loops.size(); ++i)
    {
      // Green: trusted loop; red: down-weighted by the robust loss (treated as wrong).
      std_msgs::ColorRGBA color;
      const bool trusted = i >= weights.size() || weights[i] >= 0.1;
      color.r = trusted ? 0.1f : 1.0f;
      color.g = trusted ? 0.9f : 0.1f;
      color.b = 0.1f;
      color.a = 1.0f;
      for (size_t end : {loops[i].first, loops[i].second})
      {
        lines.points.push_back(toPose(builder_.graph().pose(end)).position);
        lines.colors.push_back(color);
      }
    }
    markers.markers.push_back(lines);
    marker_pub_.publish(markers);
  }

  // map -> odom such that map -> odom -> child equals the corrected pose of the newest keyframe.
  void publishTf(const ros::Time& stamp)
  {
    if (!publish_tf_ || builder_.keyframes() == 0 || odom_frame_.empty())
      return;
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = map_frame_;
    t.child_frame_id = odom_frame_;
    const geometry_msgs::Pose p = toPose(builder_.mapFromOdometry());
    t.transform.translation.x = p.position.x;
    t.transform.translation.y = p.position.y;
    t.transform.translation.z = p.position.z;
    t.transform.rotation = p.orientation;
    tf_broadcaster_.sendTransform(t);
  }

  openable::PoseGraphBuilderOptions options_;
  openable::PoseGraphBuilder builder_;
  std::string map_frame_;
  std::string loss_name_;
  double optimise_period_ = 0.5;
  double marker_width_ = 0.3;
  bool use_unverified_ = false;
  bool publish_tf_ = true;
  std::deque<LoopClosure::ConstPtr> pending_;
  std::string odom_frame_;
  std::string child_frame_;
  size_t ignored_unverified_ = 0;
  size_t unmatched_ = 0;

  ros::Subscriber odom_sub_;
  ros::Subscriber loop_sub_;
  ros::Publisher path_pub_;
  ros::Publisher odom_path_pub_;
  ros::Publisher marker_pub_;
  ros::WallTimer optimise_timer_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::PoseGraph, nodelet::Nodelet)
