#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

namespace openable
{
/// A row-major 3x4 matrix as KITTI writes them: a projection P = K [I | t] or a pose [R | t].
using KittiMatrix = std::array<double, 12>;

/// The one reader of KITTI odometry files, used by the ground truth from poses, kitti_to_bag and the tests.
/// Every error is openable::Error naming the file and line ("path:N: ...").

/// calib.txt: the projection matrices P0..P3 by name (other lines, e.g. Tr, are skipped). Each must be
/// finite with positive focal lengths.
std::map<std::string, KittiMatrix> readKittiCalibration(const std::string& path);

/// times.txt: seconds per frame (>= 0, not going backwards); with `offset` added they must stay below
/// 2^32 s (the largest ROS time).
std::vector<double> readKittiTimes(const std::string& path, double offset = 0.0);

/// poses/NN.txt: camera-0 pose of each frame in the first camera-0 frame, one [R | t] per line, with the
/// file line of each pose (for later errors). Every pose must be finite with R a rotation.
struct KittiPoses
{
  std::vector<KittiMatrix> poses;
  std::vector<int> lines;
};
KittiPoses readKittiPoses(const std::string& path);

/// The whitespace-separated words of one line of a text file (KITTI, TUM) as numbers, appended to `numbers`;
/// false when a word is not a number. "nan" and "inf" are numbers here (so callers can name them).
bool numbersOfLine(const std::string& line, std::vector<double>& numbers);

/// Why a 3x4 pose cannot be one ("" when it can): non-finite numbers, or R not a rotation (rows not
/// orthonormal, determinant not +1) to KITTI's 7 printed digits.
std::string kittiPoseProblem(const KittiMatrix& pose);

/// The frames of an image folder (image_0 ... image_3): NNNNNN.png by frame number; other files are
/// skipped; a missing folder gives an empty map. Throws Error for a frame number past 2^32 - 1.
std::map<long, std::string> listKittiImages(const std::string& dir);

/// The camera centre offset t of a rectified P = K [I | t]: t = K^-1 * P(:, 3) (metres).
std::array<double, 3> kittiProjectionOffset(const KittiMatrix& p);

}  // namespace openable
