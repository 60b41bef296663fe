#include "openable_ros/place_messages.h"

#include <boost/make_shared.hpp>

#include "openable/description/input_contract.h"
#include "openable_ros/conversions.h"

namespace openable_ros
{
namespace
{
std::array<double, 7> toPose(const geometry_msgs::Pose& p)
{
  return {{p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z,
           p.orientation.w}};
}

geometry_msgs::Pose poseOrIdentity(bool has_pose, const std::array<double, 7>& pose)
{
  geometry_msgs::Pose p;
  p.orientation.w = 1.0;
  return has_pose ? toPoseMsg(pose) : p;
}
}  // namespace

openable::PlaceDescriptorInput toInput(const PlaceDescriptor& msg)
{
  openable::PlaceDescriptorInput in;
  in.robot = msg.robot;
  in.session = msg.session;
  in.frame_id = msg.frame_id;
  in.stamp = msg.header.stamp.toSec();
  in.config_hash = msg.config_hash;
  in.descriptor.assign(msg.descriptor.begin(), msg.descriptor.end());
  in.has_pose = msg.has_pose;
  in.pose = toPose(msg.pose);
  return in;
}

PlaceCandidatesPtr toMsg(const std_msgs::Header& header, const openable::ServerCandidates& a)
{
  auto msg = boost::make_shared<PlaceCandidates>();
  msg->header = header;
  msg->server = a.server;
  msg->query_robot = a.query_robot;
  msg->query_session = a.query_session;
  msg->query_frame = a.query_frame;
  msg->query_stored = a.stored;
  msg->query_id = a.query_id;
  msg->has_query_pose = a.has_query_pose;
  msg->query_pose = poseOrIdentity(a.has_query_pose, a.query_pose);
  msg->candidates = uint32_t(a.candidates);
  msg->own_excluded = a.own_excluded;
  msg->has_own_edge = a.has_own_edge;
  msg->own_edge_id = a.own_edge_id;
  msg->own_short_map = a.own_short_map;
  msg->own_first_id = a.own_first_id;
  msg->other_frames = uint32_t(a.other_frames);
  for (const openable::ServerCandidate& c : a.top)
  {
    PlaceCandidate m;
    m.session = c.session;
    m.id = c.id;
    m.distance = c.distance;
    m.sequence_length = c.sequence_length;
    m.direction = c.direction;
    m.shift = c.shift;
    m.stamp = ros::Time(std::max(0.0, c.stamp));
    m.has_pose = c.has_pose;
    m.pose = poseOrIdentity(c.has_pose, c.pose);
    msg->top.push_back(m);
  }
  return msg;
}

openable::ServerCandidates fromMsg(const PlaceCandidates& msg)
{
  openable::ServerCandidates a;
  a.server = msg.server;
  a.query_robot = msg.query_robot;
  a.query_session = msg.query_session;
  a.query_frame = msg.query_frame;
  a.query_stamp = msg.header.stamp.toSec();
  a.stored = msg.query_stored;
  a.query_id = msg.query_id;
  a.has_query_pose = msg.has_query_pose;
  a.query_pose = toPose(msg.query_pose);
  a.candidates = msg.candidates;
  a.own_excluded = msg.own_excluded;
  a.has_own_edge = msg.has_own_edge;
  a.own_edge_id = msg.own_edge_id;
  a.own_short_map = msg.own_short_map;
  a.own_first_id = msg.own_first_id;
  a.other_frames = msg.other_frames;
  for (const PlaceCandidate& m : msg.top)
  {
    openable::ServerCandidate c;
    c.session = m.session;
    c.id = m.id;
    c.distance = m.distance;
    c.sequence_length = m.sequence_length;
    c.direction = m.direction;
    c.shift = m.shift;
    c.stamp = m.stamp.toSec();
    c.has_pose = m.has_pose;
    c.pose = toPose(m.pose);
    a.top.push_back(c);
  }
  return a;
}

LoopClosurePtr makeLoopClosure(const std_msgs::Header& header, const openable::MergedOutcome& o,
                               openable::CandidateMerger& merger)
{
  auto msg = boost::make_shared<LoopClosure>();
  msg->header = header;
  msg->status = openable::toString(o.status);
  msg->score = o.score;
  msg->query_id = uint32_t(o.query_stored ? o.query_id : o.query_frame);
  msg->query_session = merger.sessionIndex(o.query_session);
  msg->query_session_name = o.query_session;
  msg->uniqueness = o.detection.uniqueness;
  msg->relief = o.detection.relief;
  msg->query_pose.orientation.w = 1.0;
  msg->match_pose.orientation.w = 1.0;
  msg->relative_pose.pose.orientation.w = 1.0;
  if (o.top.empty())
    return msg;
  const openable::ServerCandidate& best = o.top.front();
  msg->match_id = uint32_t(best.id);
  msg->match_stamp = ros::Time(std::max(0.0, best.stamp));
  msg->match_session = merger.sessionIndex(best.session);
  msg->match_session_name = best.session;
  msg->distance = best.distance;
  msg->sequence_length = best.sequence_length;
  msg->direction = best.direction;
  msg->shift = best.shift;
  // The last gate before a backend: poses from another server's candidates pass the input contract too.
  openable::Pose query_pose = o.query_pose, match_pose = best.pose;
  msg->has_poses = o.has_query_pose && best.has_pose && openable::checkPose(query_pose).ok() &&
                   openable::checkPose(match_pose).ok();
  if (msg->has_poses)
  {
    msg->query_pose = toPoseMsg(query_pose);
    msg->match_pose = toPoseMsg(match_pose);
  }
  return msg;
}

}  // namespace openable_ros
