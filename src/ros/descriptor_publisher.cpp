#include "openable_ros/descriptor_publisher.h"

#include <boost/make_shared.hpp>

#include "openable/map/session_map.h"
#include "openable_ros/PlaceDescriptor.h"
#include "openable_ros/conversions.h"

namespace openable_ros
{
namespace
{
std::string robotName(const ros::NodeHandle& nh, const std::string& robot)
{
  if (!robot.empty())
    return robot;
  std::string name = nh.getNamespace();
  while (!name.empty() && name.front() == '/')
    name.erase(0, 1);
  for (char& c : name)
    if (c == '/')
      c = '_';
  return name.empty() ? "robot" : name;
}
}  // namespace

DescriptorPublisher::DescriptorPublisher(ros::NodeHandle nh, const std::string& robot, int session,
                                         const openable::Config& config)
  : robot_(robotName(nh, robot)),
    session_(session == 0 ? robot_ : robot_ + "/" + std::to_string(session)),
    hash_(openable::descriptorHash(config))
{
  // Not latched, a generous queue: a server that is slow for a moment must not lose frames (a gap breaks
  // its sequences), and one descriptor is small.
  pub_ = nh.advertise<PlaceDescriptor>("place_descriptors", 1000);
}

void DescriptorPublisher::publish(const std_msgs::Header& header, const openable::FrameOutcome& outcome,
                                  const openable::LoopDetector& detector)
{
  if (!outcome.stored || detector.ownSession() < 0)
    return;
  const openable::PlaceDatabase& frames = detector.map().frames(uint32_t(detector.ownSession()));
  if (frames.empty() || frames.firstId() + frames.size() - 1 != outcome.query.id)
    return;  // not the frame just stored (cannot happen while the caller holds the detector)
  const uint64_t* words = frames.descriptor(frames.size() - 1);
  auto msg = boost::make_shared<PlaceDescriptor>();
  msg->header = header;
  msg->robot = robot_;
  msg->session = session_;
  msg->frame_id = outcome.query.id;
  msg->config_hash = hash_;
  msg->descriptor.assign(words, words + frames.layout().frameWords());
  msg->has_pose = outcome.query.has_pose;
  msg->pose.orientation.w = 1.0;
  if (outcome.query.has_pose)
    msg->pose = toPoseMsg(outcome.query.pose);
  pub_.publish(PlaceDescriptorConstPtr(msg));
}

}  // namespace openable_ros
