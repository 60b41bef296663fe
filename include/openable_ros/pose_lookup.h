#pragma once

#include <std_msgs/Header.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <array>
#include <memory>
#include <string>

namespace openable_ros
{
/// The camera's pose in ~fixed_frame at an image's stamp, from tf2. Off (always false) when the fixed
/// frame is empty.
class PoseLookup
{
public:
  PoseLookup(ros::NodeHandle& nh, const std::string& fixed_frame, double timeout);

  bool enabled() const
  {
    return buffer_ != nullptr;
  }
  /// x y z qx qy qz qw; false with `problem` set (for a throttled warning) when there is none.
  bool lookup(const std_msgs::Header& header, std::array<double, 7>& pose, std::string& problem) const;
  /// Forgets the buffered transforms (a bag restarted).
  void clear();

private:
  std::string fixed_frame_;
  double timeout_;
  std::unique_ptr<tf2_ros::Buffer> buffer_;
  std::unique_ptr<tf2_ros::TransformListener> listener_;
};

}  // namespace openable_ros
