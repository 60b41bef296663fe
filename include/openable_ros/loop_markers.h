#pragma once

#include <geometry_msgs/Point.h>
#include <ros/ros.h>

#include <deque>
#include <string>
#include <utility>

namespace openable_ros
{
/// loop_markers: the trajectory, the loop edges and the current position in ~fixed_frame (only when it is
/// set), bounded so publishing stays cheap on a robot that runs for days. Latched.
class LoopMarkers
{
public:
  LoopMarkers(ros::NodeHandle& nh, const std::string& fixed_frame, double rate);

  void addPosition(const geometry_msgs::Point& p);
  void addLoop(const geometry_msgs::Point& query, const geometry_msgs::Point& match);
  /// Publishes when watched and due (`force`: at once, e.g. after a loop closure).
  void publish(const ros::Time& stamp, bool force);
  void clear();

private:
  ros::Publisher publisher_;
  std::string fixed_frame_;
  double rate_;
  ros::WallTime last_;
  std::deque<geometry_msgs::Point> trajectory_;
  std::deque<std::pair<geometry_msgs::Point, geometry_msgs::Point>> loops_;
};

}  // namespace openable_ros
