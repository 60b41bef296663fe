// sim_time_guard: deletes /use_sim_time when the launch that set it ends.
//
// replay.launch sets /use_sim_time true for rosbag play --clock. roslaunch has no way to unset a global
// parameter on shutdown, so with a roscore of its own the next live node would wait forever for a /clock
// that no one publishes. This node does nothing until roslaunch stops it (SIGINT, then SIGTERM), and then
// deletes the parameter (ROS's default is false). When roslaunch started the master itself, the master and
// its parameters go anyway; the delete then fails quietly.
#include <ros/ros.h>

#include <atomic>
#include <csignal>

namespace
{
std::atomic<bool> stop_requested(false);

void requestStop(int)
{
  stop_requested = true;
}
}  // namespace

int main(int argc, char** argv)
{
  // Our own SIGINT handler: roscpp's would shut the node down before the parameter can be deleted.
  ros::init(argc, argv, "sim_time_guard", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, requestStop);
  std::signal(SIGTERM, requestStop);
  ros::NodeHandle nh;
  while (!stop_requested && ros::ok())
    ros::WallDuration(0.05).sleep();
  if (ros::master::check() && ros::param::has("/use_sim_time"))
  {
    ros::param::del("/use_sim_time");
    ROS_INFO("sim_time_guard: /use_sim_time deleted (back to wall-clock time)");
  }
  ros::shutdown();
  return 0;
}
