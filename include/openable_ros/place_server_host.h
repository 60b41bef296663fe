#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "openable/server/candidate_merger.h"
#include "openable/server/place_server.h"
#include "openable/node_support/throttle.h"
#include "openable_ros/LoadMap.h"
#include "openable_ros/PlaceDescriptor.h"
#include "openable_ros/SaveMap.h"

namespace openable_ros
{
/// The ROS side of a PlaceServer (openable_ros/PlaceServer nodelet): place_descriptors of every robot in
/// ~robots in, loop_closures (holding every session) or candidates (splitting them, ~sessions) out, the map
/// services and diagnostics. Every entry point takes mutex_.
class PlaceServerHost
{
public:
  /// Reads the parameters (explaining every fallback) and starts. Returns nullptr after logging why when it
  /// cannot run; never throws.
  static std::unique_ptr<PlaceServerHost> create(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~PlaceServerHost();

private:
  PlaceServerHost(ros::NodeHandle nh, ros::NodeHandle pnh, std::string name);
  /// `robot`: the robot of the topic (openable::robotOfTopic), empty when the topic carries every robot.
  void descriptorCallback(const PlaceDescriptorConstPtr& msg, const std::string& topic, const std::string& robot);
  bool save(SaveMap::Request& request, SaveMap::Response& response);
  bool load(LoadMap::Request& request, LoadMap::Response& response);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  std::mutex mutex_;
  ros::NodeHandle nh_, pnh_;
  std::string name_;
  std::string map_file_;
  std::unique_ptr<openable::PlaceServer> server_;
  std::unique_ptr<openable::CandidateMerger> merger_;  ///< when this server holds every session
  bool publish_candidates_ = false;
  std::vector<ros::Subscriber> subscribers_;
  ros::Publisher loop_pub_, decisions_pub_, candidates_pub_;
  ros::ServiceServer save_srv_, load_srv_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Timer diagnostics_timer_;
  openable::Throttle throttle_;
  size_t received_ = 0, stored_ = 0, loops_ = 0;
  std::map<std::string, size_t> refused_by_robot_;
};

}  // namespace openable_ros
