#include "openable/node_support/refusal_log.h"

namespace openable
{
bool RefusalLog::note(const std::string& reason, double now, uint64_t& held_back)
{
  ++counts_[reason];
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

uint64_t RefusalLog::total() const
{
  uint64_t sum = 0;
  for (const auto& [reason, count] : counts_)
    sum += count;
  return sum;
}

}  // namespace openable
