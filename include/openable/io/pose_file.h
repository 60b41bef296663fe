#pragma once

#include <array>
#include <string>
#include <vector>

#include "openable/io/kitti.h"

namespace openable
{
/// A camera trajectory, one pose per frame in frame order (openable_offline --poses): what a robot's
/// odometry gives the nodelets through tf, for streams replayed from files.
struct PoseFile
{
  enum class Format
  {
    Kitti,  ///< 12 numbers a line: row-major 3x4 [R|t] (KITTI odometry poses/NN.txt)
    Tum,    ///< 8 numbers a line: stamp tx ty tz qx qy qz qw (TUM RGB-D), '#' comments
  };
  Format format = Format::Kitti;
  std::vector<std::array<double, 7>> poses;  ///< x y z qx qy qz qw, unit quaternion (FrameInput::pose)
  std::vector<double> stamps;                ///< TUM: seconds, one per pose; KITTI: empty (no stamps)
};

/// Reads a KITTI or TUM trajectory; the format is the first pose line's (12 or 8 numbers) and every other
/// line must match it. Throws Error naming the file and line (and what was expected) for a line of
/// another length or with a word that is not a number, a non-finite number, a KITTI rotation that is not
/// one, a zero TUM quaternion or one whose norm is not within kQuaternionTolerance of 1 (input_contract.h;
/// near-unit ones are normalised), TUM stamps below 0 or going backwards, or a file without any pose.
PoseFile readPoseFile(const std::string& path);

/// The pose of a KITTI [R|t] as x y z qx qy qz qw (R -> unit quaternion, qw >= 0).
std::array<double, 7> poseFromKitti(const KittiMatrix& m);

const char* toString(PoseFile::Format format);

}  // namespace openable
