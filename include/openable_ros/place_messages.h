#pragma once

#include <std_msgs/Header.h>

#include "openable/server/candidate_merger.h"
#include "openable/server/place_server.h"
#include "openable_ros/LoopClosure.h"
#include "openable_ros/PlaceCandidates.h"
#include "openable_ros/PlaceDescriptor.h"

namespace openable_ros
{
/// The multi-robot messages <-> the core's types (PlaceServer, CandidateMerger).
openable::PlaceDescriptorInput toInput(const PlaceDescriptor& msg);
PlaceCandidatesPtr toMsg(const std_msgs::Header& header, const openable::ServerCandidates& answer);
openable::ServerCandidates fromMsg(const PlaceCandidates& msg);

/// A merged decision as a LoopClosure: header of the query descriptor; query_id / match_id are ids within
/// their sessions (the robot's frame id when no server stored the query); query_session / match_session
/// are the merger's indices, query_session_name / match_session_name the names.
LoopClosurePtr makeLoopClosure(const std_msgs::Header& header, const openable::MergedOutcome& outcome,
                               openable::CandidateMerger& merger);

}  // namespace openable_ros
