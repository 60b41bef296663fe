#include "openable/map/session_map.h"

#include <algorithm>

#include "map/map_file.h"
#include "openable/error.h"

namespace openable
{
SessionMap::SessionMap(const DescriptorLayout& layout, std::string config_yaml)
  : layout_(layout), config_yaml_(std::move(config_yaml))
{
  const std::string problem = layout.check();
  if (!problem.empty())
    throw Error("SessionMap: unsupported descriptor " + problem);
}

SessionMap::SessionMap(PlaceDatabase frames, SessionInfo info) : SessionMap(frames.layout(), frames.configYaml())
{
  if (info.name.empty())
    throw Error("a session needs a name");
  if (info.start_stamp == 0.0 && !frames.empty())
    info.start_stamp = frames.stamp(0);
  sessions_.push_back(std::move(info));
  frames_.push_back(std::move(frames));
}

uint32_t SessionMap::addSession(SessionInfo info, size_t capacity)
{
  return addSession(std::move(info), capacity, nextId());
}

uint32_t SessionMap::addSession(SessionInfo info, size_t capacity, uint64_t first_id)
{
  if (info.name.empty())
    throw Error("a session needs a name");
  if (findSession(info.name) >= 0)
    throw Error("session name '" + info.name + "' is already in the map (" + std::to_string(sessions_.size()) +
                " sessions); expected a new name");
  PlaceDatabase frames(layout_, capacity, config_yaml_);
  frames.renumber(first_id);
  sessions_.push_back(std::move(info));
  frames_.push_back(std::move(frames));
  return static_cast<uint32_t>(sessions_.size() - 1);
}

int SessionMap::findSession(const std::string& name) const
{
  for (size_t s = 0; s < sessions_.size(); ++s)
    if (sessions_[s].name == name)
      return static_cast<int>(s);
  return -1;
}

uint64_t SessionMap::add(uint32_t session, const FrameDescriptor& descriptor, FrameInfo info)
{
  PlaceDatabase& frames = frames_.at(session);
  info.session = session;
  if (frames.empty() && sessions_[session].start_stamp == 0.0)
    sessions_[session].start_stamp = info.stamp;
  return frames.add(descriptor, std::move(info));
}

void SessionMap::clearSession(uint32_t session)
{
  frames_.at(session).clear();
}

size_t SessionMap::frameCount() const
{
  size_t count = 0;
  for (const PlaceDatabase& frames : frames_)
    count += frames.size();
  return count;
}

uint64_t SessionMap::nextId() const
{
  uint64_t next = 0;
  for (const PlaceDatabase& frames : frames_)
    next = std::max<uint64_t>(next, frames.firstId() + frames.size());
  return next;
}

size_t SessionMap::bytes() const
{
  size_t bytes = 0;
  for (const PlaceDatabase& frames : frames_)
    bytes += frames.bytes();
  return bytes;
}

void SessionMap::shrinkToFit()
{
  for (PlaceDatabase& frames : frames_)
    frames.shrinkToFit();
}

void SessionMap::save(const std::string& path) const
{
  std::vector<map_file::SessionView> views;
  for (size_t s = 0; s < sessions_.size(); ++s)
    views.push_back({&sessions_[s], &frames_[s]});
  map_file::write(path, layout_, config_yaml_, views);
}

SessionMap SessionMap::load(const std::string& path)
{
  map_file::Contents contents = map_file::read(path);
  SessionMap map(contents.layout, std::move(contents.config_yaml));
  map.sessions_ = std::move(contents.sessions);
  map.frames_ = std::move(contents.frames);
  return map;
}

std::string descriptorDifferences(const Config& a, const Config& b, const std::string& b_name)
{
  std::string differences;
  for (const auto& key : Config::descriptorKeys())
    if (a.get(key) != b.get(key))
      differences += (differences.empty() ? "" : ", ") + key + " '" + a.get(key) + "' (" + b_name + " '" + b.get(key) + "')";
  return differences;
}

MapMismatch mapMismatch(const Config& a, const DescriptorLayout& a_layout, const Config& b,
                        const DescriptorLayout& b_layout, const std::string& b_name)
{
  MapMismatch mismatch;
  mismatch.keys = descriptorDifferences(a, b, b_name);
  mismatch.layout = a_layout != b_layout;
  return mismatch;
}

uint64_t descriptorHash(const Config& config)
{
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (const auto& key : Config::descriptorKeys())
    for (char c : key + "=" + config.get(key) + "\n")
    {
      hash ^= static_cast<uint8_t>(c);
      hash *= 0x100000001b3ULL;
    }
  return hash;
}

SessionMap SessionMap::merge(SessionMap into, const SessionMap& from)
{
  // The same text describes the same way: parsed only when the texts differ.
  const bool same_text = into.config_yaml_ == from.config_yaml_;
  const MapMismatch mismatch = mapMismatch(same_text ? Config() : Config::fromYamlString(into.config_yaml_),
                                           into.layout_,
                                           same_text ? Config() : Config::fromYamlString(from.config_yaml_),
                                           from.layout_);
  if (!mismatch.keys.empty())
    throw Error("cannot merge maps described with different configurations: " + mismatch.keys);
  if (mismatch.layout)
    throw Error("cannot merge maps whose descriptor layouts differ");
  for (const SessionInfo& session : from.sessions_)
    if (into.findSession(session.name) >= 0)
      throw Error("cannot merge: session name '" + session.name +
                  "' is in both maps; expected every session name once");
  // Renumbered in one block: the sessions keep their order and their distance in ids.
  uint64_t from_first = UINT64_MAX;
  for (const PlaceDatabase& frames : from.frames_)
    from_first = std::min<uint64_t>(from_first, frames.firstId());
  const uint64_t shift = into.nextId();
  for (size_t s = 0; s < from.sessions_.size(); ++s)
  {
    const uint32_t index = static_cast<uint32_t>(into.sessions_.size());
    PlaceDatabase frames(into.layout_, from.frames_[s].capacity(), into.config_yaml_);
    frames.renumber(shift + from.frames_[s].firstId() - from_first);
    frames.reserve(from.frames_[s].size());
    const size_t words = into.layout_.frameWords();
    for (size_t i = 0; i < from.frames_[s].size(); ++i)
    {
      FrameInfo info = from.frames_[s].info(i);
      info.session = index;
      frames.add(from.frames_[s].descriptor(i), words, std::move(info));
    }
    into.sessions_.push_back(from.sessions_[s]);
    into.frames_.push_back(std::move(frames));
  }
  return into;
}

}  // namespace openable
