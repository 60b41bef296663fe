#include "offline_options.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "openable/error.h"

namespace offline
{
namespace
{
namespace fs = std::filesystem;
using openable::Error;

const char* kUsage =
    "usage: openable_offline --config FILE.yaml --reference PATH [--query PATH] --output DIR\n"
    "                        [--set key=value]... [--reference-right PATH] [--query-right PATH]\n"
    "                        [--ground-truth-tolerance T] [--quiet]\n"
    "                        [--camera-info FILE [--verify-optional]]\n"
    "                        [--map-in FILE] [--map-out FILE] [--session NAME]\n"
    "                        [--poses FILE [--keyframe-distance M] [--keyframe-angle RAD]]\n"
    "\n"
    "PATH is a folder of images (in name order, numbers compared as numbers: image2 before image10) or a\n"
    "video file.\n"
    "  --quiet          : no progress and no input summary on stderr\n"
    "  --reference only : loop-closure mode, each frame against the stream's own past\n"
    "  --query          : localisation mode, each query frame against the reference traversal\n"
    "  --set key=value  : override a configuration key (repeatable)\n"
    "  --*-right        : right images of a rectified stereo pair (camera_type stereo)\n"
    "  --ground-truth-tolerance T : the traversals are frame-aligned; report the fraction of frames\n"
    "                     whose best match is within T frames of the same index\n"
    "  --camera-info FILE : verify every loop closure geometrically, as a nodelet with ~verify: FILE is a ROS\n"
    "                     camera_info YAML (projection_matrix: rectified images) or a KITTI calib.txt (P1: a\n"
    "                     stereo baseline). Loops that fail are failed_verification, unverifiable ones\n"
    "                     unverified; neither is published. Loop-closure mode only (a map keeps no features).\n"
    "                     The verifier's thresholds are the verify_* keys (--set verify_min_inliers=20).\n"
    "  --verify-optional  : unverifiable loops go out without a pose (~verify_required false)\n"
    "  --map-in FILE    : continue a saved map: the stream becomes a new session, matched against every\n"
    "                     session of the map and its own past (loop-closure mode only). Frame numbers in the\n"
    "                     outputs then count from the map's next id, as if the stream followed the map.\n"
    "  --map-out FILE   : save the map (every session, the stream's included; in localisation mode the\n"
    "                     reference) after a successful run\n"
    "  --session NAME   : the stream's session name in the map (default: the stream's file or folder name)\n"
    "  --poses FILE     : the camera's odometry, one pose per frame of the stream (--query in localisation\n"
    "                     mode) in frame order: a KITTI pose file (12 numbers a line, row-major 3x4 [R|t]) or\n"
    "                     a TUM trajectory (stamp tx ty tz qx qy qz qw, '#' comments; the stamps become the\n"
    "                     frames' stamps). Frames are stored as keyframes, as a nodelet with ~fixed_frame and\n"
    "                     ~keyframe_distance does; the others are not_keyframe in decisions.csv\n"
    "  --keyframe-distance M : with --poses, metres the camera must move before a frame is stored (default 1;\n"
    "                     0: every frame)\n"
    "  --keyframe-angle RAD  : with --poses, or turn this many radians (default 0: turning alone never does)\n"
    "Writes into DIR: distance_matrix.npy, distance_matrix.png, distance_matrix_thresholded.png (with a\n"
    "threshold), loop_closures.csv (published loop closures, with query_session,match_session), decisions.csv\n"
    "(every frame), timings.json.\n";



/// A number of metres or radians from the command line, in [0, max]; `expected` says so in the error.
double nonNegative(const std::string& option, const std::string& value, double max, const char* expected)
{
  size_t used = 0;
  double v = -1.0;
  try
  {
    v = std::stod(value, &used);
  }
  catch (const std::exception&)
  {
  }
  if (used != value.size() || !std::isfinite(v) || v < 0.0 || v > max)
    throw Error(option + ": '" + value + "' is not allowed; expected " + expected);
  return v;
}
}  // namespace

/// The default session name: the stream's file or folder name.
std::string nameOfPath(const std::string& path)
{
  fs::path p = fs::path(path).lexically_normal();
  if (p.filename().empty())
    p = p.parent_path();
  const std::string name = p.filename().string();
  return name.empty() || name == "." || name == ".." ? "stream" : name;
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "--quiet")
    {
      o.quiet = true;
      continue;
    }
    if (arg == "--verify-optional")
    {
      o.verify_optional = true;
      continue;
    }
    if (arg == "--help" || arg == "-h")
    {
      std::cout << kUsage;
      std::exit(0);
    }
    if (i + 1 >= argc)
      throw Error("option " + arg + " needs a value (see --help)");
    const std::string value = argv[++i];
    if (arg == "--config")
      o.config_path = value;
    else if (arg == "--reference")
      o.reference = value;
    else if (arg == "--reference-right")
      o.reference_right = value;
    else if (arg == "--query")
      o.query = value;
    else if (arg == "--query-right")
      o.query_right = value;
    else if (arg == "--output")
      o.output = value;
    else if (arg == "--set")
      o.sets.push_back(value);
    else if (arg == "--camera-info")
      o.camera_info = value;
    else if (arg == "--map-in")
      o.map_in = value;
    else if (arg == "--map-out")
      o.map_out = value;
    else if (arg == "--session")
      o.session = value;
    else if (arg == "--poses")
      o.poses = value;
    else if (arg == "--keyframe-distance")
      o.keyframe_distance = nonNegative(arg, value, 1e6, "metres in [0, 1e6] (0: every frame)");
    else if (arg == "--keyframe-angle")
      o.keyframe_angle = nonNegative(arg, value, M_PI, "radians in [0, pi] (0: off)");
    else if (arg == "--ground-truth-tolerance")
    {
      size_t used = 0;
      long t = -1;
      try
      {
        t = std::stol(value, &used);
      }
      catch (const std::exception&)
      {
      }
      if (used != value.size() || t < 0 || t > 1000000000)
        throw Error("--ground-truth-tolerance: '" + value +
                    "' is not allowed; expected frames, an integer in [0, 1e9]");
      o.ground_truth_tolerance = static_cast<int>(t);
    }
    else
      throw Error("unknown option '" + arg + "' (see --help)");
  }
  if (o.config_path.empty() || o.reference.empty() || o.output.empty())
    throw Error("--config, --reference and --output are required (see --help)");
  if (o.verify_optional && o.camera_info.empty())
    throw Error("--verify-optional needs --camera-info (there is nothing to verify without a camera)");
  if (!o.camera_info.empty() && !o.query.empty())
    throw Error(
        "--camera-info verifies loop closures within one stream; with --query the reference map keeps no features "
        "to verify against (drop --query or --camera-info)");
  if (!o.map_in.empty() && !o.query.empty())
    throw Error("--map-in continues a map with one stream; with --query the reference traversal is the map "
                "(drop --query or --map-in)");
  if (o.poses.empty() && (o.keyframe_distance >= 0.0 || o.keyframe_angle >= 0.0))
    throw Error("--keyframe-distance / --keyframe-angle need --poses (the motion comes from the poses)");
  if (!o.poses.empty())
  {
    // Unless told otherwise: a keyframe every metre travelled; turning on the spot makes none.
    o.keyframe_distance = o.keyframe_distance < 0.0 ? 1.0 : o.keyframe_distance;
    o.keyframe_angle = o.keyframe_angle < 0.0 ? 0.0 : o.keyframe_angle;
  }
  if (o.session.empty())
    o.session = nameOfPath(o.reference);
  return o;
}

}  // namespace offline
