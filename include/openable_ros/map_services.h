#pragma once

#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <string>

#include "openable_ros/LoadMap.h"
#include "openable_ros/SaveMap.h"

namespace openable_ros
{
class Detector;

/// ~save_map, ~load_map (an empty path means ~map_file) and ~reset (clears the history; with a loaded map,
/// leaves it and returns to loop-closure mode).
class MapServices
{
public:
  MapServices(ros::NodeHandle& pnh, Detector& detector);

private:
  bool save(SaveMap::Request& request, SaveMap::Response& response);
  bool load(LoadMap::Request& request, LoadMap::Response& response);
  bool reset(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  /// The path to use, or "" with `refusal` set.
  std::string path(const std::string& requested, std::string& refusal) const;

  Detector& detector_;
  ros::ServiceServer save_;
  ros::ServiceServer load_;
  ros::ServiceServer reset_;
};

}  // namespace openable_ros
