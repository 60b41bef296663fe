// Shared by the rostest checkers: real images from ../shared/data, the detector's diagnostics, and
// waiting with deadlines.
#pragma once

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <functional>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace openable_ros_test
{
/// Spins (the AsyncSpinner does the work) until `done` or `seconds` pass; returns done().
inline bool waitFor(const std::function<bool()>& done, double seconds)
{
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < deadline)
  {
    if (done())
    {
      return true;
    }
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

inline sensor_msgs::ImagePtr toMsg(const cv::Mat& image, const std::string& encoding, const ros::Time& stamp,
                                   const std::string& frame_id = "camera")
{
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = frame_id;
  return cv_bridge::CvImage(header, encoding, image).toImageMsg();
}

/// Keeps the last values of the detector's diagnostic status ("... loop closure detector").
class DiagnosticsWatcher
{
public:
  explicit DiagnosticsWatcher(ros::NodeHandle& nh)
  {
    sub_ = nh.subscribe("/diagnostics", 10, &DiagnosticsWatcher::callback, this);
  }
  /// The value of `key`, or "" when no report had it yet.
  std::string value(const std::string& key)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = values_.find(key);
    return it == values_.end() ? "" : it->second;
  }
  long number(const std::string& key)
  {
    const std::string v = value(key);
    return v.empty() ? -1 : std::stol(v);
  }
  int reports()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return reports_;
  }
  /// The worst level (OK 0, WARN 1, ERROR 2) of any report so far.
  int worstLevel()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return worst_level_;
  }

private:
  void callback(const diagnostic_msgs::DiagnosticArrayConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg->status)
    {
      const std::string suffix = "loop closure detector";
      if (status.name.size() < suffix.size() ||
          status.name.compare(status.name.size() - suffix.size(), suffix.size(), suffix) != 0)
      {
        continue;
      }
      ++reports_;
      worst_level_ = std::max(worst_level_, int(status.level));
      for (const auto& kv : status.values)
      {
        values_[kv.key] = kv.value;
      }
    }
  }

  ros::Subscriber sub_;
  std::mutex mutex_;
  std::map<std::string, std::string> values_;
  int reports_ = 0;
  int worst_level_ = 0;
};

}  // namespace openable_ros_test
