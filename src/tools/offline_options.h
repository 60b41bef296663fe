#pragma once
// openable_offline's command line: its options, their parsing and checks (the run is in openable_offline.cpp).

#include <string>
#include <vector>

namespace offline
{
struct Options
{
  std::string config_path;
  std::string reference, reference_right, query, query_right, output;
  std::vector<std::string> sets;
  int ground_truth_tolerance = -1;
  bool quiet = false;
  std::string camera_info;  // non-empty: verify, as a nodelet with ~verify and this camera_info
  bool verify_optional = false;
  std::string map_in, map_out, session;
  std::string poses;  // non-empty: keyframes from this trajectory, as a nodelet with ~fixed_frame
  double keyframe_distance = -1.0, keyframe_angle = -1.0;  // < 0: not given (defaults 1 m and 0 with --poses)
  bool help = false;  // --help: print kUsage, nothing else is read
};

extern const char* const kUsage;

/// The default session name: the stream's file or folder name.
std::string nameOfPath(const std::string& path);

/// The options of argv (only `help` with --help); throws openable::cli::UsageError on bad usage.
Options parseArguments(int argc, char** argv);

}  // namespace offline
