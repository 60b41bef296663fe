#pragma once

#include <deque>

#include "openable/geo_position.h"

namespace openable
{
/// The recent GNSS fixes of ~fix, to give each frame the fix nearest to its stamp.
///
/// Fixes and images come on separate topics at their own rates (GNSS at 1-10 Hz, cameras faster), and
/// neither waits for the other: a frame takes the nearest fix received so far, if it is within
/// `tolerance` seconds of the frame's stamp; otherwise the frame has no geographic position (a frame
/// long after the receiver lost its fix must not inherit an old one). ROS-free, so it is tested without a
/// master.
class FixHistory
{
public:
  /// Fixes kept: far more than the frames between two fixes at any tolerance that makes sense.
  static constexpr size_t kCapacity = 256;

  void add(const openable::GeoPosition& fix);
  /// The fix nearest to `stamp` within `tolerance` seconds (inclusive); false when there is none.
  bool nearest(double stamp, double tolerance, openable::GeoPosition& fix) const;
  void clear();

private:
  std::deque<openable::GeoPosition> fixes_;  ///< in arrival order
};

}  // namespace openable
