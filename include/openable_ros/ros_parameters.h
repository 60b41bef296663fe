#pragma once

#include <ros/node_handle.h>

#include <functional>
#include <string>
#include <vector>

namespace openable_ros
{
/// The ROS-only parameters of the detector nodelets (the core keys are openable::Config's). Their
/// defaults, ranges, units and docs live in one table, rosParameterTable(): config/ros.yaml and the table
/// of doc/ros_api.md are tested against it.
struct RosParameters
{
  // Inputs.
  int queue_size = 10;
  double sync_warning_timeout = 5.0;
  bool approximate_sync = false;     ///< stereo, panoramic ring
  bool use_disparity = false;        ///< stereo
  std::vector<std::string> cameras;  ///< panoramic ring
  double max_skew = 0.02;            ///< panoramic ring
  // Stream.
  bool reset_on_time_jump = false;
  int session = 0;
  std::string map_file;
  std::string map_mode = "localise";  ///< what a loaded map is for: localise | continue
  std::string session_name;           ///< the new session's name when continuing a map (empty: a default)
  // tf, keyframes, markers.
  std::string fixed_frame;
  double tf_timeout = 0.05;
  double keyframe_distance = 0.0;
  double keyframe_angle = 0.0;
  double markers_rate = 1.0;
  // Geographic positions (~fix).
  double fix_tolerance = 0.5;
  std::string geo_file;
  // distance_matrix.
  double matrix_rate = 2.0;
  int matrix_size = 512;
  std::string matrix_mode = "whole_history";
  bool matrix_threshold_view = false;
  // Geometric verification.
  bool verify = false;
  bool verify_required = true;
  double verify_memory = 256.0;
  // Multi-robot (PlaceServer).
  bool publish_descriptors = false;
  std::string robot;  ///< sent in place_descriptors and stored with this run's session
};

/// One row of the table.
struct RosParameter
{
  std::string name;
  std::string type;           ///< bool | int | double | string | list
  std::string default_value;  ///< as written in YAML
  std::string range;          ///< "[min, max]", "a | b" or ""
  std::string units;
  std::string nodelets;  ///< "all", "stereo", "panoramic", "stereo, panoramic"
  std::string doc;
  /// Reads ~name into the struct; a bad value is explained in `warnings` and the default kept.
  std::function<void(const ros::NodeHandle&, RosParameters&, std::vector<std::string>&)> read;
};

const std::vector<RosParameter>& rosParameterTable();

/// Every parameter of the table from the private node handle (each problem explained in `warnings`),
/// then the cross-parameter rules (keyframes need ~fixed_frame).
RosParameters readRosParameters(const ros::NodeHandle& private_nh, std::vector<std::string>& warnings);

/// Why `value` (as text) breaks the table's range or choices of ROS parameter `name`, as
/// "~name: value 'x' is not allowed; expected <rule>"; empty when allowed or when the row has no rule.
/// Used where values arrive without the parameter server (dynamic_reconfigure).
std::string rosParameterProblem(const std::string& name, const std::string& value);

/// Private parameters that no table knows (neither openable::Config's nor this one), e.g. a typo
/// ("treshold"): one warning each, naming the closest known name.
void warnUnknownParameters(const ros::NodeHandle& private_nh, std::vector<std::string>& warnings);

}  // namespace openable_ros
