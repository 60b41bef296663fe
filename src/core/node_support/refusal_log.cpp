#include "openable/node_support/refusal_log.h"

namespace openable
{
bool RefusalLog::note(const std::string& reason, double now, uint64_t& held_back)
{
  ++counts_[reason];
  ++total_;
  uint64_t& waiting = held_back_[reason];
  if (!throttle_.ready(reason, now, period_))
  {
    ++waiting;
    held_back = 0;
    return false;
  }
  held_back = waiting;
  waiting = 0;
  return true;
}

}  // namespace openable
