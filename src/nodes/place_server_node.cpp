// Standalone place server: loads the openable_ros/PlaceServer nodelet in this process, with this
// node's name, namespace, remappings and private parameters (the image_proc src/nodes pattern).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "place_server");
  nodelet::Loader loader(false);
  nodelet::M_string remappings(ros::names::getRemappings().begin(), ros::names::getRemappings().end());
  nodelet::V_string my_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "openable_ros/PlaceServer", remappings, my_argv))
  {
    ROS_FATAL("could not load the openable_ros/PlaceServer nodelet (is the package built and sourced?)");
    return 1;
  }
  ros::spin();
  return 0;
}
