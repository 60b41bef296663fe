#include "openable_ros/map_services.h"

#include "openable_ros/detector.h"

namespace openable_ros
{
MapServices::MapServices(ros::NodeHandle& pnh, Detector& detector) : detector_(detector)
{
  save_ = pnh.advertiseService("save_map", &MapServices::save, this);
  load_ = pnh.advertiseService("load_map", &MapServices::load, this);
  reset_ = pnh.advertiseService("reset", &MapServices::reset, this);
}

std::string MapServices::path(const std::string& requested, std::string& refusal) const
{
  const std::string path = requested.empty() ? detector_.parameters().map_file : requested;
  if (path.empty())
    refusal = "no path given and ~map_file is empty";
  return path;
}

bool MapServices::save(SaveMap::Request& request, SaveMap::Response& response)
{
  const std::string file = path(request.path, response.message);
  response.success = !file.empty() && detector_.saveMap(file, response.message, response.frames);
  if (response.success)
    ROS_INFO_STREAM(response.message);
  else
    ROS_WARN_STREAM(response.message);
  return true;
}

bool MapServices::load(LoadMap::Request& request, LoadMap::Response& response)
{
  const std::string file = path(request.path, response.message);
  response.success = !file.empty() && detector_.loadMap(file, response.message, response.frames);
  if (response.success)
    ROS_INFO_STREAM(response.message);
  else
    ROS_WARN_STREAM(response.message << "; the current state is kept");
  return true;
}

bool MapServices::reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response)
{
  response.message = detector_.reset();
  response.success = true;
  ROS_INFO_STREAM("reset: " << response.message);
  return true;
}

}  // namespace openable_ros
