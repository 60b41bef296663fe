#include "openable_ros/loop_markers.h"

#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>

namespace openable_ros
{
namespace
{
// At most this many trajectory points and loop edges are kept (oldest leave first).
const size_t kMaxTrajectoryPoints = 20000;
const size_t kMaxLoopEdges = 5000;

/// One marker: ADD when it has something to show, else DELETE (clears an old one in rviz).
visualization_msgs::Marker makeMarker(const std_msgs::Header& header, const std::string& ns, int id, int type,
                                      bool visible, double width, float r, float g, float b)
{
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visible ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
  m.pose.orientation.w = 1.0;
  m.scale.x = width;
  m.color.r = r;
  m.color.g = g;
  m.color.b = b;
  m.color.a = 1.0f;
  return m;
}
}  // namespace

LoopMarkers::LoopMarkers(ros::NodeHandle& nh, const std::string& fixed_frame, double rate)
  : publisher_(nh.advertise<visualization_msgs::MarkerArray>("loop_markers", 1, true)),
    fixed_frame_(fixed_frame),
    rate_(rate)
{
}

void LoopMarkers::addPosition(const geometry_msgs::Point& p)
{
  trajectory_.push_back(p);
  while (trajectory_.size() > kMaxTrajectoryPoints)
    trajectory_.pop_front();
}

void LoopMarkers::addLoop(const geometry_msgs::Point& query, const geometry_msgs::Point& match)
{
  loops_.emplace_back(query, match);
  while (loops_.size() > kMaxLoopEdges)
    loops_.pop_front();
}

void LoopMarkers::publish(const ros::Time& stamp, bool force)
{
  if (fixed_frame_.empty() || publisher_.getNumSubscribers() == 0 || rate_ <= 0.0)
    return;
  const ros::WallTime now = ros::WallTime::now();
  if (!force && !last_.isZero() && (now - last_).toSec() < 1.0 / rate_)
    return;
  last_ = now;
  auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
  std_msgs::Header header;
  header.frame_id = fixed_frame_;
  header.stamp = stamp;
  using visualization_msgs::Marker;

  Marker trajectory =
      makeMarker(header, "trajectory", 0, Marker::LINE_STRIP, trajectory_.size() >= 2, 0.05, 0.2f, 0.6f, 1.0f);
  trajectory.points.assign(trajectory_.begin(), trajectory_.end());
  markers->markers.push_back(trajectory);

  Marker loops = makeMarker(header, "loop_closures", 1, Marker::LINE_LIST, !loops_.empty(), 0.08, 1.0f, 0.0f, 1.0f);
  for (const auto& edge : loops_)
  {
    loops.points.push_back(edge.first);
    loops.points.push_back(edge.second);
  }
  markers->markers.push_back(loops);

  Marker current = makeMarker(header, "current", 2, Marker::SPHERE, !trajectory_.empty(), 0.3, 1.0f, 0.8f, 0.0f);
  if (!trajectory_.empty())
    current.pose.position = trajectory_.back();
  current.scale.y = current.scale.z = 0.3;
  markers->markers.push_back(current);
  publisher_.publish(visualization_msgs::MarkerArrayConstPtr(markers));
}

void LoopMarkers::clear()
{
  trajectory_.clear();
  loops_.clear();
}

}  // namespace openable_ros
