#pragma once

namespace openable
{
/// Where the parabola through three equally spaced values has its minimum, in steps from the middle one (+ towards
/// `after`): the sub-sample position of a minimum found on a grid. 0 when the three have no minimum between them
/// (the middle one not below the mean of its neighbours).
inline double parabolaMinimum(double before, double at, double after)
{
  const double curvature = before - 2.0 * at + after;
  return curvature > 0.0 ? 0.5 * (before - after) / curvature : 0.0;
}
}  // namespace openable
