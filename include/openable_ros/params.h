#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "openable/config.h"

namespace openable_ros
{
/// Reads every key of openable::Config::keys() that is set on the private node handle, by its type, into a
/// configuration that starts from `defaults` (the nodelet's: its camera_type, and D-LDB for stereo). Each
/// problem (wrong type, NaN, out of range, unknown choice, a camera_type that does not fit the nodelet) is
/// reported in `warnings` as "~name: value 'x' <what is wrong>; <the rule>; using <fallback>" and that key
/// falls back to `defaults`, so the result is always valid (`defaults` must be). camera_type is always
/// the nodelet's own.
openable::Config loadCoreConfig(const ros::NodeHandle& private_nh, const openable::Config& defaults,
                                std::vector<std::string>& warnings);

/// Makes `config` valid by replacing, key by key, what Config::validate() refuses with the value in
/// `fallback` (which must be valid). One message per refusal in `messages`:
/// "~key: value 'x' is not allowed; expected <rule>; <verb> key = <fallback value>" (or "<verb> <everything>"
/// when the rule names no key). False when a rule is still broken afterwards: the caller then falls back
/// whole. Shared by the parameter path (verb "using", the defaults) and dynamic_reconfigure ("keeping", the
/// values in force).
bool fallBackKeyByKey(openable::Config& config, const openable::Config& fallback, const std::string& verb,
                      const std::string& everything, std::vector<std::string>& messages);

/// ROS-only parameters with a rule. Each reads ~name, and when it is missing keeps `fallback`; when it
/// is set but breaks the rule (or has the wrong type) it explains in `warnings` and keeps `fallback`.
double readDouble(const ros::NodeHandle& private_nh, const std::string& name, double fallback, double min, double max,
                  const std::string& units, std::vector<std::string>& warnings);
int readInt(const ros::NodeHandle& private_nh, const std::string& name, int fallback, int min, int max,
            std::vector<std::string>& warnings);
bool readBool(const ros::NodeHandle& private_nh, const std::string& name, bool fallback,
              std::vector<std::string>& warnings);
std::string readString(const ros::NodeHandle& private_nh, const std::string& name, const std::string& fallback,
                       std::vector<std::string>& warnings);
/// A list of strings (e.g. ~cameras); a missing parameter gives an empty list.
std::vector<std::string> readStringList(const ros::NodeHandle& private_nh, const std::string& name,
                                        std::vector<std::string>& warnings);

}  // namespace openable_ros
