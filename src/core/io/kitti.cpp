#include "openable/io/kitti.h"

#include <dirent.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "openable/error.h"

namespace openable
{
namespace
{
std::string at(const std::string& path, int line)
{
  return path + ":" + std::to_string(line) + ": ";
}

bool blank(const std::string& line)
{
  return line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t\r")] == '#';
}

std::ifstream openKitti(const std::string& path, const std::string& what)
{
  std::error_code ec;
  std::ifstream in(path);
  if (!in || !std::filesystem::is_regular_file(path, ec))
    throw Error("cannot read " + what + " file '" + path + "': cannot open it (missing, unreadable or not a file)");
  return in;
}

bool allFinite(const KittiMatrix& m)
{
  return std::all_of(m.begin(), m.end(), [](double v) { return std::isfinite(v); });
}
}  // namespace

std::map<std::string, KittiMatrix> readKittiCalibration(const std::string& path)
{
  std::ifstream in = openKitti(path, "calibration");
  std::map<std::string, KittiMatrix> matrices;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    const auto colon = line.find(':');
    if (colon == std::string::npos)
      continue;
    const std::string key = line.substr(0, colon);
    if (key.size() != 2 || key[0] != 'P')
      continue;  // Tr (velodyne -> camera) and anything else: not needed
    std::istringstream fields(line.substr(colon + 1));
    KittiMatrix p;
    for (double& v : p)
      if (!(fields >> v))
        throw Error(at(path, number) + key + " has fewer than 12 numbers");
    if (!allFinite(p))
      throw Error(at(path, number) + key + " holds a NaN or infinite number; expected a finite 3x4 projection matrix");
    if (!(p[0] > 0.0) || !(p[5] > 0.0))
      throw Error(at(path, number) + key + " has focal lengths fx " + std::to_string(p[0]) + ", fy " +
                  std::to_string(p[5]) + "; expected positive ones (P = K [I | t])");
    matrices[key] = p;
  }
  return matrices;
}

std::vector<double> readKittiTimes(const std::string& path, double offset)
{
  std::ifstream in = openKitti(path, "times");
  std::vector<double> times;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (blank(line))
      continue;
    std::istringstream fields(line);
    double t;
    if (!(fields >> t) || !std::isfinite(t) || t < 0.0)
      throw Error(at(path, number) + "'" + line + "' is not a time in seconds >= 0");
    if (offset + t >= 4294967296.0)
      throw Error(at(path, number) + "time " + std::to_string(t) + " s plus --time-offset " + std::to_string(offset) +
                  " s is past the largest ROS time (2^32 s)");
    if (!times.empty() && t < times.back())
      throw Error(at(path, number) + "time " + std::to_string(t) + " goes backwards (previous " +
                  std::to_string(times.back()) + ")");
    times.push_back(t);
  }
  return times;
}

std::string kittiPoseProblem(const KittiMatrix& p)
{
  if (!allFinite(p))
    return "holds a NaN or infinite number";
  const auto dot = [&p](int a, int b)
  { return p[4 * a] * p[4 * b] + p[4 * a + 1] * p[4 * b + 1] + p[4 * a + 2] * p[4 * b + 2]; };
  const double det =
      p[0] * (p[5] * p[10] - p[6] * p[9]) - p[1] * (p[4] * p[10] - p[6] * p[8]) + p[2] * (p[4] * p[9] - p[5] * p[8]);
  const double tolerance = 1e-3;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b)
      if (std::abs(dot(a, b) - (a == b ? 1.0 : 0.0)) > tolerance)
        return "has a rotation part that is not a rotation (rows not orthonormal)";
  if (std::abs(det - 1.0) > tolerance)
    return "has a rotation part with determinant " + std::to_string(det) + " (expected 1)";
  return "";
}

KittiPoses readKittiPoses(const std::string& path)
{
  std::ifstream in = openKitti(path, "poses");
  KittiPoses out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (blank(line))
      continue;
    std::vector<double> numbers;
    if (!numbersOfLine(line, numbers) || numbers.size() != 12)
      throw Error(at(path, number) + "line " + std::to_string(number) +
                  " is not a row-major 3x4 pose (12 numbers, [R|t])");
    KittiMatrix p;
    std::copy(numbers.begin(), numbers.end(), p.begin());
    const std::string problem = kittiPoseProblem(p);
    if (!problem.empty())
      throw Error(at(path, number) + "the pose " + problem);
    out.poses.push_back(p);
    out.lines.push_back(number);
  }
  if (out.poses.empty())
    throw Error("KITTI poses: '" + path + "' holds no pose");
  return out;
}

// strtod, not istream >> double: the latter refuses "nan" and "inf", which would be misreported as a
// malformed line instead of as a non-finite number.
bool numbersOfLine(const std::string& line, std::vector<double>& numbers)
{
  std::istringstream words(line);
  std::string word;
  while (words >> word)
  {
    char* end = nullptr;
    numbers.push_back(std::strtod(word.c_str(), &end));
    if (end == word.c_str() || *end != '\0')
      return false;
  }
  return true;
}

std::map<long, std::string> listKittiImages(const std::string& dir)
{
  std::map<long, std::string> images;
  DIR* d = opendir(dir.c_str());
  if (!d)
    return images;
  while (dirent* entry = readdir(d))
  {
    const std::string name = entry->d_name;
    if (name.size() < 5 || name.substr(name.size() - 4) != ".png")
      continue;
    const std::string stem = name.substr(0, name.size() - 4);
    if (stem.empty() || !std::all_of(stem.begin(), stem.end(), ::isdigit))
      continue;
    // Frame numbers become the uint32 header.seq; a longer digit string is not a KITTI frame.
    errno = 0;
    const unsigned long long index = std::strtoull(stem.c_str(), nullptr, 10);
    if (errno == ERANGE || index > UINT32_MAX)
    {
      closedir(d);
      throw Error(dir + "/" + name + ": frame number " + stem + " is too large (expected at most " +
                  std::to_string(UINT32_MAX) + ", KITTI names frames NNNNNN.png)");
    }
    images[static_cast<long>(index)] = name;
  }
  closedir(d);
  return images;
}

std::array<double, 3> kittiProjectionOffset(const KittiMatrix& p)
{
  const double fx = p[0], cx = p[2], fy = p[5], cy = p[6];
  const double tz = p[11];
  return {(p[3] - cx * tz) / fx, (p[7] - cy * tz) / fy, tz};
}

}  // namespace openable
