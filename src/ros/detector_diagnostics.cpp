#include "openable_ros/detector_diagnostics.h"

#include <algorithm>

namespace openable_ros
{
void FrameCounters::addTimes(const openable::StageTimes& times)
{
  describe_ms_last = times.preprocess_ms + times.describe_ms;
  match_ms_last = times.match_ms;
  describe_ms_total += describe_ms_last;
  match_ms_total += match_ms_last;
  ++timed;
}

void DetectorDiagnostics::fill(diagnostic_updater::DiagnosticStatusWrapper& status, const FrameCounters& counters,
                               uint64_t matrix_published, const openable::OnlineDetector& detector,
                               const RosParameters& parameters)
{
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = std::max(1e-6, (now - last_).toSec());
  const double rate = double(counters.received - received_at_last_) / elapsed;
  const uint64_t rejected_total = counters.refusals.total();
  const uint64_t rejected_recently = rejected_total - rejected_at_last_;
  const uint64_t dropped_recently = counters.dropped_queue - dropped_at_last_;
  dropped_at_last_ = counters.dropped_queue;
  received_at_last_ = counters.received;
  rejected_at_last_ = rejected_total;
  last_ = now;

  const bool localising = detector.localisationMode();
  if (rejected_recently > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%lu input frames rejected since the last report",
                    static_cast<unsigned long>(rejected_recently));
  else if (dropped_recently > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "%lu input frames dropped in a queue since the last report (raise ~queue_size, or the "
                    "detector is slower than the input)",
                    static_cast<unsigned long>(dropped_recently));
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, localising ? "localising" : "running");
  status.add("mode",
             localising ? "localisation (query stream vs loaded map)" : "loop closure (stream vs its own history)");
  status.add("input rate (Hz)", rate);
  status.add("frames received", counters.received);
  status.add("frames stored", counters.stored);
  status.add("frames skipped (not a keyframe)", counters.skipped_keyframe);
  status.add("frames rejected", rejected_total);
  for (const auto& r : counters.refusals.counts())
    status.add("rejected: " + r.first, r.second);
  status.add("frames dropped by the synchroniser", counters.dropped_by_synchroniser);
  // Gaps in the inputs' header.seq: messages published that never reached a callback (a full queue).
  status.add("frames dropped (queue)", counters.dropped_queue);
  // What is in force (dynamic_reconfigure may have changed it).
  const openable::Config& config = detector.config();
  status.add("threshold", config.threshold);
  status.add("sequence length", config.sequence_length);
  status.add("exclusion window", config.exclusion_window);
  status.add("min uniqueness", config.min_uniqueness);
  status.add("history size", detector.loopDetector().map().frameCount());
  status.add("history bytes", detector.loopDetector().map().bytes());
  const double timed = double(std::max<uint64_t>(1, counters.timed));
  status.add("describe latency last (ms)", counters.describe_ms_last);
  status.add("describe latency mean (ms)", counters.describe_ms_total / timed);
  status.add("match latency last (ms)", counters.match_ms_last);
  status.add("match latency mean (ms)", counters.match_ms_total / timed);
  status.add("loop closures", counters.loops);
  if (counters.fixes > 0)
  {
    status.add("fixes received", counters.fixes);
    status.add("frames with a fix", counters.frames_with_fix);
  }
  status.add("distance_matrix images published", matrix_published);
  if (parameters.verify)
    status.add("verification", detector.hasVerifier() ? "on" : "waiting for camera_info");
  for (const auto& v : counters.verification)
    status.add("verification: " + v.first, v.second);
  for (const auto& s : counters.statuses)
    status.add("frames " + s.first, s.second);
}

}  // namespace openable_ros
