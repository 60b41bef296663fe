#include "openable/node_support/fix_history.h"

#include <cmath>

namespace openable
{
void FixHistory::add(const openable::GeoPosition& fix)
{
  fixes_.push_back(fix);
  if (fixes_.size() > kCapacity)
    fixes_.pop_front();
}

bool FixHistory::nearest(double stamp, double tolerance, openable::GeoPosition& fix) const
{
  // A linear scan: at most kCapacity fixes, once per frame. Arrival order need not be stamp order (a
  // bag replayed with several publishers), so no binary search.
  bool found = false;
  double best = 0.0;
  for (const auto& f : fixes_)
  {
    const double gap = std::abs(f.stamp - stamp);
    if (gap <= tolerance && (!found || gap < best || (gap == best && f.stamp > fix.stamp)))
    {
      fix = f;
      best = gap;
      found = true;
    }
  }
  return found;
}

void FixHistory::clear()
{
  fixes_.clear();
}

}  // namespace openable
