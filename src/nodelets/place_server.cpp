// openable_ros/PlaceServer: closes loops between robots from their place_descriptors (no images).
#include <nodelet/nodelet.h>

#include <pluginlib/class_list_macros.hpp>

#include "openable_ros/place_server_host.h"

namespace openable_ros
{
class PlaceServer : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    host_ = PlaceServerHost::create(getNodeHandle(), getPrivateNodeHandle(), getName());
  }

  std::unique_ptr<PlaceServerHost> host_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::PlaceServer, nodelet::Nodelet)
