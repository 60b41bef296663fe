#include "openable/description/input_contract.h"

#include <cmath>
#include <sstream>

namespace openable
{
namespace
{
std::string number(double value)
{
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}
}  // namespace

InputProblem checkPose(Pose& pose)
{
  static const char* const kNames[7] = {"x", "y", "z", "qx", "qy", "qz", "qw"};
  for (int i = 0; i < 7; ++i)
    if (!std::isfinite(pose[size_t(i)]))
      return {"pose not finite", std::string("pose ") + kNames[i] + " is " + number(pose[size_t(i)]) +
                                     "; expected finite numbers (x y z qx qy qz qw)"};
  const double norm = std::sqrt(pose[3] * pose[3] + pose[4] * pose[4] + pose[5] * pose[5] + pose[6] * pose[6]);
  if (norm < 1e-9)
    return {"zero quaternion", "the pose's quaternion qx qy qz qw is zero; expected a unit quaternion (a rotation)"};
  if (std::fabs(norm - 1.0) > kQuaternionTolerance)
    return {"quaternion not unit", "the pose's quaternion has norm " + number(norm) +
                                       "; expected a unit quaternion "
                                       "(norm within " +
                                       number(kQuaternionTolerance) + " of 1)"};
  for (size_t i = 3; i < 7; ++i)
    pose[i] /= norm;
  return {};
}

Pose validPose(const Pose& pose, const std::string& who)
{
  Pose out = pose;
  const InputProblem problem = checkPose(out);
  if (!problem.ok())
    throw InputRefused(problem.reason, who + ": " + problem.what);
  return out;
}

InputProblem checkStamp(double stamp, double previous, bool stream_has_stamps, bool require_stamps)
{
  if (!std::isfinite(stamp))
    return {"stamp not finite", "stamp " + number(stamp) + "; expected finite seconds"};
  if (stamp < 0.0)
    return {"negative stamp", "stamp " + number(stamp) + " is negative; expected seconds >= 0"};
  if (stamp == 0.0 && stream_has_stamps)
    return {"stamp 0", "stamp 0 (unset) after stamped frames (previous " + number(previous) +
                           "); expected every frame of a stamped stream stamped"};
  if (stamp == 0.0 && require_stamps)
    return {"stamp 0",
            "stamp 0 (unset); expected every frame stamped (a driver or bag that leaves "
            "header.stamp unset?)"};
  if (stream_has_stamps && stamp < previous)
    return {"stamp went backwards", "stamp " + number(stamp) + " is before the previous frame's " + number(previous)};
  return {};
}

bool textured(const std::vector<Patch>& cells, double min_std_dev)
{
  for (const Patch& cell : cells)
  {
    cv::Scalar mean, deviation;
    cv::meanStdDev(cell.intensity, mean, deviation);
    if (deviation[0] >= min_std_dev)
      return true;
  }
  return false;
}

InputProblem checkImageSize(int width, int height)
{
  if (width >= kMinImageSide && height >= kMinImageSide)
    return {};
  return {"image too small", "image of " + std::to_string(width) + "x" + std::to_string(height) +
                                 " pixels; expected at least " + std::to_string(kMinImageSide) +
                                 " pixels a side to describe a place"};
}

InputProblem checkTexture(const std::vector<Patch>& cells, bool illumination_invariance)
{
  if (illumination_invariance || textured(cells, kMinFrameStdDev))
    return {};
  return {"no texture", "the frame is constant (grey-level spread below " + number(kMinFrameStdDev) +
                            " in every cell: all black, all one grey, a covered lens); expected a frame "
                            "that shows a place (or illumination_invariance, where dark frames are legitimate)"};
}

}  // namespace openable
