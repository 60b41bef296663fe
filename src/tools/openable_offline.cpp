// openable_offline: the OpenABLE toolbox as a command-line program.
//
//   openable_offline --config FILE.yaml --reference PATH [--query PATH] --output DIR [--set key=value]...
//                    [--reference-right PATH] [--query-right PATH] [--ground-truth-tolerance T]
//
// With --reference only, the stream is matched against its own past (loop-closure mode); with --query,
// every query frame is matched against the reference traversal (localisation mode). See --help.

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/error.h"
#include "openable/frame_describer.h"
#include "openable/image_source.h"
#include "openable/loop_detector.h"
#include "openable/npy.h"
#include "openable/render.h"
#include "openable/stereo.h"

namespace fs = std::filesystem;
using openable::Error;

namespace
{
const char* kUsage =
    "usage: openable_offline --config FILE.yaml --reference PATH [--query PATH] --output DIR\n"
    "                        [--set key=value]... [--reference-right PATH] [--query-right PATH]\n"
    "                        [--ground-truth-tolerance T]\n"
    "\n"
    "PATH is a folder of images (sorted by file name) or a video file.\n"
    "  --reference only : loop-closure mode, each frame against the stream's own past\n"
    "  --query          : localisation mode, each query frame against the reference traversal\n"
    "  --set key=value  : override a configuration key (repeatable)\n"
    "  --*-right        : right images of a rectified stereo pair (camera_type stereo)\n"
    "  --ground-truth-tolerance T : the traversals are frame-aligned; report the fraction of frames\n"
    "                     whose best match is within T frames of the same index\n"
    "Writes into DIR: distance_matrix.npy, distance_matrix.png, distance_matrix_thresholded.png (with a\n"
    "threshold), loop_closures.csv, timings.json.\n";

struct Options
{
  std::string config_path;
  std::string reference, reference_right, query, query_right, output;
  std::vector<std::string> sets;
  int ground_truth_tolerance = -1;
};

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
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
    else if (arg == "--ground-truth-tolerance")
      o.ground_truth_tolerance = std::stoi(value);
    else
      throw Error("unknown option '" + arg + "' (see --help)");
  }
  if (o.config_path.empty() || o.reference.empty() || o.output.empty())
    throw Error("--config, --reference and --output are required (see --help)");
  return o;
}

openable::Config loadConfig(const Options& o)
{
  openable::Config config = openable::Config::fromYamlFile(o.config_path);
  for (const auto& assignment : o.sets)
  {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos)
      throw Error("--set expects key=value, got '" + assignment + "'");
    config.set(assignment.substr(0, eq), assignment.substr(eq + 1));
  }
  config.validateOrThrow();
  const bool stereo = config.camera_type == "stereo";
  if (stereo && (o.reference_right.empty() || (!o.query.empty() && o.query_right.empty())))
    throw Error("camera_type stereo needs --reference-right (and --query-right with --query)");
  if (!stereo && (!o.reference_right.empty() || !o.query_right.empty()))
    throw Error("--reference-right / --query-right need camera_type stereo");
  return config;
}

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Timings
{
  double read = 0, preprocess = 0, describe = 0, match = 0;
  size_t frames = 0;
};

/// Reads a traversal (and its right images in stereo mode) and describes every frame. Unreadable frames
/// are reported and left out; `indices` keeps the file index of each described frame.
class TraversalReader
{
public:
  TraversalReader(const std::string& path, const std::string& right_path, const openable::FrameDescriber& describer,
                  const openable::Config& config)
    : source_(path), describer_(describer), config_(config)
  {
    if (!right_path.empty())
    {
      right_ = std::make_unique<openable::ImageSource>(right_path);
      if (right_->size() != source_.size())
        throw Error("left '" + path + "' has " + std::to_string(source_.size()) + " frames but right '" + right_path +
                    "' has " + std::to_string(right_->size()));
    }
  }

  size_t size() const
  {
    return source_.size();
  }

  /// Next frame's descriptor; false at the end. `described` is false for an unreadable frame.
  bool next(openable::FrameDescriptor& descriptor, std::string& name, bool& described, Timings& t)
  {
    cv::Mat image, right;
    auto start = Clock::now();
    if (!source_.next(image, name))
      return false;
    std::string right_name;
    if (right_)
      right_->next(right, right_name);
    t.read += msSince(start);
    described = false;
    try
    {
      start = Clock::now();
      std::vector<openable::Patch> patches;
      if (right_)
      {
        openable::checkStereoPair(image, right);
        patches =
            describer_.preprocessor().patchesWithDisparity(image, openable::disparityFromPair(image, right, config_));
      }
      else
        patches = describer_.preprocessor().patches(image);
      t.preprocess += msSince(start);
      start = Clock::now();
      descriptor = describer_.describe(patches);
      t.describe += msSince(start);
      described = true;
    }
    catch (const Error& e)
    {
      std::cerr << "warning: skipping " << name << ": " << e.what() << "\n";
    }
    catch (const cv::Exception& e)
    {
      std::cerr << "warning: skipping " << name << ": " << e.what() << "\n";
    }
    return true;
  }

private:
  openable::ImageSource source_;
  std::unique_ptr<openable::ImageSource> right_;
  const openable::FrameDescriber& describer_;
  const openable::Config& config_;
};

void writePng(const std::string& path, const cv::Mat& image)
{
  // Small matrices are enlarged (nearest neighbour: one cell stays one colour) so they can be seen.
  cv::Mat shown = image;
  const int longest = std::max(image.cols, image.rows);
  if (longest > 0 && longest < 600)
  {
    const int scale = (600 + longest - 1) / longest;
    cv::resize(image, shown, cv::Size(), scale, scale, cv::INTER_NEAREST);
  }
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", shown, bytes))
    throw Error("cannot encode " + path);
  openable::writeFileAtomically(path, std::string(bytes.begin(), bytes.end()));
}

std::string jsonStage(const char* name, double total, size_t frames)
{
  std::ostringstream out;
  out << std::fixed << std::setprecision(4) << "  \"" << name << "\": {\"total_ms\": " << total
      << ", \"per_frame_ms\": " << (frames ? total / frames : 0.0) << "}";
  return out.str();
}

int run(const Options& options)
{
  const openable::Config config = loadConfig(options);
  const openable::FrameDescriber describer(config);
  std::error_code ec;
  fs::create_directories(options.output, ec);
  if (!fs::is_directory(options.output))
    throw Error("cannot create output folder '" + options.output + "'");
  {
    // Fail now, not after minutes of work, when the folder cannot be written.
    const std::string probe = (fs::path(options.output) / ".openable_write_test").string();
    openable::writeFileAtomically(probe, "");
    fs::remove(probe, ec);
  }

  const bool localisation = !options.query.empty();
  Timings timings;
  TraversalReader reference(options.reference, options.reference_right, describer, config);
  std::unique_ptr<openable::LoopDetector> detector;
  std::vector<long> reference_file_of;  // database position -> file index
  openable::FrameDescriptor descriptor;
  std::string name;
  bool described = false;

  if (localisation)
  {
    openable::PlaceDatabase map(describer.layout(), 0, config.toYaml());
    for (long file = 0; reference.next(descriptor, name, described, timings); ++file)
      if (described)
      {
        openable::FrameInfo info;
        info.source = name;
        map.add(descriptor, info);
        reference_file_of.push_back(file);
      }
    if (map.empty())
      throw Error("no reference frame could be described in '" + options.reference + "'");
    timings.frames += map.size();
    detector = std::make_unique<openable::LoopDetector>(config, std::move(map));
  }
  else
  {
    detector = std::make_unique<openable::LoopDetector>(config);
  }

  TraversalReader* stream = &reference;
  std::unique_ptr<TraversalReader> query;
  if (localisation)
  {
    query = std::make_unique<TraversalReader>(options.query, options.query_right, describer, config);
    stream = query.get();
  }
  const size_t columns = reference.size();
  const size_t rows = stream->size();
  cv::Mat matrix(static_cast<int>(rows), static_cast<int>(columns), CV_32F, cv::Scalar(std::nanf("")));

  std::ostringstream csv;
  const bool panoramic = config.camera_type == "panoramic";
  csv << "query,match,distance" << (panoramic ? ",direction,shift" : "") << "\n";
  size_t matches = 0, truth_checked = 0, truth_hits = 0, matches_correct = 0;
  // With a threshold or a uniqueness bound, only accepted loop closures are listed; with neither, every
  // frame's best match.
  const bool gated = config.threshold >= 0 || config.min_uniqueness > 0;
  std::vector<float> row;
  std::vector<long> stream_file_of;  // loop-closure mode: database position -> file index
  for (long file = 0; stream->next(descriptor, name, described, timings); ++file)
  {
    if (!described || file >= matrix.rows)
      continue;
    ++timings.frames;
    const auto start = Clock::now();
    openable::FrameInfo info;
    info.source = name;
    const openable::Detection d = detector->process(descriptor, info);
    detector->lastRow(row);
    timings.match += msSince(start);
    if (!localisation)
      stream_file_of.push_back(file);
    const std::vector<long>& file_of = localisation ? reference_file_of : stream_file_of;
    float* out = matrix.ptr<float>(static_cast<int>(file));
    for (size_t p = 0; p < row.size() && p < file_of.size(); ++p)
      out[file_of[p]] = row[p];
    if (!d.has_candidates)
      continue;
    const long match = file_of[d.best.position];
    if (options.ground_truth_tolerance >= 0)
    {
      ++truth_checked;
      truth_hits += std::labs(match - file) <= options.ground_truth_tolerance ? 1 : 0;
    }
    if (gated && !d.accepted)
      continue;
    ++matches;
    matches_correct += std::labs(match - file) <= std::max(0, options.ground_truth_tolerance) ? 1 : 0;
    csv << file << "," << match << "," << std::setprecision(6) << d.best.distance;
    if (panoramic)
      csv << "," << int(d.best.direction) << "," << d.best.shift;
    csv << "\n";
  }

  const fs::path out_dir(options.output);
  openable::writeNpy((out_dir / "distance_matrix.npy").string(), matrix);
  writePng((out_dir / "distance_matrix.png").string(),
           openable::colorize(config.display_normalization == "max" ? openable::normalizeByMax(matrix)
                                                                    : openable::normalizeMinMax(matrix),
                              config.color_map));
  if (config.threshold >= 0)
    writePng((out_dir / "distance_matrix_thresholded.png").string(), openable::thresholdView(matrix, config.threshold));
  openable::writeFileAtomically((out_dir / "loop_closures.csv").string(), csv.str());

  std::ostringstream json;
  json << "{\n"
       << jsonStage("read", timings.read, timings.frames) << ",\n"
       << jsonStage("preprocess", timings.preprocess, timings.frames) << ",\n"
       << jsonStage("describe", timings.describe, timings.frames) << ",\n"
       << jsonStage("match", timings.match, timings.frames) << ",\n"
       << "  \"frames\": " << timings.frames << ",\n"
       << "  \"database_bytes\": " << detector->database().bytes() << "\n}\n";
  openable::writeFileAtomically((out_dir / "timings.json").string(), json.str());

  const double per_frame =
      timings.frames ? (timings.preprocess + timings.describe + timings.match) / timings.frames : 0;
  std::cout << "mode: " << (localisation ? "localisation (query vs reference)" : "loop closure (stream vs its past)")
            << "\n"
            << "frames: " << rows << " x " << columns << " (described " << timings.frames << ")\n"
            << "matches: " << matches
            << (gated ? " accepted (threshold " + config.get("threshold") + ", min_uniqueness " +
                            config.get("min_uniqueness") + ")"
                      : " (no threshold or uniqueness bound: every frame's best match)")
            << "\n";
  if (truth_checked)
    std::cout << "best match within " << options.ground_truth_tolerance << " frames of the truth: " << std::fixed
              << std::setprecision(3) << double(truth_hits) / truth_checked << " (" << truth_hits << " of "
              << truth_checked << ")\n"
              << "listed matches within " << options.ground_truth_tolerance
              << " frames of the truth: " << matches_correct << " of " << matches << "\n";
  std::cout << std::fixed << std::setprecision(3) << "time per frame: " << per_frame
            << " ms (preprocess + describe + match, image decoding excluded: "
            << timings.read / std::max<size_t>(1, timings.frames) << " ms)\n"
            << "wrote: " << options.output << "/{distance_matrix.npy,distance_matrix.png,"
            << (config.threshold >= 0 ? "distance_matrix_thresholded.png," : "") << "loop_closures.csv,timings.json}\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    options = parseArguments(argc, argv);
  }
  catch (const std::exception& e)
  {
    std::cerr << "openable_offline: " << e.what() << "\n";
    return 2;
  }
  try
  {
    return run(options);
  }
  catch (const std::exception& e)
  {
    std::cerr << "openable_offline: " << e.what() << "\n";
    return 1;
  }
}
