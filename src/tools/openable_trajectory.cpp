// openable_trajectory: loop closures drawn on the trajectory (PNG, CSV, KML for Google Earth); see --help.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
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

using openable::cli::UsageError;

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

/// --size WxH: width and height in pixels, from 320x240 to 20000x20000.
cv::Size parseSize(const std::string& text)
{
  const size_t x = text.find('x');
  const std::optional<long long> width = openable::cli::toInteger(text.substr(0, x));
  const std::optional<long long> height = x == std::string::npos ? std::nullopt
                                                                 : openable::cli::toInteger(text.substr(x + 1));
  if (!width || !height || *width < 320 || *height < 240 || *width > 20000 || *height > 20000)
    throw UsageError("--size: '" + text + "' is not allowed; expected WxH pixels, e.g. 1000x800, from 320x240 to " +
                     "20000x20000");
  return cv::Size(static_cast<int>(*width), static_cast<int>(*height));
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  openable::cli::Arguments args(argc, argv);
  while (args.next())
  {
    if (args.isHelp())
      o.help = true;
    else if (args.is("--loops"))
      o.loops = args.value();
    else if (args.is("--poses"))
      o.poses = args.value();
    else if (args.is("--geo"))
      o.geo = args.value();
    else if (args.is("--times"))
      o.times = args.value();
    else if (args.is("--pairs"))
      o.pairs = args.value();
    else if (args.is("--pair-tolerance"))
      o.pair_tolerance = args.integer(0, 1000000000, "frames");
    else if (args.is("--distance"))
    {
      o.distance = args.positive("metres");
      o.pose_truth_set = true;
    }
    else if (args.is("--exclusion"))
    {
      o.exclusion = args.integer(0, 1000000000, "frames");
      o.pose_truth_set = true;
    }
    else if (args.is("--output"))
      o.output = args.value();
    else if (args.is("--title"))
      o.title = args.value();
    else if (args.is("--size"))
      o.size = parseSize(args.value());
    else
      args.unknown();
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
  return openable::cli::runTool({"openable_trajectory"}, argc, argv,
                                [](int argc, char** argv)
                                {
                                  const Options options = parseArguments(argc, argv);
                                  if (options.help || argc == 1)
                                  {
                                    std::cout << kUsage;
                                    return argc == 1 ? 2 : 0;
                                  }
                                  return run(options);
                                });
}
