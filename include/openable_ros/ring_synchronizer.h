#pragma once

#include <sensor_msgs/Image.h>

#include <cstddef>
#include <deque>
#include <vector>

namespace openable_ros
{
/// Synchronises a runtime number of image topics (a camera ring), which message_filters' Synchronizer
/// (fixed arity) cannot. A set is complete when every camera has an image whose stamp is within
/// `max_skew` seconds of the newest arrival (0 = identical stamps, ExactTime-like). Each camera keeps at
/// most `queue_size` images; older ones are dropped, and every image at or before a completed set's
/// stamps is discarded with it.
class RingSynchronizer
{
public:
  using Set = std::vector<sensor_msgs::ImageConstPtr>;

  RingSynchronizer(size_t cameras, size_t queue_size, double max_skew);

  /// Adds camera `camera`'s image; returns true and fills `set` (ring order) when it completes a set.
  bool add(size_t camera, const sensor_msgs::ImageConstPtr& image, Set& set);
  /// Images dropped without ever being part of a set (queue overflow).
  size_t dropped() const
  {
    return dropped_;
  }

private:
  std::vector<std::deque<sensor_msgs::ImageConstPtr>> queues_;
  size_t queue_size_;
  double max_skew_;
  size_t dropped_ = 0;
};

}  // namespace openable_ros
