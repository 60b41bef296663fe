#include "openable/loop_decision.h"

#include <cstdlib>

namespace openable
{
const char* toString(FrameStatus status)
{
  switch (status)
  {
    case FrameStatus::Published:
      return "published";
    case FrameStatus::NotKeyframe:
      return "not_keyframe";
    case FrameStatus::TimeJump:
      return "time_jump";
    case FrameStatus::TooEarly:
      return "too_early";
    case FrameStatus::Excluded:
      return "excluded";
    case FrameStatus::AboveThreshold:
      return "above_threshold";
    case FrameStatus::NotUnique:
      return "not_unique";
    case FrameStatus::Inconsistent:
      return "inconsistent";
    case FrameStatus::FailedVerification:
      return "failed_verification";
    case FrameStatus::Unverified:
      return "unverified";
  }
  return "unknown";
}

LoopDecision::LoopDecision(const Config& config) : config_(config) {}

void LoopDecision::setConfig(const Config& config)
{
  config_ = config;
  reset();
}

void LoopDecision::reset()
{
  run_ = 0;
}

float LoopDecision::score(const Detection& detection) const
{
  const bool meaningful =
      detection.has_candidates && detection.candidates >= static_cast<size_t>(config_.min_candidates);
  return meaningful ? detection.uniqueness : 0.0f;
}

bool LoopDecision::gatesPass(const Detection& detection, FrameStatus& why) const
{
  if (config_.threshold >= 0.0 && detection.best.distance > config_.threshold)
  {
    why = FrameStatus::AboveThreshold;
    return false;
  }
  // With neither gate set nothing is a loop: the best match of a frame always exists, a loop does not.
  const bool gated = config_.threshold >= 0.0 || config_.min_uniqueness > 0.0;
  if (!gated || detection.uniqueness < config_.min_uniqueness)
  {
    why = FrameStatus::NotUnique;
    return false;
  }
  return true;
}

bool LoopDecision::advancesWithRun(const Detection& detection) const
{
  // A run follows one route: a match in another session starts a new run.
  if (run_ == 0 || detection.best.direction != previous_direction_ || detection.best.session != previous_session_)
    return false;
  // Same direction: the match moves one place forward per frame; reverse: one place back. Checked per
  // step and over the whole run, so a match that stays put (a "hub" place every frame matches) never
  // becomes consistent by small steps.
  const auto offset = [&detection](uint64_t from, long frames)
  {
    return std::labs(static_cast<long>(detection.best.id) - static_cast<long>(from) -
                     detection.best.direction * frames);
  };
  return offset(previous_match_, 1) <= config_.consistency_tolerance &&
         offset(run_start_match_, run_) <= config_.consistency_tolerance;
}

FrameStatus LoopDecision::decide(const Detection& detection)
{
  FrameStatus status = FrameStatus::Published;
  if (!detection.has_candidates)
    status = detection.excluded ? FrameStatus::Excluded : FrameStatus::TooEarly;
  else if (detection.candidates < static_cast<size_t>(config_.min_candidates))
    status = FrameStatus::TooEarly;
  else if (!gatesPass(detection, status))
  {
  }
  else
  {
    if (advancesWithRun(detection))
      ++run_;
    else
    {
      run_ = 1;
      run_start_match_ = detection.best.id;
    }
    previous_match_ = detection.best.id;
    previous_direction_ = detection.best.direction;
    previous_session_ = detection.best.session;
    return run_ >= config_.consistent_frames ? FrameStatus::Published : FrameStatus::Inconsistent;
  }
  reset();
  return status;
}

}  // namespace openable
