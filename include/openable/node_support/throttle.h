#pragma once

#include <map>
#include <string>

namespace openable
{
/// "At most once per period per key": the rule behind throttled warnings. The caller passes the time, so
/// it works on wall time, ROS time or a test's clock, and several detectors never silence each other
/// (a member, not a function-local static).
class Throttle
{
public:
  /// True (and remembers `now`) when `key` was never let through or at least `period` seconds ago.
  bool ready(const std::string& key, double now, double period);

private:
  std::map<std::string, double> last_;
};

}  // namespace openable
