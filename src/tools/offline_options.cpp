#include "offline_options.h"

#include <cmath>
#include <filesystem>

#include "cli.h"

namespace offline
{
namespace fs = std::filesystem;
using openable::cli::UsageError;

const char* const kUsage =
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
    "                     To add recall with it: --set verification_veto=false (appearance decides what it\n"
    "                     rejects); frames below min_uniqueness are verified too (verified_min_uniqueness)\n"
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
    "(every frame; inliers: the verifier's for the best match, -1 where it did not run), timings.json.\n";

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
  openable::cli::Arguments args(argc, argv);
  while (args.next())
  {
    if (args.isHelp())
    {
      o.help = true;  // the usage, whatever else is given
      return o;
    }
    if (args.is("--quiet"))
      o.quiet = true;
    else if (args.is("--verify-optional"))
      o.verify_optional = true;
    else if (args.is("--config"))
      o.config_path = args.value();
    else if (args.is("--reference"))
      o.reference = args.value();
    else if (args.is("--reference-right"))
      o.reference_right = args.value();
    else if (args.is("--query"))
      o.query = args.value();
    else if (args.is("--query-right"))
      o.query_right = args.value();
    else if (args.is("--output"))
      o.output = args.value();
    else if (args.is("--set"))
      o.sets.push_back(args.value());
    else if (args.is("--camera-info"))
      o.camera_info = args.value();
    else if (args.is("--map-in"))
      o.map_in = args.value();
    else if (args.is("--map-out"))
      o.map_out = args.value();
    else if (args.is("--session"))
      o.session = args.value();
    else if (args.is("--poses"))
      o.poses = args.value();
    else if (args.is("--keyframe-distance"))
      o.keyframe_distance = args.number(0.0, 1e6, "metres; 0: every frame");
    else if (args.is("--keyframe-angle"))
      o.keyframe_angle = args.number(0.0, M_PI, "radians, pi at most; 0: off");
    else if (args.is("--ground-truth-tolerance"))
      o.ground_truth_tolerance = args.integer(0, 1000000000, "frames");
    else
      args.unknown();
  }
  if (o.config_path.empty() || o.reference.empty() || o.output.empty())
    throw UsageError("--config, --reference and --output are required (see --help)");
  if (o.verify_optional && o.camera_info.empty())
    throw UsageError("--verify-optional needs --camera-info (there is nothing to verify without a camera)");
  if (!o.camera_info.empty() && !o.query.empty())
    throw UsageError(
        "--camera-info verifies loop closures within one stream; with --query the reference map keeps no features "
        "to verify against (drop --query or --camera-info)");
  if (!o.map_in.empty() && !o.query.empty())
    throw UsageError("--map-in continues a map with one stream; with --query the reference traversal is the map "
                "(drop --query or --map-in)");
  if (o.poses.empty() && (o.keyframe_distance >= 0.0 || o.keyframe_angle >= 0.0))
    throw UsageError("--keyframe-distance / --keyframe-angle need --poses (the motion comes from the poses)");
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
