#pragma once

#include <cstdint>
#include <vector>

#include "openable/config.h"
#include "openable/detection/loop_decision.h"
#include "openable/map/session_map.h"

namespace openable
{
/// A loop closure between two frames of a map.
struct MapLoop
{
  uint32_t query_session = 0;
  uint64_t query_id = 0;
  uint32_t match_session = 0;
  uint64_t match_id = 0;
  float distance = 0.0f;
  float score = 0.0f;
};

/// The loop closures between the frames of a map, as continuing it session after session would publish
/// them: each session, in map order, matched against the sessions before it and its own past with
/// `config` (the map's own configuration, usually), decided by LoopDecision and confirmed by LoopConfirmation
/// (a session's last pending loops are dropped, as at the end of its run). Needs no image: the map holds
/// the descriptors. Geometric verification, which needs images, is not replayed.
std::vector<MapLoop> replayLoops(const SessionMap& map, const Config& config);

}  // namespace openable
