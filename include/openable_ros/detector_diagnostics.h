#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/time.h>

#include <cstdint>
#include <map>
#include <string>

#include "openable/detection/online_detector.h"
#include "openable/node_support/refusal_log.h"
#include "openable_ros/ros_parameters.h"

namespace openable_ros
{
/// What the detector counts for /diagnostics. Every input that reaches a callback is "received", whether
/// it is then rejected or not, so the input rate is the rate at which messages arrive.
struct FrameCounters
{
  uint64_t received = 0;
  uint64_t stored = 0;
  uint64_t skipped_keyframe = 0;
  uint64_t loops = 0;
  uint64_t dropped_by_synchroniser = 0;
  /// Messages that never reached a callback (subscriber or publisher queue full), from header.seq gaps
  /// (openable::SequenceGaps: what it can and cannot see). Not part of "received".
  uint64_t dropped_queue = 0;
  uint64_t fixes = 0;            ///< usable ~fix messages
  uint64_t frames_with_fix = 0;  ///< stored frames that took a fix (written to ~geo_file when set)
  /// Refused inputs: a count and a warning throttle per reason (counted and logged by Detector::refuse).
  openable::RefusalLog refusals;
  std::map<std::string, uint64_t> statuses;      ///< frames per decision status
  std::map<std::string, uint64_t> verification;  ///< verifier outcomes ("accepted", "identical images", ...)
  double describe_ms_last = 0.0, describe_ms_total = 0.0;
  double match_ms_last = 0.0, match_ms_total = 0.0;
  uint64_t timed = 0;

  void addTimes(const openable::StageTimes& times);
};

/// Fills one /diagnostics status from the counters and the detector's state. `received_before` and
/// `rejected_before` are the counts at the previous report (for the rates); `seconds` since then.
class DetectorDiagnostics
{
public:
  void fill(diagnostic_updater::DiagnosticStatusWrapper& status, const FrameCounters& counters,
            uint64_t matrix_published, const openable::OnlineDetector& detector, const RosParameters& parameters);

private:
  uint64_t received_at_last_ = 0;
  uint64_t rejected_at_last_ = 0;
  uint64_t dropped_at_last_ = 0;
  ros::WallTime last_ = ros::WallTime::now();
};

}  // namespace openable_ros
