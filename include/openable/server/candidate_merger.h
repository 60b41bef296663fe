#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/detection/loop_confirmation.h"
#include "openable/detection/loop_decision.h"
#include "openable/server/place_server.h"

namespace openable
{
/// One query decided over the answers of every server.
struct MergedOutcome
{
  std::string query_session;
  std::string query_robot;
  uint64_t query_frame = 0;  ///< the robot's frame id
  double query_stamp = 0.0;
  bool has_query_pose = false;
  std::array<double, 7> query_pose{{0, 0, 0, 0, 0, 0, 1}};
  bool query_stored = false;  ///< some server owns the query's session and stored it as query_id
  uint64_t query_id = 0;
  /// The merged detection; Candidate::session is the merger's index of the session (sessionName()),
  /// Candidate::position is not meaningful (the place lives on another server).
  Detection detection;
  std::vector<ServerCandidate> top;  ///< the same places, named; up to top_k, best first
  FrameStatus status = FrameStatus::TooEarly;
  float score = 0.0f;
  size_t servers = 0;  ///< answers merged
  /// Earlier queries of the same stream that this one confirmed (confirm_frames), now Published: publish
  /// these, each with its own query stamp, besides this query when it is published itself (confirm_frames 0).
  std::vector<MergedOutcome> confirmed;
  FrameStatus status_before = FrameStatus::Pending;  ///< in `confirmed`: as FrameOutcome::status_before

  bool published() const
  {
    return status == FrameStatus::Published;
  }
};

/// Combines what several PlaceServers found for the same query into what one server holding all their
/// sessions would have found, then decides with one LoopDecision and one LoopConfirmation per query stream
/// (a loop closure is published once confirm_frames more queries of its stream go on with its run).
///
/// Why this is exact: every session lives on one server, and MapMatcher picks a session's distinct places
/// without looking at other sessions, so the global best places are the union of each server's best,
/// sorted by distance; the second best (uniqueness) is the second of that union, and the count of compared
/// places is the sum. Each server sends at least two places for that reason. Equal distances in different
/// sessions are ordered by server name here, by session order on one server: only then can the best place
/// named differ (never its distance, the uniqueness or the decision's gates).
class CandidateMerger
{
public:
  explicit CandidateMerger(const Config& config);

  /// Decides one query from the answers of every server that saw it (in any order; at least one, all for
  /// the same query session and frame, else Error).
  MergedOutcome merge(std::vector<ServerCandidates> answers);

  /// A stable index for a session name: the first name seen is 0, and so on (LoopClosure's sessions).
  uint32_t sessionIndex(const std::string& name);
  const std::vector<std::string>& sessionNames() const
  {
    return names_;
  }
  const Config& config() const
  {
    return config_;
  }

private:
  Config config_;
  std::vector<std::string> names_;
  std::map<std::string, uint32_t> indices_;
  /// What decides a query stream's loops: a run never mixes robots.
  struct StreamDecision
  {
    LoopDecision decision;
    BasicLoopConfirmation<MergedOutcome> confirmation;
  };
  std::map<std::string, StreamDecision> streams_;  ///< by query session
};

}  // namespace openable
