#include "openable/io/pose_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "openable/error.h"
#include "openable/description/input_contract.h"

namespace openable
{
namespace
{
const char* const kExpected =
    "expected a KITTI pose (12 numbers: row-major 3x4 [R|t]) or a TUM pose (8 numbers: stamp tx ty tz qx qy qz qw)";

std::string at(const std::string& path, int line)
{
  return path + ":" + std::to_string(line) + ": ";
}

bool comment(const std::string& line)
{
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

std::ifstream openPoses(const std::string& path)
{
  std::error_code ec;
  std::ifstream in(path);
  if (!in || !std::filesystem::is_regular_file(path, ec))
    throw Error("cannot read pose file '" + path + "': cannot open it (missing, unreadable or not a file)");
  return in;
}

/// The first pose line: how many numbers it holds (0: the file has no pose line) and its number.
struct FirstPose
{
  size_t columns = 0;
  int line = 0;
};

FirstPose firstPose(const std::string& path)
{
  std::ifstream in = openPoses(path);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (comment(line))
      continue;
    std::vector<double> numbers;
    if (!numbersOfLine(line, numbers))
      throw Error(at(path, number) + "'" + line + "' holds a word that is not a number; " + kExpected);
    return {numbers.size(), number};
  }
  return {};
}

PoseFile readTum(const std::string& path)
{
  std::ifstream in = openPoses(path);
  PoseFile out;
  out.format = PoseFile::Format::Tum;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (comment(line))
      continue;
    std::vector<double> v;
    if (!numbersOfLine(line, v) || v.size() != 8)
      throw Error(at(path, number) + "'" + line +
                  "' is not a TUM pose like the file's first one (8 numbers: stamp tx ty tz qx qy qz qw)");
    if (!std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }))
      throw Error(at(path, number) + "the pose holds a NaN or infinite number");
    const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (norm < 1e-9)
      throw Error(at(path, number) + "the quaternion qx qy qz qw is zero; expected a rotation (a non-zero quaternion)");
    if (v[0] < 0.0)
      throw Error(at(path, number) + "stamp " + std::to_string(v[0]) + " is negative; expected seconds >= 0");
    if (!out.stamps.empty() && v[0] < out.stamps.back())
      throw Error(at(path, number) + "stamp " + std::to_string(v[0]) + " goes backwards (previous " +
                  std::to_string(out.stamps.back()) + "); expected the poses in frame order");
    // The input contract: a near-unit quaternion is normalised, a clearly non-unit one refused.
    Pose pose{{v[1], v[2], v[3], v[4], v[5], v[6], v[7]}};
    const InputProblem problem = checkPose(pose);
    if (!problem.ok())
      throw Error(at(path, number) + problem.what);
    out.stamps.push_back(v[0]);
    out.poses.push_back(pose);
  }
  return out;
}
}  // namespace

std::array<double, 7> poseFromKitti(const KittiMatrix& m)
{
  // Shepperd: divide by the largest of the four (4 q_i^2) terms, the best conditioned for any rotation.
  const double r00 = m[0], r01 = m[1], r02 = m[2], r10 = m[4], r11 = m[5], r12 = m[6], r20 = m[8], r21 = m[9],
               r22 = m[10];
  const double trace = r00 + r11 + r22;
  double x, y, z, w;
  if (trace > 0.0)
  {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    w = 0.25 * s, x = (r21 - r12) / s, y = (r02 - r20) / s, z = (r10 - r01) / s;
  }
  else if (r00 > r11 && r00 > r22)
  {
    const double s = 2.0 * std::sqrt(1.0 + r00 - r11 - r22);
    w = (r21 - r12) / s, x = 0.25 * s, y = (r01 + r10) / s, z = (r02 + r20) / s;
  }
  else if (r11 > r22)
  {
    const double s = 2.0 * std::sqrt(1.0 + r11 - r00 - r22);
    w = (r02 - r20) / s, x = (r01 + r10) / s, y = 0.25 * s, z = (r12 + r21) / s;
  }
  else
  {
    const double s = 2.0 * std::sqrt(1.0 + r22 - r00 - r11);
    w = (r10 - r01) / s, x = (r02 + r20) / s, y = (r12 + r21) / s, z = 0.25 * s;
  }
  // KITTI prints 7 digits: R is a rotation only to ~1e-7, so the quaternion is normalised again.
  const double sign = w < 0.0 ? -1.0 : 1.0;
  const double norm = sign * std::sqrt(x * x + y * y + z * z + w * w);
  return {m[3], m[7], m[11], x / norm, y / norm, z / norm, w / norm};
}

PoseFile readPoseFile(const std::string& path)
{
  const FirstPose first = firstPose(path);
  if (first.columns == 0)
    throw Error("pose file '" + path + "' holds no pose (empty or only comments); " + kExpected + ", one per frame");
  if (first.columns == 8)
    return readTum(path);
  if (first.columns != 12)
    throw Error(at(path, first.line) + std::to_string(first.columns) + " numbers; " + kExpected);
  PoseFile out;
  out.format = PoseFile::Format::Kitti;
  for (const KittiMatrix& m : readKittiPoses(path).poses)
    out.poses.push_back(poseFromKitti(m));
  return out;
}

const char* toString(PoseFile::Format format)
{
  return format == PoseFile::Format::Tum ? "TUM" : "KITTI";
}

}  // namespace openable
