#pragma once

#include "openable/config.h"
#include "openable/detection/loop_decision.h"

namespace openable_test
{
/// Whether the loop-acceptance gate that runs (LoopDecision) lets `detection` through under `config`'s
/// threshold and min_uniqueness alone: no minimum of candidates, no consistency run. A frame without
/// candidates never passes.
inline bool passesAcceptanceGate(openable::Config config, const openable::Detection& detection)
{
  config.min_candidates = 0;
  config.consistent_frames = 1;
  return openable::LoopDecision(config).decide(detection) == openable::FrameStatus::Published;
}

}  // namespace openable_test
