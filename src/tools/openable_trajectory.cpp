// openable_trajectory: loop closures drawn on the trajectory (PNG, CSV, KML for Google Earth); see --help.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "openable/io/atomic_file.h"
#include "openable/io/staged_output.h"
#include "openable/error.h"
#include "openable/evaluation/evaluation.h"
#include "openable/io/image_source.h"
#include "openable/evaluation/loop_list.h"
#include "openable/view/trajectory_export.h"
#include "openable/view/trajectory_plot.h"

namespace
{
namespace fs = std::filesystem;

const char kUsage[] = R"(openable_trajectory: loop closures drawn on the trajectory they were found on.

Usage:
  openable_trajectory --loops FILE --output DIR (--poses FILE | --geo FILE --pairs FILE)
                      [--poses FILE] [--geo FILE] [--times FILE]
                      [--pairs FILE [--pair-tolerance K] | --distance D --exclusion E]
                      [--title TEXT] [--size WxH]

Input:
  --loops FILE         detected loop closures: openable_offline's loop_closures.csv (header 'query,match,...')
                       or 'i j' lines (0-based frames, # comments), e.g. a published ground-truth file.
  --poses FILE         KITTI poses (row-major 3x4 [R|t] per line, camera frame: x right, y down, z forward).
  --geo FILE           geographic position per frame: CSV 'frame,stamp,latitude,longitude,altitude'.
  --times FILE         one stamp per frame in seconds (KITTI times.txt): the stamp column of the CSV.

Ground truth (colours each loop: green when it agrees, red when not), as openable_eval takes it:
  --pairs FILE         'i j' lines; a loop agrees when the file holds it in either direction.
  --pair-tolerance K   with --pairs: also within K frames of the listed match (default 0).
  --distance D         without --pairs: from the poses, positions closer than D metres (default 6) ...
  --exclusion E        ... and more than E frames apart (default 100).

Output (DIR is created if missing):
  trajectory.png       with --poses: the path seen from above (x right, z up; same scale on both axes,
                       metres), each loop a line between its two positions, a legend with the counts.
  trajectory.csv       with --poses: frame,stamp,x,y,z,loop_partner,loop_agrees (one line per frame).
  trajectory.kml       with --geo: the path as a LineString and each loop as a Placemark (Google Earth).
  --title TEXT         title of the picture (default: the loops file name).
  --size WxH           picture size in pixels (default 1000x800, at least 320x240).
Prints the number of loops, how many agree with the ground truth, and the files written.

Exit status: 0 on success, 1 with a one-line reason on stderr for bad input, 2 for bad usage.
)";

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

struct Options
{
  std::string loops, poses, geo, times, pairs, output, title;
  int pair_tolerance = 0;
  double distance = openable::kDefaultLoopDistance;
  int exclusion = openable::kDefaultLoopExclusion;
  bool pose_truth_set = false;
  cv::Size size = cv::Size(1000, 800);
  bool help = false;
};

double parseNumber(const std::string& flag, const std::string& text, double low)
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
  if (used == 0 || used != text.size() || !std::isfinite(value) || value < low)
    throw UsageError(flag + " expects a number >= " + std::to_string(static_cast<int>(low)) + ", got '" + text + "'");
  return value;
}

int parseCount(const std::string& flag, const std::string& text)
{
  const double value = parseNumber(flag, text, 0.0);
  if (value != std::floor(value) || value > 1e9)
    throw UsageError(flag + " expects a whole number >= 0, got '" + text + "'");
  return static_cast<int>(value);
}

cv::Size parseSize(const std::string& text)
{
  const size_t x = text.find('x');
  if (x == std::string::npos)
    throw UsageError("--size expects WxH, e.g. 1000x800, got '" + text + "'");
  const cv::Size size(parseCount("--size", text.substr(0, x)), parseCount("--size", text.substr(x + 1)));
  if (size.width < 320 || size.height < 240 || size.width > 20000 || size.height > 20000)
    throw UsageError("--size " + text + " is outside 320x240 .. 20000x20000");
  return size;
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string flag = argv[i];
    const auto value = [&]() -> std::string
    {
      if (i + 1 >= argc)
        throw UsageError(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--help" || flag == "-h")
      o.help = true;
    else if (flag == "--loops")
      o.loops = value();
    else if (flag == "--poses")
      o.poses = value();
    else if (flag == "--geo")
      o.geo = value();
    else if (flag == "--times")
      o.times = value();
    else if (flag == "--pairs")
      o.pairs = value();
    else if (flag == "--pair-tolerance")
      o.pair_tolerance = parseCount(flag, value());
    else if (flag == "--distance")
    {
      o.distance = parseNumber(flag, value(), 0.0);
      o.pose_truth_set = true;
      if (!(o.distance > 0.0))
        throw UsageError("--distance expects metres > 0");
    }
    else if (flag == "--exclusion")
    {
      o.exclusion = parseCount(flag, value());
      o.pose_truth_set = true;
    }
    else if (flag == "--output")
      o.output = value();
    else if (flag == "--title")
      o.title = value();
    else if (flag == "--size")
      o.size = parseSize(value());
    else
      throw UsageError("unknown argument '" + flag + "' (see --help)");
  }
  if (o.help)
    return o;
  if (o.loops.empty() || o.output.empty())
    throw UsageError("--loops and --output are required (see --help)");
  if (o.poses.empty() && o.geo.empty())
    throw UsageError("give --poses (picture and CSV) and/or --geo (KML)");
  if (!o.pairs.empty() && o.pose_truth_set)
    throw UsageError("give the ground truth as --pairs or as --distance/--exclusion, not both");
  if (o.pairs.empty() && o.poses.empty())
    throw UsageError("without --poses the ground truth must come from --pairs");
  if (!o.times.empty() && o.poses.empty())
    throw UsageError("--times gives the stamps of the CSV, which needs --poses");
  return o;
}

std::vector<double> loadTimes(const std::string& path)
{
  std::ifstream in(path);
  if (!in)
    throw openable::Error("times: cannot read '" + path + "'");
  std::vector<double> times;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#')
      continue;
    std::istringstream fields(line);
    double t = 0.0;
    std::string rest;
    if (!(fields >> t) || (fields >> rest) || !std::isfinite(t))
      throw openable::Error("times: '" + path + "' line " + std::to_string(number) + " is not one time in seconds: '" +
                            line + "'");
    times.push_back(t);
  }
  return times;
}

/// Stages the output file `name` (published with the others at the end of the run).
void writeText(openable::StagedOutput& output, const fs::path& dir, const std::string& name, const std::string& text)
{
  openable::writeFileAtomically(output.path(name), text);
  std::cout << "wrote " << (dir / name).string() << "\n";
}

int run(const Options& o)
{
  std::vector<openable::LoopPair> loops = openable::loadLoopPairs(o.loops);
  std::vector<cv::Vec3d> positions;
  if (!o.poses.empty())
    positions = openable::loadKittiPositions(o.poses);
  const openable::GroundTruth truth = o.pairs.empty() ? openable::posesGroundTruth(positions, o.distance, o.exclusion)
                                                      : openable::loadPairsGroundTruth(o.pairs, o.pair_tolerance);
  openable::judgeLoops(loops, truth);
  // Every input is read before anything is printed or written: a bad one leaves no half-done output.
  std::vector<double> stamps;
  if (!o.times.empty())
  {
    stamps = loadTimes(o.times);
    // times.txt of a whole sequence may list more frames than the poses cover: keep the first ones.
    if (stamps.size() < positions.size())
      throw openable::Error("times: '" + o.times + "' has " + std::to_string(stamps.size()) + " stamps for " +
                            std::to_string(positions.size()) + " poses");
    stamps.resize(positions.size());
  }
  const std::map<int, openable::GeoPosition> geo =
      o.geo.empty() ? std::map<int, openable::GeoPosition>() : openable::loadGeoPositions(o.geo);
  size_t agreeing = 0;
  for (const auto& loop : loops)
    agreeing += loop.agrees ? 1 : 0;
  openable::StagedOutput output(o.output, "openable_trajectory");  // one set: a failed run leaves the earlier one
  const std::string title = o.title.empty() ? fs::path(o.loops).filename().string() : o.title;
  std::cout << "loops: " << loops.size() << "\nagree with the ground truth: " << agreeing
            << "\ndisagree: " << loops.size() - agreeing << "\nground truth: " << truth.description() << "\n";

  if (!positions.empty())
  {
    const openable::TrajectoryPlot plot(positions, o.size);
    std::vector<unsigned char> png;
    cv::imencode(".png", plot.draw(loops, title), png);
    writeText(output, o.output, "trajectory.png", std::string(png.begin(), png.end()));
    writeText(output, o.output, "trajectory.csv", openable::trajectoryCsv(positions, stamps, loops));
  }
  if (!o.geo.empty())
  {
    size_t skipped = 0;
    const std::string kml = openable::trajectoryKml(geo, loops, title, &skipped);
    if (skipped > 0)
      std::cerr << "openable_trajectory: " << skipped << " loops name a frame without geographic position in '" << o.geo
                << "'; left out of the KML\n";
    writeText(output, o.output, "trajectory.kml", kml);
  }
  output.publish();
  return 0;
}

}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    options = parseArguments(argc, argv);
    if (options.help || argc == 1)
    {
      std::cout << kUsage;
      return argc == 1 ? 2 : 0;
    }
  }
  catch (const UsageError& e)
  {
    std::cerr << "openable_trajectory: " << e.what() << "\n";
    return 2;
  }
  try
  {
    return run(options);
  }
  catch (const std::exception& e)
  {
    std::string reason = e.what();
    for (char& c : reason)
      c = (c == '\n') ? ' ' : c;
    std::cerr << "openable_trajectory: error: " << reason << "\n";
    return 1;
  }
}
