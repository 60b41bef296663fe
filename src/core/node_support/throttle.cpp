#include "openable/node_support/throttle.h"

namespace openable
{
bool Throttle::ready(const std::string& key, double now, double period)
{
  const auto it = last_.find(key);
  if (it != last_.end() && now - it->second < period)
    return false;
  last_[key] = now;
  return true;
}

}  // namespace openable
