// The key table of Config: one row per key (name, type, description, range, live / describes flags) and
// how each is read from and written to text. Every list of keys (YAML, --set, ROS parameters,
// cfg/Detector.cfg, the documentation) derives from or is tested against these rows.
#include "config_keys.h"

#include <cstdint>
#include <sstream>
#include <string>

#include "openable/error.h"

namespace openable
{
namespace config_keys
{
namespace
{
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
}  // namespace

std::string trim(const std::string& s)
{
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos)
    return "";
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

std::string formatDouble(double v)
{
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
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
      makeKey("lateral_shift",
              "fraction of the image width a revisit may see the scene shifted sideways: places are described from the "
              "centre (1 - 2 x lateral_shift of the width), queries also shifted left and right, the smallest distance "
              "counts (max_pace > 1); 0 = whole image. Mono images only: not panoramas, not D-LDB",
              &Config::lateral_shift).range(0, 0.25).describes(),
      makeKey("descriptor", "LDB | D-LDB | BRIEF | BRISK | ORB | FREAK | HOG-B | SIFT | SURF | HOG", &Config::descriptor).describes(),
      makeKey("descriptor_bits",
              "a binary descriptor keeps this many of its bits, evenly spread (0 = all): fewer bytes a place",
              &Config::descriptor_bits).range(0, 65536).describes(),
      makeKey("view_channel_shift",
              "a second channel: the image's centre crop (1 - 2 x this of the width) matched with the frame's views "
              "shifted left and right, its own sequences and decision; a frame's loop is the whole image's, else this "
              "channel's (0 = off). Loop-closure mode of a new stream, images with views: not a panorama, D-LDB or lateral_shift",
              &Config::view_channel_shift).range(0, 0.25),
      makeKey("view_channel_bits", "descriptor_bits of the view channel's places (0 = all)",
              &Config::view_channel_bits).range(0, 65536),
      makeKey("view_channel_consistent_frames", "consistent_frames of the view channel (0 = consistent_frames)",
              &Config::view_channel_consistent_frames).range(0, 1000),
      makeKey("sequence_length", "L: frames per sequence (1 = single images)", &Config::sequence_length).range(1, 10000).live(),
      makeKey("min_sequence_length",
              "sequences of fewer frames are never candidates; 0 = only full sequences of "
              "sequence_length frames (1 = any, the mean of the available terms)",
              &Config::min_sequence_length).range(0, 10000).live(),
      makeKey("min_loop_sequence_length",
              "loop-closure mode: sequences of fewer frames (at most sequence_length) are never candidates; "
              "0 = only full sequences of sequence_length frames",
              &Config::min_loop_sequence_length).range(0, 10000).live(),
      makeKey("threshold", "accept when normalised distance <= threshold (0..1); -1 = no distance gate",
              &Config::threshold).range(-1, 1).minusOneIsOff().live(),
      makeKey("exclusion_window", "loop-closure mode: most recent frames never matched (frames)",
              &Config::exclusion_window).range(0, 100000000).live(),
      makeKey("short_map_exclusion",
              "loop-closure mode: while the stream's own map holds at most 2 x exclusion_window + sequence_length "
              "frames, its own candidates come from a second matcher leaving out only this many recent frames "
              "(-1 = off; off also at exclusion_window or more)",
              &Config::short_map_exclusion).range(-1, 100000000).minusOneIsOff(),
      makeKey("top_k", "candidates reported per frame", &Config::top_k).range(1, 1000).live(),
      makeKey("min_uniqueness", "accept only when 1 - best / second best >= this (0 = off)", &Config::min_uniqueness).range(0, 1).live(),
      makeKey("uniqueness_window", "frames around the best match skipped when finding the second best (frames)",
              &Config::uniqueness_window).range(0, 100000).live(),
      makeKey("bidirectional", "also match sequences travelled in the opposite direction", &Config::bidirectional).live(),
      makeKey("max_history", "frames kept in the loop-closure history (0 = unbounded)", &Config::max_history).range(0, 100000000),
      makeKey("max_pace",
              "places a revisit may advance per frame: 1 = the first pass's pace only (the paper's sequences); "
              "more = any pace from a stop up to this",
              &Config::max_pace).range(1, 64).live(),
      makeKey("pace_penalty",
              "cost of a change of pace, in standard deviations of a sequence's distance under noise (max_pace > 1)",
              &Config::pace_penalty).range(0, 100).live(),
      makeKey("slip_penalty",
              "cost of a sequence moving one place off its line in a frame (a revisit between two of the paces "
              "followed, or drifting), as a fraction of pace_penalty; 0 = never (max_pace > 1)",
              &Config::slip_penalty).range(0, 10).live(),
      makeKey("pace_prior",
              "while no loop closure is published, what a sequence at a pace 30 % or more from the first pass's pays "
              "to be its place's best, as a fraction of pace_penalty (less nearer 1x); 0 = every pace alike (max_pace > 1)",
              &Config::pace_prior).range(0, 10).live(),
      makeKey("pace_tolerance",
              "places a sequence may be off its line in each frame, for paces between the ones followed (max_pace > 1)",
              &Config::pace_tolerance).range(0, 2).live(),
      makeKey("screen_places",
              "a row of more places than this is screened: one cost a place follows any pace, and only the chunks of "
              "2048 places it ranks first (a quarter of this many places) keep every pace's costs; 0 = every place "
              "always (max_pace > 1)",
              &Config::screen_places).range(0, 1000000000),
      makeKey("standstill_distance",
              "a frame closer than this (normalised distance) to the last stored frame is the camera standing still: "
              "not stored, not matched, it repeats the last decision (0 = off)",
              &Config::standstill_distance).range(0, 1).live(),
      makeKey("stop_distance",
              "a frame closer than this (normalised distance) to the first frame of a still stretch, or to the last "
              "stored frame, is within a still camera's noise; after stop_frames such frames in a row the camera has "
              "stopped: not stored, not matched, no loop closure (0 = off)",
              &Config::stop_distance).range(0, 1).live(),
      makeKey("stop_frames",
              "frames in a row within stop_distance that are still stored and matched before the camera counts as "
              "stopped (a slow camera in a featureless scene moves that long)",
              &Config::stop_frames).range(1, 100000).live(),
      makeKey("min_candidates",
              "loop-closure decision: fewer candidate places than this is 'too early' (21 = 2 x uniqueness_window + 1: "
              "a best match has a rival outside the window unless it is the middle one)",
              &Config::min_candidates).range(0, 100000000).live(),
      makeKey("consistent_frames",
              "loop-closure decision: consecutive frames that must pass the gates with matches advancing "
              "together (1 = off)",
              &Config::consistent_frames).range(1, 1000).live(),
      makeKey("consistency_tolerance",
              "loop-closure decision: frames a match may deviate from advancing one place per frame",
              &Config::consistency_tolerance).range(0, 1000).live(),
      makeKey("continue_uniqueness",
              "loop-closure decision: a published run goes on through frames whose uniqueness is at least this "
              "(below min_uniqueness) while their matches keep to its line (>= min_uniqueness = off)",
              &Config::continue_uniqueness).range(0, 1).live(),
      makeKey("run_start_tolerance",
              "loop-closure decision: once a run is consistent, the frames before it (its first frames, and not-unique "
              "ones before them) whose matches lie within this many places of its line, extended back, are published "
              "too, late, with their own stamps (-1 = off)",
              &Config::run_start_tolerance).range(-1, 1000).minusOneIsOff().live(),
      makeKey("run_resume_frames",
              "loop-closure decision: for this many frames after a published run breaks, a frame whose match lies on "
              "its line, extended (within consistency_tolerance), at continue_uniqueness resumes it (0 = off)",
              &Config::run_resume_frames).range(0, 100000).live(),
      makeKey("min_relief",
              "loop-closure decision: no loop closure where the places around the best match look alike: the median "
              "over the last 5 frames of how much their distances to the places within uniqueness_window of the match "
              "vary, in standard deviations of the row, below this (0 = off; needs max_pace > 1)",
              &Config::min_relief).range(0, 100).live(),
      makeKey("confirm_frames",
              "loop-closure decision: a loop closure is published once this many more stored frames go on with its "
              "run; it arrives that many keyframes late, with its own stamp (0 = at once)",
              &Config::confirm_frames).range(0, 1000).live(),
      makeKey("verified_min_uniqueness",
              "loop-closure decision with geometric verification: a frame below min_uniqueness (or with fewer than "
              "min_candidates places) joins its run when verification accepts its best match and its uniqueness is "
              "at least this; the run must still be consistent (-1 = off)",
              &Config::verified_min_uniqueness).range(-1, 1).minusOneIsOff().live(),
      makeKey("verification_veto",
              "loop-closure decision with geometric verification: a loop closure that verification rejects is not "
              "published (false: appearance decides it, published without a relative pose)",
              &Config::verification_veto).live(),
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
      // Geometric verification. Low ends as VerifierParams::validate() has them; the high ends are sanity
      // bounds of this table (VerifierParams has none). Not live: the verifier is built once, with the camera.
      makeKey("verify_max_features", "ORB features per frame (the bound on per-frame memory)",
              &Config::verify_max_features).range(50, 100000),
      makeKey("verify_ratio", "Lowe ratio test: best / second-best Hamming distance must be below this",
              &Config::verify_ratio).range(0, 1).aboveMin(),
      makeKey("verify_max_hamming", "a feature match with more differing bits (of 256) is discarded (bits)",
              &Config::verify_max_hamming).range(1, 256),
      makeKey("verify_min_inliers", "fewer RANSAC inliers (or ratio-test matches, or keypoints): rejected",
              &Config::verify_min_inliers).range(8, 100000),
      makeKey("verify_ransac_threshold_px",
              "inlier threshold: reprojection (stereo PnP) or Sampson (mono) error (pixels)",
              &Config::verify_ransac_threshold_px).range(0, 100).aboveMin(),
      makeKey("verify_ransac_confidence", "RANSAC confidence", &Config::verify_ransac_confidence)
          .range(0, 1).aboveMin().belowMax(),
      makeKey("verify_ransac_iterations", "PnP RANSAC iterations",
              &Config::verify_ransac_iterations).range(10, 1000000),
      makeKey("verify_min_parallax_deg", "mono: less median parallax after derotation is pure rotation (degrees)",
              &Config::verify_min_parallax_deg).range(0, 180),
      makeKey("verify_identical_max_flow_px", "less median motion of the matches is the same image twice (pixels)",
              &Config::verify_identical_max_flow_px).range(0, 1000),
      makeKey("verify_stereo_max_row_diff_px", "stereo depth: |y_left - y_right| allowed at octave 0 (pixels)",
              &Config::verify_stereo_max_row_diff_px).range(0, 100).aboveMin(),
      makeKey("verify_stereo_min_disparity_px", "stereo depth: a smaller disparity (too far) gives no depth (pixels)",
              &Config::verify_stereo_min_disparity_px).range(0, 10000).aboveMin(),
      makeKey("verify_stereo_max_disparity_px", "stereo depth: a larger disparity gives no depth (pixels)",
              &Config::verify_stereo_max_disparity_px).range(0, 10000).aboveMin(),
      makeKey("verify_stereo_max_hamming", "stereo depth: left/right descriptor distance allowed (bits)",
              &Config::verify_stereo_max_hamming).range(1, 256),
      makeKey("verify_min_stereo_points", "stereo: fewer match-frame keypoints with depth: rejected",
              &Config::verify_min_stereo_points).range(4, 100000),
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

}  // namespace config_keys

using config_keys::table;

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
  config_keys::find(key).set(*this, value);
}

std::string Config::get(const std::string& key) const
{
  return config_keys::find(key).get(*this);
}

}  // namespace openable
