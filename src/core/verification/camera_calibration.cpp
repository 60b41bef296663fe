#include "openable/verification/camera_calibration.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/io/kitti.h"

namespace openable
{
namespace
{
// A calibration is a few hundred bytes; anything much larger is not one (and is not read whole).
constexpr size_t kMaxCalibrationBytes = 1u << 20;

[[noreturn]] void fail(const std::string& name, const std::string& key, const std::string& what)
{
  throw Error(name + ": " + key + ": " + what);
}

std::string str(double value)
{
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string firstLine(const std::string& text)
{
  const auto end = text.find('\n');
  return end == std::string::npos ? text : text.substr(0, end);
}

double number(const std::string& name, const std::string& key, const std::string& text)
{
  size_t used = 0;
  double value = 0.0;
  try
  {
    value = std::stod(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
    fail(name, key, "'" + text + "' is not a finite number");
  return value;
}

// A matrix as camera_calibration writes it: {rows, cols, data: [...]}, row-major.
std::vector<double> yamlMatrix(const YAML::Node& node, const std::string& name, const std::string& key, int rows,
                               int cols)
{
  if (!node.IsMap())
    fail(name, key, "expected a mapping with rows, cols and data");
  for (const auto& [field, expected] : {std::make_pair("rows", rows), std::make_pair("cols", cols)})
  {
    const YAML::Node n = node[field];
    if (n && (!n.IsScalar() || n.Scalar() != std::to_string(expected)))
      fail(name, key + "." + field,
           "'" + (n.IsScalar() ? n.Scalar() : std::string("?")) + "', expected " + std::to_string(expected));
  }
  const YAML::Node data = node["data"];
  if (!data || !data.IsSequence())
    fail(name, key + ".data", "missing or not a list; expected [" + std::to_string(rows * cols) + " numbers]");
  if (static_cast<int>(data.size()) != rows * cols)
    fail(name, key + ".data",
         std::to_string(data.size()) + " numbers, expected " + std::to_string(rows * cols) + " (" +
             std::to_string(rows) + "x" + std::to_string(cols) + " row-major)");
  std::vector<double> values;
  for (const auto& v : data)
  {
    if (!v.IsScalar())
      fail(name, key + ".data", "an entry is a list or mapping; expected numbers");
    values.push_back(number(name, key + ".data", v.Scalar()));
  }
  return values;
}

int yamlSize(const YAML::Node& root, const std::string& name, const char* key)
{
  const YAML::Node n = root[key];
  if (!n)
    return 0;
  const std::string text = n.IsScalar() ? n.Scalar() : "?";
  size_t used = 0;
  long value = -1;
  try
  {
    value = std::stol(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used == 0 || used != text.size() || value <= 0 || value > 100000)
    fail(name, key, "'" + text + "', expected pixels, an integer in [1, 100000]");
  return static_cast<int>(value);
}

void checkIntrinsics(const PinholeCamera& camera, const std::string& name, const std::string& key)
{
  if (!(camera.fx > 0.0) || !(camera.fy > 0.0))
    fail(name, key, "fx " + str(camera.fx) + ", fy " + str(camera.fy) + ", expected > 0 (uncalibrated?)");
  if (camera.baseline < 0.0)
    fail(name, key, "stereo baseline " + str(camera.baseline) + " m, expected >= 0");
}

PinholeCamera parseRosYaml(const std::string& text, const std::string& name)
{
  YAML::Node root;
  try
  {
    root = YAML::Load(text);
  }
  catch (const YAML::Exception& e)
  {
    fail(name, "YAML", firstLine(e.what()));
  }
  if (!root.IsMap())
    fail(name, "projection_matrix",
         "missing; expected a ROS camera_info YAML (camera_calibration) or a KITTI calib.txt (P0: line)");
  PinholeCamera camera;
  try
  {
    camera.image_size = cv::Size(yamlSize(root, name, "image_width"), yamlSize(root, name, "image_height"));
    if ((camera.image_size.width == 0) != (camera.image_size.height == 0))
      fail(name, camera.image_size.width ? "image_height" : "image_width", "missing while the other size is given");
    std::string key;
    if (root["projection_matrix"])
    {
      // Rectified images: P's intrinsics. One file is one camera, so its P(0,3) (-fx * baseline for a right
      // camera) is not used: verification from a single camera_info is mono.
      key = "projection_matrix";
      const auto p = yamlMatrix(root[key], name, key, 3, 4);
      camera.fx = p[0];
      camera.cx = p[2];
      camera.fy = p[5];
      camera.cy = p[6];
    }
    else if (root["camera_matrix"])
    {
      key = "camera_matrix";
      const auto k = yamlMatrix(root[key], name, key, 3, 3);
      camera.fx = k[0];
      camera.cx = k[2];
      camera.fy = k[4];
      camera.cy = k[5];
    }
    else
    {
      fail(name, "projection_matrix",
           "missing (and no camera_matrix); expected a ROS camera_info YAML (camera_calibration) or a KITTI "
           "calib.txt (P0: line)");
    }
    checkIntrinsics(camera, name, key);
  }
  catch (const YAML::Exception& e)
  {
    fail(name, "YAML", firstLine(e.what()));
  }
  return camera;
}

// KITTI's own reader checks the numbers; here only what the verifier needs: P0, and P1 giving a baseline.
PinholeCamera fromKitti(const std::map<std::string, KittiMatrix>& matrices, const std::string& name)
{
  const auto matrix = [](const KittiMatrix& m)
  {
    cv::Matx34d p;
    std::copy(m.begin(), m.end(), p.val);
    return p;
  };
  const auto p0 = matrices.find("P0");
  if (p0 == matrices.end())
    fail(name, "P0", "missing; expected a line 'P0: 12 numbers' (the left camera)");
  const auto p1 = matrices.find("P1");
  const PinholeCamera camera = PinholeCamera::fromProjection(
      matrix(p0->second), p1 == matrices.end() ? cv::Matx34d::zeros() : matrix(p1->second));
  if (p1 != matrices.end() && !camera.stereo())
    fail(name, "P1", "gives no baseline (P1(0,3) = " + str(p1->second[3]) + "); expected -fx * baseline < 0");
  return camera;
}
}  // namespace

PinholeCamera parseCameraCalibration(const std::string& text, const std::string& name)
{
  return parseRosYaml(text, name);
}

PinholeCamera readCameraCalibration(const std::string& path)
{
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(path + ": is a folder; expected a camera_info YAML or a KITTI calib.txt");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error(path + ": cannot be read; expected a camera_info YAML or a KITTI calib.txt");
  std::string text(kMaxCalibrationBytes + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  if (in.bad())
    throw Error(path + ": cannot be read");
  text.resize(static_cast<size_t>(in.gcount()));
  if (text.size() > kMaxCalibrationBytes)
    throw Error(path + ": larger than " + std::to_string(kMaxCalibrationBytes) + " bytes; not a calibration file");
  static const std::regex kitti(R"((^|\n)\s*P0\s*:)");
  if (std::regex_search(text, kitti))
    return fromKitti(readKittiCalibration(path), path);
  return parseRosYaml(text, path);
}

}  // namespace openable
