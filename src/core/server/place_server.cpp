#include "openable/server/place_server.h"

#include <algorithm>
#include <sstream>

#include "openable/description/frame_describer.h"

namespace openable
{
namespace
{
Config matchingConfig(const Config& config)
{
  config.validateOrThrow();
  Config c = config;
  // MapMatcher always looks for max(top_k, 2) places and returns top_k: asking for at least two changes
  // nothing it computes, and gives a merger the second best it needs for uniqueness.
  c.top_k = std::max(c.top_k, 2);
  return c;
}

std::string hex(uint64_t value)
{
  std::ostringstream out;
  out << "0x" << std::hex << value;
  return out.str();
}
}  // namespace

PlaceServer::PlaceServer(const Config& config, std::vector<std::string> owned, std::string name)
  : config_(config),
    matching_(matchingConfig(config)),
    owned_(std::move(owned)),
    name_(std::move(name)),
    hash_(descriptorHash(config)),
    map_(descriptorLayout(config), config.toYaml())
{
}

bool PlaceServer::owns(const std::string& session) const
{
  return owned_.empty() || std::find(owned_.begin(), owned_.end(), session) != owned_.end();
}

std::string robotOfTopic(const std::string& topic)
{
  std::string robot = topic;
  const std::string suffix = "place_descriptors";
  if (robot.size() >= suffix.size() && robot.compare(robot.size() - suffix.size(), suffix.size(), suffix) == 0)
    robot.erase(robot.size() - suffix.size());
  while (!robot.empty() && robot.front() == '/')
    robot.erase(0, 1);
  while (!robot.empty() && robot.back() == '/')
    robot.pop_back();
  for (char& c : robot)
    if (c == '/')
      c = '_';
  return robot;
}

std::array<double, 7> PlaceServer::check(const PlaceDescriptorInput& input) const
{
  const std::string who = "robot '" + input.robot + "' session '" + input.session + "'";
  if (input.session.empty())
    throw DescriptorRefused("no session name", "robot '" + input.robot + "': a descriptor without a session name");
  if (!input.topic_robot.empty() && input.robot != input.topic_robot)
    throw DescriptorRefused("robot name", who + ": robot name '" + input.robot + "' on the topic of robot '" +
                                              input.topic_robot + "'; expected '" + input.topic_robot +
                                              "' (a detector names itself after its namespace)");
  if (input.config_hash != hash_)
    throw DescriptorRefused("configuration hash",
                            who + ": configuration hash " + hex(input.config_hash) + " differs from this server's " +
                                hex(hash_) + " (descriptor keys: " + config_.descriptor + ", patch " +
                                std::to_string(config_.patch_size) +
                                "...); the robot describes with another configuration");
  const size_t words = map_.layout().frameWords();
  if (input.descriptor.size() != words)
    throw DescriptorRefused("length", who + ": descriptor of " + std::to_string(input.descriptor.size() * 8) +
                                          " bytes; this server's configuration makes " + std::to_string(words * 8));
  const auto s = streams_.find(input.session);
  const bool started = s != streams_.end() && s->second.started;
  const double previous = started ? s->second.last_stamp : 0.0;
  if (started && s->second.has_frame_id && input.frame_id == s->second.last_frame_id && input.stamp == previous)
    throw DescriptorRefused("repeated message", who + ": frame " + std::to_string(input.frame_id) +
                                                    " again (the same message twice); expected each frame once");
  const InputProblem stamp = checkStamp(input.stamp, previous, started, true);
  if (!stamp.ok())
    throw DescriptorRefused(stamp.reason, who + ": " + stamp.what +
                                              (stamp.reason == "stamp went backwards"
                                                   ? " (a restarted robot must send a new session name)"
                                                   : ""));
  if (started && input.stamp == previous)
  {
    std::ostringstream what;
    what.precision(17);
    what << who << ": stamp " << input.stamp << " again (frame " << input.frame_id
         << "); expected stamps strictly increasing within a session";
    throw DescriptorRefused("stamp repeated", what.str());
  }
  if (started && s->second.has_frame_id && input.frame_id <= s->second.last_frame_id)
    throw DescriptorRefused("frame id went backwards",
                            who + ": frame id " + std::to_string(input.frame_id) + " is not after the previous " +
                                std::to_string(s->second.last_frame_id) + "; expected increasing frame ids");
  if (!input.has_pose)
    return input.pose;
  Pose pose = input.pose;
  const InputProblem problem = checkPose(pose);
  if (!problem.ok())
    throw DescriptorRefused(problem.reason, who + ": " + problem.what);
  return pose;
}

PlaceServer::Stream& PlaceServer::stream(const std::string& session)
{
  auto s = streams_.find(session);
  if (s == streams_.end())
  {
    // Full sequences only (loop-closure use): the partial chains at a stream's start were the main source
    // of false loops (MapMatcher).
    s = streams_.emplace(session, Stream{MapMatcher(matching_, map_.layout(), false), 0.0, false, false, 0}).first;
    // A session continued from a loaded map keeps its stamps in order too.
    const int index = map_.findSession(session);
    if (index >= 0 && !map_.frames(uint32_t(index)).empty())
    {
      const PlaceDatabase& frames = map_.frames(uint32_t(index));
      s->second.last_stamp = frames.stamp(frames.size() - 1);
      s->second.started = true;
    }
  }
  return s->second;
}

ServerCandidate PlaceServer::named(const Candidate& c) const
{
  ServerCandidate n;
  n.session = map_.session(c.session).name;
  n.id = c.id;
  n.distance = c.distance;
  n.direction = c.direction;
  n.shift = c.shift;
  n.sequence_length = c.sequence_length;
  const PlaceDatabase& frames = map_.frames(c.session);
  if (c.position < frames.size())
  {
    const FrameInfo info = frames.info(c.position);
    n.stamp = info.stamp;
    n.has_pose = info.has_pose;
    n.pose = info.pose;
  }
  return n;
}

ServerCandidates PlaceServer::process(const PlaceDescriptorInput& input)
{
  std::array<double, 7> pose;
  try
  {
    pose = check(input);
  }
  catch (const DescriptorRefused& e)
  {
    ++refused_[e.reason()];
    throw;
  }
  const bool owned = owns(input.session);
  int own = map_.findSession(input.session);
  if (owned && own < 0)
  {
    const size_t capacity = config_.max_history > 0 ? size_t(config_.max_history) : 0;
    own = int(map_.addSession(SessionInfo{input.session, input.robot, input.stamp}, capacity, 0));
  }
  Stream& s = stream(input.session);

  ServerCandidates out;
  out.server = name_;
  out.query_session = input.session;
  out.query_robot = input.robot;
  out.query_frame = input.frame_id;
  out.query_stamp = input.stamp;
  out.has_query_pose = input.has_pose;
  out.query_pose = pose;
  const Detection detection = s.matcher.match(input.descriptor, map_, own, input.stamp);
  out.candidates = detection.candidates;
  for (const Candidate& c : detection.top)
    out.top.push_back(named(c));
  out.other_frames = map_.frameCount();
  if (own >= 0)
  {
    const PlaceDatabase& frames = map_.frames(uint32_t(own));
    out.own_excluded = detection.own_excluded;  // MapMatcher's exclusion: frames exist, none outside it
    out.has_own_edge = detection.has_exclusion_edge;
    out.own_edge_id = detection.exclusion_edge_id;
    out.own_short_map = detection.short_map;
    out.own_first_id = frames.firstId();
    out.other_frames -= frames.size();
  }
  if (owned)
  {
    FrameInfo info;
    info.stamp = input.stamp;
    info.source = input.robot;
    info.has_pose = input.has_pose;
    info.pose = pose;
    out.query_id = map_.add(uint32_t(own), input.descriptor, info);
    out.stored = true;
  }
  s.last_stamp = input.stamp;
  s.started = true;
  s.has_frame_id = true;
  s.last_frame_id = input.frame_id;
  return out;
}

void PlaceServer::save(const std::string& path) const
{
  if (map_.frameCount() == 0)
    throw Error("the map holds no frame (" + std::to_string(map_.sessionCount()) + " sessions): nothing saved to '" +
                path + "' (the detectors refuse an empty map)");
  map_.save(path);
}

void PlaceServer::load(const std::string& path)
{
  SessionMap loaded = SessionMap::load(path);
  const Config theirs = Config::fromYamlString(loaded.configYaml());
  const MapMismatch mismatch = mapMismatch(config_, map_.layout(), theirs, loaded.layout(), "the map");
  if (!mismatch.keys.empty())
    throw Error("map '" + path + "' was described with another configuration: " + mismatch.keys);
  if (mismatch.layout)
    throw Error("map '" + path + "': its descriptor layout differs from this configuration's");
  map_ = std::move(loaded);
  streams_.clear();
}

}  // namespace openable
