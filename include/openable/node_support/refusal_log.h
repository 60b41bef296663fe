#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "openable/node_support/throttle.h"

namespace openable
{
/// The inputs a node refused, by reason (InputRefused::reason(), InputProblem::reason, or a reason of the
/// node's own: "unsupported encoding", "left/right mismatch"...). Each reason has its own count (one
/// diagnostics entry per reason) and its own warning throttle: a burst of one kind never hides the first
/// warning of another, and a reason that keeps coming back is warned again once per period with the number
/// it held back. The caller passes the time (wall time, ROS time or a test's clock). Not thread-safe.
class RefusalLog
{
public:
  /// `period`: seconds between two warnings of one reason.
  explicit RefusalLog(double period = 5.0) : period_(period) {}

  /// Counts one refusal of `reason` at `now`. True when its warning is to be logged now: the first of this
  /// reason, or the first `period` seconds after the last one logged; `held_back` is then set to how many of
  /// this reason were counted but not logged since that one.
  bool note(const std::string& reason, double now, uint64_t& held_back);

  /// Refusals so far, by reason.
  const std::map<std::string, uint64_t>& counts() const
  {
    return counts_;
  }
  /// Refusals so far, all reasons (the sum of counts(); a handful of reasons, read once per diagnostics update).
  uint64_t total() const;

private:
  double period_;
  Throttle throttle_;
  std::map<std::string, uint64_t> counts_;
  std::map<std::string, uint64_t> held_back_;
};

}  // namespace openable
