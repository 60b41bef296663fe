#include "openable/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "openable/descriptor.h"
#include "openable/error.h"

namespace openable
{
namespace
{
/// One row per key: how to read and write it. Keeping every key in one table means YAML, --set, ROS
/// parameters and the documentation can never disagree about names or types.
struct KeyAccess
{
  Config::Key key;
  std::function<void(Config&, const std::string&)> set;
  std::function<std::string(const Config&)> get;

  KeyAccess range(double low, double high)
  {
    key.min = low;
    key.max = high;
    key.has_range = true;
    return *this;
  }
  KeyAccess live()
  {
    key.live = true;
    return *this;
  }
  KeyAccess describes()
  {
    key.describes = true;
    return *this;
  }
};

std::string trim(const std::string& s)
{
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos)
    return "";
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

int parseInt(const std::string& key, const std::string& text)
{
  try
  {
    size_t used = 0;
    const long value = std::stol(trim(text), &used);
    if (used == trim(text).size() && value >= INT32_MIN && value <= INT32_MAX)
      return static_cast<int>(value);
  }
  catch (const std::exception&)
  {
  }
  throw Error(key + ": '" + text + "' is not an integer");
}

double parseDouble(const std::string& key, const std::string& text)
{
  try
  {
    size_t used = 0;
    const double value = std::stod(trim(text), &used);
    if (used == trim(text).size())
      return value;
  }
  catch (const std::exception&)
  {
  }
  throw Error(key + ": '" + text + "' is not a number");
}

bool parseBool(const std::string& key, const std::string& text)
{
  const std::string t = trim(text);
  if (t == "true" || t == "True" || t == "TRUE" || t == "1" || t == "yes" || t == "on")
    return true;
  if (t == "false" || t == "False" || t == "FALSE" || t == "0" || t == "no" || t == "off")
    return false;
  throw Error(key + ": '" + text + "' is not a boolean (true / false)");
}

std::string formatDouble(double v)
{
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

template <typename T>
KeyAccess makeKey(const char* name, const char* description, T Config::*member);

template <>
KeyAccess makeKey<int>(const char* name, const char* description, int Config::*member)
{
  return {{name, "int", description},
          [name, member](Config& c, const std::string& v) { c.*member = parseInt(name, v); },
          [member](const Config& c) { return std::to_string(c.*member); }};
}

template <>
KeyAccess makeKey<double>(const char* name, const char* description, double Config::*member)
{
  return {{name, "double", description},
          [name, member](Config& c, const std::string& v) { c.*member = parseDouble(name, v); },
          [member](const Config& c) { return formatDouble(c.*member); }};
}

template <>
KeyAccess makeKey<bool>(const char* name, const char* description, bool Config::*member)
{
  return {{name, "bool", description},
          [name, member](Config& c, const std::string& v) { c.*member = parseBool(name, v); },
          [member](const Config& c) { return std::string(c.*member ? "true" : "false"); }};
}

template <>
KeyAccess makeKey<std::string>(const char* name, const char* description, std::string Config::*member)
{
  return {{name, "string", description},
          [member](Config& c, const std::string& v) { c.*member = trim(v); },
          [member](const Config& c) { return c.*member; }};
}

const std::vector<KeyAccess>& table()
{
  static const std::vector<KeyAccess> keys = {
      makeKey("camera_type", "mono | stereo | panoramic", &Config::camera_type).describes(),
      makeKey("description_type", "global (one descriptor per image) | grid (grid_x x grid_y cells)",
              &Config::description_type).describes(),
      makeKey("patch_size", "side of the square patch every cell is downsampled to (pixels)", &Config::patch_size).range(8, 1024).describes(),
      makeKey("grid_x", "cells across, description_type grid", &Config::grid_x).range(1, 64).describes(),
      makeKey("grid_y", "cells down, description_type grid", &Config::grid_y).range(1, 64).describes(),
      makeKey("panoramas", "vertical sub-panoramas per panorama, camera_type panoramic", &Config::panoramas).range(1, 64).describes(),
      makeKey("illumination_invariance", "apply paper Eq. 6 before description (colour input)",
              &Config::illumination_invariance).describes(),
      makeKey("alpha", "alpha of Eq. 6 (0.47 for KITTI's camera; Eq. 7 from peak wavelengths)", &Config::alpha).range(0, 1).describes(),
      makeKey("patch_normalization", "block side (pixels of the patch) for local contrast normalisation; 0 = off",
              &Config::patch_normalization).range(0, 1024).describes(),
      makeKey("descriptor", "LDB | D-LDB | BRIEF | BRISK | ORB | FREAK | HOG-B | SIFT | SURF | HOG", &Config::descriptor).describes(),
      makeKey("sequence_length", "L: frames per sequence (1 = single images)", &Config::sequence_length).range(1, 10000).live(),
      makeKey("min_sequence_length",
              "sequences of fewer frames are never candidates; 0 = only full sequences of "
              "sequence_length frames (1 = any, the mean of the available terms)",
              &Config::min_sequence_length).range(0, 10000).live(),
      makeKey("threshold", "accept when normalised distance <= threshold (0..1); -1 = no distance gate",
              &Config::threshold).range(-1, 1).live(),
      makeKey("exclusion_window", "loop-closure mode: most recent frames never matched (frames)",
              &Config::exclusion_window).range(0, 100000000).live(),
      makeKey("top_k", "candidates reported per frame", &Config::top_k).range(1, 1000).live(),
      makeKey("min_uniqueness", "accept only when 1 - best / second best >= this (0 = off)", &Config::min_uniqueness).range(0, 1).live(),
      makeKey("uniqueness_window", "frames around the best match skipped when finding the second best (frames)",
              &Config::uniqueness_window).range(0, 100000).live(),
      makeKey("bidirectional", "also match sequences travelled in the opposite direction", &Config::bidirectional).live(),
      makeKey("max_history", "frames kept in the loop-closure history (0 = unbounded)", &Config::max_history).range(0, 100000000),
      makeKey("min_candidates",
              "loop-closure decision: fewer full-sequence candidate places than this is 'too early' (frames)",
              &Config::min_candidates).range(0, 100000000).live(),
      makeKey("consistent_frames",
              "loop-closure decision: consecutive frames that must pass the gates with matches advancing "
              "together (1 = off)",
              &Config::consistent_frames).range(1, 1000).live(),
      makeKey("consistency_tolerance",
              "loop-closure decision: frames a match may deviate from advancing one place per frame",
              &Config::consistency_tolerance).range(0, 1000).live(),
      makeKey("exclusion_seconds",
              "loop-closure mode: frames stamped less than this before the query are never matched (s; 0 = off)",
              &Config::exclusion_seconds).range(0, 1e9).live(),
      makeKey("stereo_num_disparities", "SGBM disparity range at 640 px width (pixels)",
              &Config::stereo_num_disparities).range(16, 1024).describes(),
      makeKey("stereo_block_size", "SGBM block size (odd, pixels)", &Config::stereo_block_size).range(1, 31).describes(),
      makeKey("display_normalization",
              "distance matrix images: max (paper Eq. 5, M / max M) | minmax (contrast "
              "stretch)",
              &Config::display_normalization),
      makeKey("color_map",
              "distance matrix colour map 0..11 (AUTUMN BONE JET WINTER RAINBOW OCEAN SUMMER SPRING "
              "COOL HSV PINK HOT)",
              &Config::color_map).range(0, 11).live(),
  };
  return keys;
}

const KeyAccess& find(const std::string& key)
{
  for (const auto& k : table())
    if (k.key.name == key)
      return k;
  std::string known;
  std::vector<std::string> names;
  for (const auto& k : table())
  {
    known += (known.empty() ? "" : ", ") + k.key.name;
    names.push_back(k.key.name);
  }
  throw Error("unknown configuration key '" + key + "' (did you mean '" + closestName(key, names) +
              "'?); known keys: " + known);
}

/// A configuration file is a few kilobytes; anything much larger is not one (or is a device).
constexpr size_t kMaxConfigFileBytes = 1 << 20;

std::string oneLine(std::string text)
{
  std::replace(text.begin(), text.end(), '\n', ' ');
  return trim(text);
}

std::string oneOf(const std::vector<std::string>& values)
{
  std::string s;
  for (const auto& v : values)
    s += (s.empty() ? "" : " | ") + v;
  return s;
}

}  // namespace

const std::vector<Config::Key>& Config::keys()
{
  static const std::vector<Key> keys = []
  {
    std::vector<Key> out;
    for (const auto& k : table())
      out.push_back(k.key);
    return out;
  }();
  return keys;
}

const std::vector<std::string>& Config::descriptorKeys()
{
  static const std::vector<std::string> keys = []
  {
    std::vector<std::string> out;
    for (const auto& k : table())
      if (k.key.describes)
        out.push_back(k.key.name);
    return out;
  }();
  return keys;
}

const std::vector<std::string>& Config::liveKeys()
{
  static const std::vector<std::string> keys = []
  {
    std::vector<std::string> out;
    for (const auto& k : table())
      if (k.key.live)
        out.push_back(k.key.name);
    return out;
  }();
  return keys;
}

void Config::set(const std::string& key, const std::string& value)
{
  find(key).set(*this, value);
}

std::string Config::get(const std::string& key) const
{
  return find(key).get(*this);
}

bool Config::isBinaryDescriptor() const
{
  return !(descriptor == "SIFT" || descriptor == "SURF" || descriptor == "HOG");
}

std::vector<std::string> Config::validate() const
{
  std::vector<std::string> errors;
  auto bad = [&errors](const std::string& key, const std::string& value, const std::string& expected)
  { errors.push_back(key + ": value '" + value + "' is not allowed; expected " + expected); };

  // Ranges from the key table (the same figures cfg/Detector.cfg carries, tested).
  for (const auto& k : table())
  {
    if (!k.key.has_range)
      continue;
    const std::string text = k.get(*this);
    const double value = std::strtod(text.c_str(), nullptr);
    if (value >= k.key.min && value <= k.key.max)  // false for NaN too
      continue;
    if (k.key.type == "int")
      bad(k.key.name, text,
          "an integer in [" + std::to_string(int64_t(k.key.min)) + ", " + std::to_string(int64_t(k.key.max)) + "]");
    else if (k.key.name == "threshold")
      bad(k.key.name, text, "-1 (off) or a number in [0, 1]");
    else
      bad(k.key.name, text, "a number in [" + formatDouble(k.key.min) + ", " + formatDouble(k.key.max) + "]");
  }

  // Rules beyond a range.
  const std::vector<std::string> cameras = {"mono", "stereo", "panoramic"};
  if (std::find(cameras.begin(), cameras.end(), camera_type) == cameras.end())
    bad("camera_type", camera_type, oneOf(cameras));
  if (description_type != "global" && description_type != "grid")
    bad("description_type", description_type, "global | grid");
  if (description_type == "global" && (grid_x != 1 || grid_y != 1))
    bad("grid_x/grid_y", std::to_string(grid_x) + "x" + std::to_string(grid_y),
        "1x1 with description_type global (set description_type: grid to use a grid)");
  const uint64_t working_bytes = workingBytesPerFrame();
  if (working_bytes > kMaxWorkingBytesPerFrame)
    bad("patch_size/grid_x/grid_y" + std::string(camera_type == "panoramic" ? "/panoramas" : ""),
        std::to_string(patch_size) + " px, " + std::to_string(grid_x) + "x" + std::to_string(grid_y) + " cells" +
            (camera_type == "panoramic" ? ", " + std::to_string(panoramas) + " panoramas" : ""),
        "at most " + std::to_string(kMaxWorkingBytesPerFrame) + " bytes of images per frame; this asks for " +
            std::to_string(working_bytes) + " bytes per frame (" + std::to_string(kWorkingBytesPerPatchPixel) +
            " bytes per patch pixel)");
  if (patch_normalization > patch_size && patch_size >= 8)
    bad("patch_normalization", std::to_string(patch_normalization),
        "an integer in [0, " + std::to_string(patch_size) + "] (at most patch_size)");
  const auto& names = descriptorNames();
  if (std::find(names.begin(), names.end(), descriptor) == names.end())
    bad("descriptor", descriptor, oneOf(names));
  else if (descriptor == "D-LDB" && camera_type != "stereo")
    bad("descriptor", descriptor, "a mono descriptor (D-LDB needs camera_type stereo)");
  if (min_sequence_length > sequence_length && sequence_length >= 1)
    bad("min_sequence_length", std::to_string(min_sequence_length),
        "an integer in [0, " + std::to_string(sequence_length) + "] (at most sequence_length)");
  if (threshold > -1.0 && threshold < 0.0)
    bad("threshold", formatDouble(threshold), "-1 (off) or a number in [0, 1]");
  // In 64 bits: sequence_length and exclusion_window may themselves be out of range (up to INT_MAX) here.
  const int64_t history_floor = 2 * (int64_t(sequence_length) + int64_t(exclusion_window));
  if (max_history > 0 && max_history <= history_floor)
    bad("max_history", std::to_string(max_history),
        "0 (unbounded) or more than 2 * (sequence_length + exclusion_window) = " + std::to_string(history_floor));
  if (stereo_block_size % 2 == 0)
    bad("stereo_block_size", std::to_string(stereo_block_size), "an odd integer in [1, 31]");
  if (display_normalization != "max" && display_normalization != "minmax")
    bad("display_normalization", display_normalization, "max | minmax");
  return errors;
}

uint64_t Config::workingBytesPerFrame() const
{
  // Out-of-range fields (up to INT_MAX, or negative) are validation errors of their own; here they must
  // neither wrap nor hide the figure, so negatives count as 0 and products saturate.
  const auto field = [](int v) { return uint64_t(std::max(v, 0)); };
  const auto times = [](uint64_t a, uint64_t b) { return (b != 0 && a > UINT64_MAX / b) ? UINT64_MAX : a * b; };
  uint64_t cells = description_type == "grid" ? times(field(grid_x), field(grid_y)) : 1;
  if (camera_type == "panoramic")
    cells = times(cells, field(panoramas));
  return times(times(cells, times(field(patch_size), field(patch_size))), kWorkingBytesPerPatchPixel);
}

void Config::validateOrThrow() const
{
  const auto errors = validate();
  if (errors.empty())
    return;
  std::string message = "invalid configuration: ";
  for (size_t i = 0; i < errors.size(); ++i)
    message += (i ? "; " : "") + errors[i];
  throw Error(message);
}

Config Config::fromYamlString(const std::string& yaml)
{
  YAML::Node root;
  try
  {
    root = YAML::Load(yaml);
  }
  catch (const YAML::Exception& e)
  {
    throw Error(std::string("configuration is not valid YAML: ") + e.what());
  }
  Config config;
  if (root.IsNull())
    return config;
  if (!root.IsMap())
    throw Error("configuration must be a YAML mapping of key: value");
  try
  {
    for (const auto& entry : root)
    {
      // YAML allows lists and mappings as keys too ("? [a, b]: 1"); as<std::string>() would throw
      // yaml-cpp's own exception for them.
      if (!entry.first.IsScalar())
        throw Error("key '" + oneLine(YAML::Dump(entry.first)) + "' is a list or mapping; expected a key name");
      const std::string key = entry.first.Scalar();
      if (!entry.second.IsScalar())
        throw Error(key + ": value '" + oneLine(YAML::Dump(entry.second)) +
                    "' is a list, a mapping or empty; expected a single value");
      config.set(key, entry.second.Scalar());
    }
  }
  catch (const YAML::Exception& e)
  {
    // Whatever yaml-cpp still throws (it has no other way to say no) leaves as the library's Error.
    throw Error(std::string("configuration cannot be read: ") + e.what());
  }
  return config;
}

Config Config::fromYamlFile(const std::string& path)
{
  // A folder opens as an empty stream on Linux and would silently give the defaults; a device or a pipe
  // could be read forever. A configuration file is a regular file of a few kilobytes.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error("configuration '" + path + "' is a folder; expected a YAML file");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error("cannot read configuration file '" + path + "'");
  std::string text(kMaxConfigFileBytes + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  if (in.bad())
    throw Error("cannot read configuration file '" + path + "'");
  text.resize(static_cast<size_t>(in.gcount()));
  if (text.size() > kMaxConfigFileBytes)
    throw Error("configuration file '" + path + "' is larger than " + std::to_string(kMaxConfigFileBytes) +
                " bytes; expected a YAML mapping of key: value");
  try
  {
    return fromYamlString(text);
  }
  catch (const Error& e)
  {
    throw Error(path + ": " + e.what());
  }
}

std::string Config::toYaml() const
{
  std::string out;
  for (const auto& k : table())
  {
    std::string value = k.get(*this);
    if (k.key.type == "string")
      value = "\"" + value + "\"";
    out += k.key.name + ": " + value + "\n";
  }
  return out;
}

std::string closestName(const std::string& name, const std::vector<std::string>& candidates)
{
  // Levenshtein distance, one row at a time.
  const auto distance = [&name](const std::string& other)
  {
    std::vector<size_t> row(other.size() + 1);
    for (size_t j = 0; j <= other.size(); ++j)
      row[j] = j;
    for (size_t i = 1; i <= name.size(); ++i)
    {
      size_t diagonal = row[0];
      row[0] = i;
      for (size_t j = 1; j <= other.size(); ++j)
      {
        const size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (name[i - 1] == other[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    return row[other.size()];
  };
  std::string best;
  size_t best_distance = SIZE_MAX;
  for (const auto& candidate : candidates)
  {
    const size_t d = distance(candidate);
    if (d < best_distance)
    {
      best = candidate;
      best_distance = d;
    }
  }
  return best;
}

double alphaFromWavelengths(double lambda_red, double lambda_green, double lambda_blue)
{
  if (!(lambda_red > 0 && lambda_green > 0 && lambda_blue > 0) || lambda_red == lambda_blue)
    throw Error("alphaFromWavelengths: peak wavelengths must be positive and red != blue (nm)");
  // Paper Eq. 7.
  return (lambda_blue / lambda_green - lambda_blue / lambda_red) / (1.0 - lambda_blue / lambda_red);
}

}  // namespace openable
