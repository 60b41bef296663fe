#pragma once

#include <ros/ros.h>
#include <std_msgs/Header.h>

#include <string>

#include "openable/detection/loop_detector.h"
#include "openable/detection/online_detector.h"

namespace openable_ros
{
/// place_descriptors (openable_ros/PlaceDescriptor): every frame a detector stores, as its descriptor, so
/// that PlaceServers elsewhere on the ROS network can close loops between robots without images.
class DescriptorPublisher
{
public:
  /// `robot` empty: the namespace of `nh` without slashes ("/robot1" -> "robot1"; the root: "robot").
  /// The session name is the robot name, plus "/<session>" when `session` is not 0.
  DescriptorPublisher(ros::NodeHandle nh, const std::string& robot, int session, const openable::Config& config);

  /// Publishes the frame `outcome` stored, read back from the detector's own session (the outcome does not
  /// carry the descriptor). Nothing when the frame was not stored (keyframe, localisation).
  void publish(const std_msgs::Header& header, const openable::FrameOutcome& outcome,
               const openable::LoopDetector& detector);

  const std::string& robot() const
  {
    return robot_;
  }

private:
  ros::Publisher pub_;
  std::string robot_;
  std::string session_;
  uint64_t hash_;
};

}  // namespace openable_ros
