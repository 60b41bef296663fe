#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/description/input_contract.h"
#include "openable/detection/map_matcher.h"
#include "openable/map/session_map.h"

namespace openable
{
/// One frame's signature as a robot sends it over a network (openable_ros/PlaceDescriptor): no image.
struct PlaceDescriptorInput
{
  std::string robot;    ///< who sent it (for warnings and the session table)
  /// The robot the message's topic belongs to (robotOfTopic), when the caller knows it: a message whose
  /// `robot` differs is refused. Empty: not checked.
  std::string topic_robot;
  std::string session;  ///< the stream it belongs to: one per robot run ("robot1", "robot1/2026-11-22")
  uint64_t frame_id = 0;     ///< the robot's own id of the frame: strictly increasing within a session
  double stamp = 0.0;        ///< seconds, finite and > 0; strictly increasing within a session
  uint64_t config_hash = 0;  ///< descriptorHash() of the configuration the robot described with
  FrameDescriptor descriptor;
  bool has_pose = false;
  std::array<double, 7> pose{{0, 0, 0, 0, 0, 0, 1}};  ///< x y z qx qy qz qw (finite, unit quaternion)
};

/// A descriptor the server will not use, and why. Nothing was stored or matched. `reason` is a short key
/// for counting ("configuration hash", "length", "no session name", "robot name", the stamp reasons of
/// checkStamp, "stamp repeated", "repeated message", "frame id went backwards", the pose reasons of
/// checkPose); `what` names the robot, the value and what was expected.
class DescriptorRefused : public InputRefused
{
public:
  using InputRefused::InputRefused;
};

/// The robot a place_descriptors topic belongs to, as a detector in that namespace names itself by default:
/// "/robot1" and "/robot1/place_descriptors" -> "robot1", "/fleet/r2" -> "fleet_r2".
std::string robotOfTopic(const std::string& topic);

/// One matched place, named so that it means the same on every server: session name and the id of the
/// frame within that session (every server numbers a session's frames from 0).
struct ServerCandidate
{
  std::string session;
  uint64_t id = 0;
  float distance = 1.0f;
  int8_t direction = 1;
  int16_t shift = 0;
  uint16_t sequence_length = 0;
  double stamp = 0.0;
  bool has_pose = false;
  std::array<double, 7> pose{{0, 0, 0, 0, 0, 0, 1}};
};

/// What one server found for one query frame: its best places over the sessions it holds (at least two,
/// so that a merger can find the global second best), how many places it compared, and what a merger
/// needs to tell "too early" from "excluded".
struct ServerCandidates
{
  std::string server;         ///< the server's name
  std::string query_session;  ///< the query's session name
  std::string query_robot;
  uint64_t query_frame = 0;   ///< the robot's frame id
  double query_stamp = 0.0;
  bool has_query_pose = false;
  std::array<double, 7> query_pose{{0, 0, 0, 0, 0, 0, 1}};
  bool stored = false;        ///< this server owns the query's session and stored the frame as query_id
  uint64_t query_id = 0;      ///< id within the session (valid when stored)
  size_t candidates = 0;      ///< places compared with a sequence long enough to be a candidate
  /// best first, up to max(top_k, 2) distinct places; with `candidates` 0, a short map's early places
  /// (MapMatcher::earlyPicks), which the merger keeps only where no server counts a candidate
  std::vector<ServerCandidate> top;
  bool own_excluded = false;  ///< the query's own past is here but all of it inside the exclusion
  /// The exclusion cut the query's own past here: own_edge_id is the newest of its places compared (a match
  /// there starts no run, LoopDecision).
  bool has_own_edge = false;
  uint64_t own_edge_id = 0;
  /// The query's own past here was matched with the short map's window (Detection::short_map); own_first_id is its
  /// first place (a match there starts no run, Detection::best_at_session_start).
  bool own_short_map = false;
  uint64_t own_first_id = 0;
  size_t other_frames = 0;    ///< frames held here in sessions other than the query's
};

/// Closes loops between robots: one SessionMap with a session per incoming stream, one MapMatcher (query
/// state) per stream, so frames of several robots may arrive interleaved. Each frame is matched against the
/// other sessions it holds and its own session's past (the exclusion window applies there only), then
/// stored when this server owns its session (`owned` empty = every session). Several servers can split the
/// sessions between them; CandidateMerger combines their answers into what one server would decide.
/// Not thread-safe: callers serialise.
class PlaceServer
{
public:
  /// Throws Error when the configuration is invalid.
  PlaceServer(const Config& config, std::vector<std::string> owned = {}, std::string name = "place_server");

  /// Validates, matches, stores (if owned) and returns the candidates. Throws DescriptorRefused (nothing
  /// changes) for a wrong configuration hash or length, an empty session name, a robot name that is not its
  /// topic's, a stamp that is not finite, 0, or not after the previous one of the same session, a frame id
  /// not after the previous one (the same message twice: "repeated message"), or a pose that is not finite
  /// or whose quaternion is not a unit one (a near-unit one is normalised). A session never restarts: a
  /// robot whose stamps start over (a restart, a bag played in a loop) must send a new session name.
  ServerCandidates process(const PlaceDescriptorInput& input);

  /// True when this server stores the frames of `session`.
  bool owns(const std::string& session) const;
  const Config& config() const
  {
    return config_;
  }
  uint64_t configHash() const
  {
    return hash_;
  }
  const std::string& name() const
  {
    return name_;
  }
  const SessionMap& map() const
  {
    return map_;
  }
  /// Frames refused so far, by reason.
  const std::map<std::string, size_t>& refused() const
  {
    return refused_;
  }

  /// Saves every session (SessionMap format). Throws Error, also for a map without any frame (the detectors
  /// refuse an empty map: it is not written).
  void save(const std::string& path) const;
  /// Replaces the map with a saved one described with the same configuration (else Error naming the keys
  /// that differ; the map in memory is kept). Query streams restart.
  void load(const std::string& path);

private:
  struct Stream
  {
    MapMatcher matcher;
    double last_stamp = 0.0;
    bool started = false;
    bool has_frame_id = false;  ///< false for a session continued from a loaded map (ids unknown)
    uint64_t last_frame_id = 0;
  };
  /// Throws DescriptorRefused; returns the pose to store (normalised).
  std::array<double, 7> check(const PlaceDescriptorInput& input) const;
  Stream& stream(const std::string& session);
  ServerCandidate named(const Candidate& c) const;

  Config config_;
  Config matching_;  ///< config_ with top_k >= 2: a merger needs every server's second best
  std::vector<std::string> owned_;
  std::string name_;
  uint64_t hash_;
  SessionMap map_;
  std::map<std::string, Stream> streams_;
  std::map<std::string, size_t> refused_;
};

}  // namespace openable
