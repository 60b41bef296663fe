#pragma once

#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/server.h>

#include <boost/thread/recursive_mutex.hpp>

#include "openable/config.h"
#include "openable_ros/DetectorConfig.h"
#include "openable_ros/ros_parameters.h"

namespace openable_ros
{
class Detector;

/// dynamic_reconfigure for the detectors: every core key flagged live in openable::Config's table (by
/// name, no hand-written list: cfg/Detector.cfg is tested against the table) plus the display parameters.
/// A change goes straight to Detector::applyLive(); what the core refuses is reverted and the server shows
/// the values in force.
class LiveReconfigure
{
public:
  /// Starts the server from the values in force (not from the raw parameters), then calls back on changes.
  LiveReconfigure(ros::NodeHandle& pnh, Detector& detector, const openable::Config& config,
                  const RosParameters& parameters);

  /// The live core keys of a reconfigure message into `config` (keys not in the message are kept).
  static void toCore(const dynamic_reconfigure::Config& message, openable::Config& config);
  /// The live core keys of `config` into a reconfigure message that already holds every parameter.
  static void fromCore(const openable::Config& config, dynamic_reconfigure::Config& message);

private:
  void callback(DetectorConfig& requested, uint32_t level);

  Detector& detector_;
  boost::recursive_mutex mutex_;  // dynamic_reconfigure wants a boost mutex
  dynamic_reconfigure::Server<DetectorConfig> server_;
};

}  // namespace openable_ros
