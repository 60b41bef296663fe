// The checkers' odometry on /tf. A tf2_ros::TransformBroadcaster publishes at once, and a transform sent
// before the detector's tf listener has connected is lost: that frame is then kept without a pose (one more
// keyframe than expected). TfSender waits for the listener first.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include "test_helpers.h"

namespace openable_ros_test
{
class TfSender
{
public:
  explicit TfSender(ros::NodeHandle& nh) : pub_(nh.advertise<tf2_msgs::TFMessage>("/tf", 100))
  {
  }
  /// True once a tf listener (the detector's) is connected, within `seconds`.
  bool waitForListener(double seconds)
  {
    return waitFor([this] { return pub_.getNumSubscribers() > 0; }, seconds);
  }
  void send(const geometry_msgs::TransformStamped& transform)
  {
    tf2_msgs::TFMessage message;
    message.transforms.push_back(transform);
    pub_.publish(message);
  }

private:
  ros::Publisher pub_;
};

}  // namespace openable_ros_test
