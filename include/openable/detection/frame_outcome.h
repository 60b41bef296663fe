#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "openable/detection/loop_decision.h"
#include "openable/map/place_database.h"
#include "openable/verification/geometric_verifier.h"

namespace openable
{
/// Wall time of each stage of one frame (milliseconds).
struct StageTimes
{
  double preprocess_ms = 0.0;
  double describe_ms = 0.0;
  double match_ms = 0.0;   ///< match
  double verify_ms = 0.0;  ///< decide, with the verification (and its features) the decision needs
};

/// The outcome of one frame (OnlineDetector::process).
struct FrameOutcome
{
  FrameStatus status = FrameStatus::TooEarly;
  uint64_t frame = 0;   ///< the input's number: frames the detector was given before it (every status counts)
  bool stored = false;  ///< added to the history (loop-closure mode) / matched (localisation)
  FrameInfo query;      ///< the frame as stored (its id and session are set)
  Detection detection;  ///< candidates, uniqueness, ...
  float score = 0.0f;   ///< decision score, higher = surer (LoopDecision::score)
  bool has_match_info = false;
  FrameInfo match;        ///< the best match's stored info (with its session), when it is still in the map
  bool verified = false;  ///< `verification` holds an accepted relative pose
  bool verification_ran = false;  ///< `verification` is the best match's (accepted or not)
  Verification verification;
  std::string verification_note;  ///< why verification did not run or failed (empty when verified)
  StageTimes times;
  /// Loop closures of earlier frames that this frame confirmed (confirm_frames): each is an earlier frame's
  /// outcome, now Published, with its own `frame`, stamp and source. A caller publishes these, in order, besides
  /// this frame's own outcome when that is published (confirm_frames 0).
  std::vector<FrameOutcome> confirmed;
  /// In `confirmed`: the status it had before (Pending, or, for one of its run's first frames published after the
  /// fact, Inconsistent or Standstill; with two channels, the status the frame was reported with when the other
  /// channel's decision was reported), so a caller that counts statuses moves it from there.
  FrameStatus status_before = FrameStatus::Pending;
  /// The decision (and loop closure) is the view channel's (Config::view_channel_shift), not the whole image's.
  bool view_channel = false;

  bool published() const
  {
    return status == FrameStatus::Published;
  }
};

}  // namespace openable
