#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/map/place_database.h"

namespace openable
{
/// One traversal in a map: a run of one robot (or camera), recorded at one time.
struct SessionInfo
{
  std::string name;          ///< unique within a map ("day_right", "robot1/2026-11-22")
  std::string robot;         ///< robot or camera that recorded it; may be empty
  double start_stamp = 0.0;  ///< stamp of its first frame (0 = unknown or none yet)
};

/// A life-long map: several sessions, each its own PlaceDatabase, all described with one configuration.
///
/// Sessions are kept apart, not interleaved in one store, because a sequence never spans two sessions: the
/// frame after a session's last one is not the next place of that route. Each session's frames have
/// consecutive ids; a new session's ids continue after the highest id in the map (nextId()), so ids stay
/// unique across a map that grows one session after another (openable_offline --map-in, merge).
/// Robots that record at the same time (PlaceServer) give each session its own ids; (session, id) is
/// always unique.
class SessionMap
{
public:
  /// config_yaml is the configuration every session was described with (Config::toYaml()).
  SessionMap(const DescriptorLayout& layout, std::string config_yaml);
  /// A map of one session holding `frames` (its configuration and layout become the map's).
  SessionMap(PlaceDatabase frames, SessionInfo info);

  const DescriptorLayout& layout() const
  {
    return layout_;
  }
  const std::string& configYaml() const
  {
    return config_yaml_;
  }

  /// Adds an empty session. capacity 0 = unbounded (else the oldest frames of this session leave first).
  /// Throws Error when the name is empty or already in the map. Returns the session's index.
  uint32_t addSession(SessionInfo info, size_t capacity = 0);
  /// The same, with the session's ids starting at `first_id` instead of nextId(): a PlaceServer numbers
  /// each robot's frames from 0, so that servers holding different sessions name a frame alike.
  uint32_t addSession(SessionInfo info, size_t capacity, uint64_t first_id);
  /// Index of the session called `name`, or -1.
  int findSession(const std::string& name) const;
  size_t sessionCount() const
  {
    return sessions_.size();
  }
  const SessionInfo& session(uint32_t index) const
  {
    return sessions_.at(index);
  }
  const PlaceDatabase& frames(uint32_t index) const
  {
    return frames_.at(index);
  }

  /// Stores a frame in `session` (info.session is set to it; the first frame's stamp becomes the
  /// session's start stamp). Returns the frame's id.
  uint64_t add(uint32_t session, const FrameDescriptor& descriptor, FrameInfo info = FrameInfo());
  /// Forgets the frames of one session (ids go on from where they were).
  void clearSession(uint32_t session);

  /// Frames in every session.
  size_t frameCount() const;
  /// One more than the highest id in the map (0 for an empty map).
  uint64_t nextId() const;
  /// Bytes held by every session's descriptors and metadata.
  size_t bytes() const;
  /// Releases the room kept for frames not added yet (a map that no longer grows).
  void shrinkToFit();

  /// Versioned binary file (format 3: every session's table entry, metadata and descriptors, one checksum),
  /// written atomically. Throws Error.
  void save(const std::string& path) const;
  /// Reads format 3 and the single-session formats 1 and 2 (one session called "session 0"). Throws Error
  /// naming what is wrong.
  static SessionMap load(const std::string& path);

  /// `into` followed by every session of `from`, renumbered so that ids stay unique (as if `from`'s
  /// sessions had been recorded after `into`'s). Refuses, naming the keys and values, maps described with
  /// different configurations, and a session name found in both.
  static SessionMap merge(SessionMap into, const SessionMap& from);

private:
  DescriptorLayout layout_;
  std::string config_yaml_;
  std::vector<SessionInfo> sessions_;
  std::vector<PlaceDatabase> frames_;
};

/// The descriptor keys (Config::descriptorKeys) on which two configurations differ, as
/// "key 'a' (<b_name> 'b'), ..."; empty when maps described with them can be compared.
std::string descriptorDifferences(const Config& a, const Config& b, const std::string& b_name = "other");

/// Why descriptors of one map (or configuration) cannot be compared with another's. The one map compatibility
/// check, used wherever a map meets another configuration or map: a detector loading a reference map, a
/// PlaceServer loading a map, two maps merged. Each caller words its refusal.
struct MapMismatch
{
  std::string keys;     ///< descriptorDifferences(a, b, b_name): empty when the descriptor keys agree
  bool layout = false;  ///< the descriptor layouts differ

  bool any() const
  {
    return !keys.empty() || layout;
  }
};
MapMismatch mapMismatch(const Config& a, const DescriptorLayout& a_layout, const Config& b,
                        const DescriptorLayout& b_layout, const std::string& b_name = "other");

/// A 64-bit fingerprint of the descriptor keys' values (FNV-1a of "key=value\n" in Config::descriptorKeys()
/// order): equal for configurations whose descriptors can be compared, the same on every machine. Sent
/// with descriptors over a network, so a receiver can refuse ones described otherwise.
uint64_t descriptorHash(const Config& config);

}  // namespace openable
