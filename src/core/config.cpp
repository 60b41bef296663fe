#include "openable/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "config_keys.h"
#include "openable/descriptors/descriptor_registry.h"
#include "openable/error.h"

namespace openable
{
using config_keys::formatDouble;
using config_keys::table;
using config_keys::trim;

namespace
{
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

namespace
{
// The words of camera_type and description_type and what they parse to: the one place they are spelled.
const std::vector<std::pair<std::string, CameraType>> kCameraWords = {
    {"mono", CameraType::Mono}, {"stereo", CameraType::Stereo}, {"panoramic", CameraType::Panoramic}};
const std::vector<std::pair<std::string, DescriptionType>> kDescriptionWords = {
    {"global", DescriptionType::Global}, {"grid", DescriptionType::Grid}};

template <class Enum>
const Enum* parseWord(const std::vector<std::pair<std::string, Enum>>& words, const std::string& word)
{
  for (const auto& w : words)
    if (w.first == word)
      return &w.second;
  return nullptr;
}

template <class Enum>
std::vector<std::string> wordsOf(const std::vector<std::pair<std::string, Enum>>& words)
{
  std::vector<std::string> out;
  for (const auto& w : words)
    out.push_back(w.first);
  return out;
}
}  // namespace

CameraType Config::camera() const
{
  if (const CameraType* type = parseWord(kCameraWords, camera_type))
    return *type;
  throw Error("camera_type: value '" + camera_type + "' is not allowed; expected " + oneOf(wordsOf(kCameraWords)));
}

DescriptionType Config::description() const
{
  if (const DescriptionType* type = parseWord(kDescriptionWords, description_type))
    return *type;
  throw Error("description_type: value '" + description_type + "' is not allowed; expected " +
              oneOf(wordsOf(kDescriptionWords)));
}

std::string ConfigProblem::message() const
{
  std::string joined;
  for (const auto& key : keys)
    joined += (joined.empty() ? "" : "/") + key;
  return joined + ": value '" + value + "' is not allowed; expected " + expected;
}

std::vector<std::string> Config::validate() const
{
  std::vector<std::string> messages;
  for (const auto& problem : problems())
    messages.push_back(problem.message());
  return messages;
}

Config Config::sanitized(const Config& fallback, std::vector<ConfigRepair>& repairs,
                         const std::vector<std::string>& fixed) const
{
  Config config = *this;
  // One round per key at most: each round resets at least one more key, or nothing is left to reset.
  for (size_t round = 0; round < keys().size(); ++round)
  {
    const auto found = config.problems();
    if (found.empty())
      break;
    for (const auto& problem : found)
    {
      ConfigRepair repair{problem, {}};
      for (const auto& key : problem.keys)
        if (std::find(fixed.begin(), fixed.end(), key) == fixed.end())
        {
          config.set(key, fallback.get(key));
          repair.reset_keys.push_back(key);
        }
      repairs.push_back(std::move(repair));
    }
  }
  return config;
}

std::vector<ConfigProblem> Config::problems() const
{
  std::vector<ConfigProblem> errors;
  auto bad = [&errors](std::vector<std::string> keys, const std::string& value, const std::string& expected)
  { errors.push_back(ConfigProblem{std::move(keys), value, expected}); };

  // Ranges from the key table (the same figures cfg/Detector.cfg carries, tested).
  for (const auto& k : table())
  {
    if (!k.key.has_range)
      continue;
    const std::string text = k.get(*this);
    const double value = std::strtod(text.c_str(), nullptr);
    const bool above_min = k.key.min_exclusive ? value > k.key.min : value >= k.key.min;
    const bool below_max = k.key.max_exclusive ? value < k.key.max : value <= k.key.max;
    const bool between_off_and_zero = k.key.minus_one_is_off && value > -1.0 && value < 0.0;
    if (above_min && below_max && !between_off_and_zero)  // false for NaN too
      continue;
    if (k.key.type == "int")
      bad({k.key.name}, text,
          "an integer in [" + std::to_string(int64_t(k.key.min)) + ", " + std::to_string(int64_t(k.key.max)) + "]");
    else if (k.key.minus_one_is_off)
      bad({k.key.name}, text, "-1 (off) or a number in [0, " + formatDouble(k.key.max) + "]");
    else
      bad({k.key.name}, text,
          std::string("a number in ") + (k.key.min_exclusive ? "(" : "[") + formatDouble(k.key.min) + ", " +
              formatDouble(k.key.max) + (k.key.max_exclusive ? ")" : "]"));
  }

  // Rules beyond a range.
  const CameraType* camera_parsed = parseWord(kCameraWords, camera_type);
  if (!camera_parsed)
    bad({"camera_type"}, camera_type, oneOf(wordsOf(kCameraWords)));
  const DescriptionType* description_parsed = parseWord(kDescriptionWords, description_type);
  if (!description_parsed)
    bad({"description_type"}, description_type, oneOf(wordsOf(kDescriptionWords)));
  else if (*description_parsed == DescriptionType::Global && (grid_x != 1 || grid_y != 1))
    bad({"grid_x", "grid_y"}, std::to_string(grid_x) + "x" + std::to_string(grid_y),
        "1x1 with description_type global (set description_type: grid to use a grid)");
  const uint64_t working_bytes = workingBytesPerFrame();
  if (working_bytes > kMaxWorkingBytesPerFrame)
  {
    const bool panoramic = camera_parsed && *camera_parsed == CameraType::Panoramic;
    std::vector<std::string> keys_of_rule = {"patch_size", "grid_x", "grid_y"};
    if (panoramic)
      keys_of_rule.push_back("panoramas");
    bad(keys_of_rule,
        std::to_string(patch_size) + " px, " + std::to_string(grid_x) + "x" + std::to_string(grid_y) + " cells" +
            (panoramic ? ", " + std::to_string(panoramas) + " panoramas" : ""),
        "at most " + std::to_string(kMaxWorkingBytesPerFrame) + " bytes of images per frame; this asks for " +
            std::to_string(working_bytes) + " bytes per frame (" + std::to_string(kWorkingBytesPerPatchPixel) +
            " bytes per patch pixel)");
  }
  if (patch_normalization > patch_size && patch_size >= 8)
    bad({"patch_normalization"}, std::to_string(patch_normalization),
        "an integer in [0, " + std::to_string(patch_size) + "] (at most patch_size)");
  const DescriptorInfo* descriptor_row = findDescriptor(descriptor);
  if (!descriptor_row)
    bad({"descriptor"}, descriptor, oneOf(descriptorNames()));
  else if (descriptor_row->needs_disparity && !(camera_parsed && *camera_parsed == CameraType::Stereo))
    bad({"descriptor"}, descriptor,
        "a mono descriptor (" + descriptor + " describes disparity and needs camera_type stereo)");
  const auto bitsOf = [&](const char* key, int bits)
  {
    if (bits == 0 || !descriptor_row)
      return;
    if (!descriptor_row->binary())
      bad({key}, std::to_string(bits), "0 (" + descriptor + " is a float descriptor: it keeps every value)");
    else if (bits > descriptor_row->length)
      bad({key}, std::to_string(bits),
          "0 (all) or at most the " + std::to_string(descriptor_row->length) + " bits of " + descriptor);
  };
  bitsOf("descriptor_bits", descriptor_bits);
  if (descriptor_row && descriptor_row->binary())  // a float descriptor's view channel keeps every value
    bitsOf("view_channel_bits", view_channel_bits);
  if (min_sequence_length > sequence_length && sequence_length >= 1)
    bad({"min_sequence_length"}, std::to_string(min_sequence_length),
        "an integer in [0, " + std::to_string(sequence_length) + "] (at most sequence_length)");
  // In 64 bits: sequence_length and exclusion_window may themselves be out of range (up to INT_MAX) here.
  const int64_t history_floor = 2 * (int64_t(sequence_length) + int64_t(exclusion_window));
  if (max_history > 0 && max_history <= history_floor)
    bad({"max_history"}, std::to_string(max_history),
        "0 (unbounded) or more than 2 * (sequence_length + exclusion_window) = " + std::to_string(history_floor));
  if (stereo_block_size % 2 == 0)
    bad({"stereo_block_size"}, std::to_string(stereo_block_size), "an odd integer in [1, 31]");
  if (display_normalization != "max" && display_normalization != "minmax")
    bad({"display_normalization"}, display_normalization, "max | minmax");
  // Both keys named, so a ROS parameter reader falls back on both (either one alone could still break it).
  if (!(verify_stereo_min_disparity_px < verify_stereo_max_disparity_px))
    bad({"verify_stereo_min_disparity_px", "verify_stereo_max_disparity_px"},
        formatDouble(verify_stereo_min_disparity_px) + " / " + formatDouble(verify_stereo_max_disparity_px),
        "the smallest disparity below the largest");
  return errors;
}

uint64_t Config::workingBytesPerFrame() const
{
  // Out-of-range fields (up to INT_MAX, or negative) are validation errors of their own; here they must
  // neither wrap nor hide the figure, so negatives count as 0 and products saturate.
  const auto field = [](int v) { return uint64_t(std::max(v, 0)); };
  const auto times = [](uint64_t a, uint64_t b) { return (b != 0 && a > UINT64_MAX / b) ? UINT64_MAX : a * b; };
  // Parsed without throwing: this runs inside validate(), on values it may yet refuse.
  const DescriptionType* description_parsed = parseWord(kDescriptionWords, description_type);
  const CameraType* camera_parsed = parseWord(kCameraWords, camera_type);
  uint64_t cells = description_parsed && *description_parsed == DescriptionType::Grid ? times(field(grid_x), field(grid_y)) : 1;
  if (camera_parsed && *camera_parsed == CameraType::Panoramic)
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

ValidConfig::ValidConfig(Config config) : config_(std::move(config))
{
  config_.validateOrThrow();
}

Config Config::viewChannel() const
{
  Config views = *this;
  views.lateral_shift = view_channel_shift;
  const DescriptorInfo* row = findDescriptor(descriptor);
  views.descriptor_bits = row && row->binary() ? view_channel_bits : 0;
  if (view_channel_consistent_frames > 0)
    views.consistent_frames = view_channel_consistent_frames;
  views.view_channel_shift = 0.0;
  views.view_channel_bits = 0;
  views.view_channel_consistent_frames = 0;
  return views;
}

Config Config::paper()
{
  Config c;
  c.descriptor = "LDB";
  c.sequence_length = 1;
  c.min_uniqueness = 0.0;
  c.max_pace = 1;
  c.lateral_shift = 0.0;
  c.descriptor_bits = 0;
  c.view_channel_shift = 0.0;
  c.view_channel_bits = 0;
  c.view_channel_consistent_frames = 0;
  c.pace_tolerance = 1;
  c.slip_penalty = 0.0;
  c.pace_prior = 0.0;
  c.standstill_distance = 0.0;
  c.stop_distance = 0.0;
  c.consistent_frames = 4;
  c.min_candidates = 60;
  c.min_loop_sequence_length = 0;
  c.continue_uniqueness = 1.0;
  c.confirm_frames = 0;
  c.run_start_tolerance = -1;
  c.run_resume_frames = 0;
  c.short_map_exclusion = -1;
  c.min_relief = 0.0;
  c.verified_min_uniqueness = -1.0;
  return c;
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
