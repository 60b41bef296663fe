// openable_offline: the OpenABLE toolbox as a command-line program.
//
//   openable_offline --config FILE.yaml --reference PATH [--query PATH] --output DIR [--set key=value]...
//                    [--reference-right PATH] [--query-right PATH] [--ground-truth-tolerance T]
//                    [--camera-info FILE [--verify-optional]] [--map-in FILE] [--map-out FILE] [--session NAME]
//                    [--poses FILE [--keyframe-distance M] [--keyframe-angle RAD]]
//
// With --reference only, the stream is matched against its own past (loop-closure mode); with --query,
// every query frame is matched against the reference traversal (localisation mode). See --help.

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "openable/io/atomic_file.h"
#include "openable/verification/camera_calibration.h"
#include "openable/config.h"
#include "openable/description/frame_describer.h"
#include "openable/error.h"
#include "openable/io/image_source.h"
#include "openable/detection/loop_csv.h"
#include "openable/io/npy.h"
#include "openable/detection/online_detector.h"
#include "openable/io/pose_file.h"
#include "progress.h"
#include "openable/view/render.h"
#include "openable/map/reference_map.h"
#include "openable/io/staged_output.h"
#include "cli.h"
#include "offline_frame_numbers.h"
#include "offline_options.h"
#include "offline_traversal.h"

namespace fs = std::filesystem;
using openable::Error;

namespace
{
using namespace offline;  // TraversalReader, tryFrame, Timings

openable::SessionInfo sessionNamed(const std::string& name)
{
  return openable::SessionInfo{name, "", 0.0};
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
  const bool stereo = config.camera() == openable::CameraType::Stereo;
  if (stereo && (o.reference_right.empty() || (!o.query.empty() && o.query_right.empty())))
    throw Error("camera_type stereo needs --reference-right (and --query-right with --query)");
  if (!stereo && (!o.reference_right.empty() || !o.query_right.empty()))
    throw Error("--reference-right / --query-right need camera_type stereo");
  return config;
}

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


/// What loop_closures.csv and decisions.csv say of one frame (frame numbers as FrameNumbers gives them).
openable::LoopCsvFrame csvFrame(long query, long match, const openable::FrameOutcome& outcome, uint32_t query_session)
{
  const openable::Detection& d = outcome.detection;
  openable::LoopCsvFrame f;
  f.query = query;
  f.match = match;
  f.has_candidates = d.has_candidates;
  f.distance = d.best.distance;
  f.score = outcome.score;
  f.pace = d.best.pace;
  f.status = outcome.status;
  f.direction = d.best.direction;
  f.shift = d.best.shift;
  f.query_session = query_session;
  f.match_session = d.best.session;
  f.inliers = outcome.verification_ran ? outcome.verification.inliers : -1;
  return f;
}

int run(const Options& options)
{
  const openable::Config config = loadConfig(options);
  openable::StagedOutput output(options.output, "openable_offline");  // fails now, not after minutes of work, when DIR cannot be written
  const bool localisation = !options.query.empty();
  Timings timings;

  // Verification as a nodelet with ~verify whose camera_info arrived before the first image.
  openable::OnlineOptions online;
  openable::PinholeCamera camera;
  if (!options.camera_info.empty())
  {
    camera = openable::readCameraCalibration(options.camera_info);
    online.verify = true;
    online.verify_required = !options.verify_optional;
    if (!options.quiet)
      std::cerr << "verifying loop closures with " << options.camera_info << " ("
                << (camera.stereo() && config.camera() == openable::CameraType::Stereo ? "stereo" : "mono")
                << (online.verify_required ? ", required)\n" : ", optional)\n");
  }
  // Odometry: the poses a nodelet would look up in ~fixed_frame, and its keyframe parameters.
  openable::PoseFile odometry;
  if (!options.poses.empty())
  {
    odometry = openable::readPoseFile(options.poses);
    online.keyframe_distance = options.keyframe_distance;
    online.keyframe_angle = options.keyframe_angle;
    if (!options.quiet)
    {
      std::cerr << "poses: " << odometry.poses.size() << " from " << options.poses << " ("
                << openable::toString(odometry.format) << "); a keyframe every " << online.keyframe_distance << " m";
      if (online.keyframe_angle > 0.0)
        std::cerr << " or turn of " << online.keyframe_angle << " rad";
      std::cerr << "\n";
    }
  }

  // Localisation: describe the reference traversal into a map first. Loop closure: a new map, or a saved
  // one continued (--map-in), with the stream as its newest session.
  std::unique_ptr<openable::OnlineDetector> detector;
  long reference_files = 0;
  std::unique_ptr<FrameNumbers> numbers;
  if (localisation)
  {
    const openable::OnlineDetector describer(config);
    openable::PlaceDatabase map(describer.describer().layout(), 0, config.toYaml());
    numbers = std::make_unique<FrameNumbers>(0);
    TraversalReader reference(options.reference, options.reference_right, options.quiet);
    openable::Progress progress("openable_offline: reference", reference.size(), options.quiet);
    openable::FrameInput input;
    for (; reference.next(input, timings); ++reference_files)
    {
      const auto start = Clock::now();
      tryFrame(input.source,
               [&]
               {
                 openable::FrameInfo info;
                 info.source = input.source;
                 map.add(describer.describe(input), info);
                 numbers->stored(reference_files);
               });
      timings.describe += msSince(start);
      progress.step();
    }
    progress.finish();
    if (map.empty())
      throw Error("no reference frame could be described in '" + options.reference + "'");
    timings.frames += map.size();
    detector = std::make_unique<openable::OnlineDetector>(
        config, openable::SessionMap(std::move(map), sessionNamed(nameOfPath(options.reference))), openable::MapMode::Localise,
        openable::SessionInfo(), online);
  }
  else
  {
    openable::SessionMap map = options.map_in.empty()
                                   ? openable::SessionMap(openable::FrameDescriber(config).layout(), config.toYaml())
                                   : openable::loadReferenceMap(options.map_in, config);
    if (!options.map_in.empty() && !options.quiet)
      std::cerr << "continuing " << options.map_in << ": " << map.sessionCount() << " sessions, " << map.frameCount()
                << " frames; this stream is session '" << options.session << "'\n";
    numbers = std::make_unique<FrameNumbers>(map.nextId());
    detector = std::make_unique<openable::OnlineDetector>(config, std::move(map), openable::MapMode::Continue,
                                                          sessionNamed(options.session), online);
  }
  if (online.verify)
    detector->setCamera(camera);
  const openable::SessionMap& map = detector->loopDetector().map();
  const uint32_t own = localisation ? 0 : static_cast<uint32_t>(detector->loopDetector().ownSession());
  const long first_column = numbers->query(0);

  // The stream: every frame through the online pipeline, as a nodelet would see it.
  TraversalReader stream(localisation ? options.query : options.reference,
                         localisation ? options.query_right : options.reference_right, options.quiet);
  const std::string& stream_path = localisation ? options.query : options.reference;
  if (!options.poses.empty() && !stream.isVideo() && odometry.poses.size() < stream.size())
    throw Error("--poses: '" + options.poses + "' holds " + std::to_string(odometry.poses.size()) + " poses but '" +
                stream_path + "' has " + std::to_string(stream.size()) + " frames; expected one pose per frame");
  openable::Progress progress(localisation ? "openable_offline: query" : "openable_offline", stream.size(),
                              options.quiet);
  std::vector<std::vector<float>> rows;  // per stream file: distances by frame number (empty = not described)
  // A panorama's circular shift, or a mono frame's view (lateral_shift, view_channel_shift): where the match faces.
  const bool with_shift = config.camera() == openable::CameraType::Panoramic || config.lateral_shift > 0.0 ||
                          config.view_channel_shift > 0.0;
  openable::LoopCsvWriter csv(with_shift);
  std::map<std::string, size_t> status_counts;
  size_t published = 0, truth_checked = 0, truth_hits = 0, published_correct = 0;
  std::vector<float> row;
  openable::FrameInput input;
  for (long file = 0; stream.next(input, timings); ++file)
  {
    if (!options.poses.empty())
    {
      // A video's frames are counted only as they are decoded: the check above cannot see them all.
      if (static_cast<size_t>(file) >= odometry.poses.size())
        throw Error("--poses: '" + options.poses + "' holds " + std::to_string(odometry.poses.size()) +
                    " poses but '" + stream_path + "' has at least " + std::to_string(file + 1) +
                    " frames; expected one pose per frame");
      input.has_pose = true;
      input.pose = odometry.poses[static_cast<size_t>(file)];
      if (!odometry.stamps.empty())
        input.stamp = odometry.stamps[static_cast<size_t>(file)];
    }
    rows.emplace_back();
    progress.update(rows.size());
    openable::FrameOutcome outcome;
    if (!tryFrame(input.source, [&] { outcome = detector->process(input); }))
      continue;
    timings.preprocess += outcome.times.preprocess_ms;
    timings.describe += outcome.times.describe_ms;
    timings.match += outcome.times.match_ms + outcome.times.verify_ms;
    ++timings.frames;
    if (!localisation && outcome.stored)
      numbers->stored(file);
    const long query = localisation ? file : numbers->query(file);
    detector->loopDetector().lastRow(row);
    numbers->toNumbers(map, own, row, static_cast<size_t>(localisation ? reference_files : query + 1), rows.back());

    const openable::Detection& d = outcome.detection;
    const long match = d.has_candidates ? numbers->stored(map, d.best.session, d.best.position, own) : -1;
    // One row per outcome, and only a frame that came back has a number (one that threw has neither): a
    // frame's row is its number, where a later frame's confirmation finds it.
    csv.add(csvFrame(query, match, outcome, localisation ? static_cast<uint32_t>(map.sessionCount()) : own));
    for (const openable::FrameOutcome& earlier : outcome.confirmed)
    {
      csv.setStatus(earlier.frame, openable::FrameStatus::Published);
      if (earlier.detection.has_candidates)  // placed in hindsight, it may have moved
        csv.setMatch(earlier.frame, numbers->stored(map, earlier.detection.best.session, earlier.detection.best.position, own));
    }
    if (d.has_candidates && options.ground_truth_tolerance >= 0)
    {
      ++truth_checked;
      truth_hits += std::labs(match - query) <= options.ground_truth_tolerance ? 1 : 0;
    }
  }
  progress.finish();
  csv.settlePending();  // no frame after the last ones could confirm them
  for (const openable::LoopCsvFrame& f : csv.frames())
  {
    ++status_counts[openable::toString(f.status)];
    if (f.status != openable::FrameStatus::Published)
      continue;
    ++published;
    published_correct += std::labs(f.match - f.query) <= std::max(0, options.ground_truth_tolerance) ? 1 : 0;
  }
  if (timings.frames == 0)
    throw Error("no frame of '" + stream_path + "' could be described");

  // Frames are counted as decoded: the matrix is as wide as the reference really was.
  const long columns = localisation ? reference_files : first_column + static_cast<long>(rows.size());
  cv::Mat matrix(static_cast<int>(rows.size()), static_cast<int>(columns), CV_32F, cv::Scalar(std::nanf("")));
  for (size_t r = 0; r < rows.size(); ++r)
    std::copy(rows[r].begin(), rows[r].end(), matrix.ptr<float>(static_cast<int>(r)));

  openable::writeNpy(output.path("distance_matrix.npy"), matrix);
  writePng(output.path("distance_matrix.png"),
           openable::colorize(config.display_normalization == "max" ? openable::normalizeByMax(matrix)
                                                                    : openable::normalizeMinMax(matrix),
                              config.color_map));
  if (config.threshold >= 0)
    writePng(output.path("distance_matrix_thresholded.png"), openable::thresholdView(matrix, config.threshold));
  openable::writeFileAtomically(output.path("loop_closures.csv"), csv.loopClosures());
  openable::writeFileAtomically(output.path("decisions.csv"), csv.decisions());

  std::ostringstream json;
  json << "{\n"
       << jsonStage("read", timings.read, timings.frames) << ",\n"
       << jsonStage("preprocess", timings.preprocess, timings.frames) << ",\n"
       << jsonStage("describe", timings.describe, timings.frames) << ",\n"
       << jsonStage("match", timings.match, timings.frames) << ",\n"
       << "  \"frames\": " << timings.frames << ",\n"
       << "  \"descriptor_bytes\": " << sizeof(uint64_t) * detector->loopDetector().map().layout().frameWords()
       << ",\n  \"database_bytes\": " << detector->loopDetector().map().bytes() << "\n}\n";
  openable::writeFileAtomically(output.path("timings.json"), json.str());
  if (!options.map_out.empty())  // before the outputs: a map that cannot be written fails the whole run
  {
    map.save(options.map_out);
    if (!options.quiet)
      std::cerr << "saved the map (" << map.sessionCount() << " sessions, " << map.frameCount() << " frames) to "
                << options.map_out << "\n";
  }
  output.publish();

  std::cout << "mode: " << (localisation ? "localisation (query vs reference)" : "loop closure (stream vs its past)")
            << "\n"
            << "frames: " << rows.size() << " x " << columns << " (described " << timings.frames << ")\n"
            << "published: " << published << " loop closures (";
  bool first = true;
  for (const auto& [status, count] : status_counts)
  {
    std::cout << (first ? "" : ", ") << status << " " << count;
    first = false;
  }
  std::cout << ")\n";
  if (truth_checked)
    std::cout << "best match within " << options.ground_truth_tolerance << " frames of the truth: " << std::fixed
              << std::setprecision(3) << double(truth_hits) / truth_checked << " (" << truth_hits << " of "
              << truth_checked << ")\n"
              << "published loop closures within " << options.ground_truth_tolerance
              << " frames of the truth: " << published_correct << " of " << published << "\n";
  const double per_frame = (timings.preprocess + timings.describe + timings.match) / timings.frames;
  std::cout << std::fixed << std::setprecision(3) << "time per frame: " << per_frame
            << " ms (preprocess + describe + match + decide; decoding the image took " << timings.read / timings.frames
            << " ms more)\n"
            << "wrote: " << options.output << "/{distance_matrix.npy,distance_matrix.png,"
            << (config.threshold >= 0 ? "distance_matrix_thresholded.png," : "")
            << "loop_closures.csv,decisions.csv,timings.json}\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  // Run errors read "openable_offline: reason", as bad usage does (exit status 1 and 2).
  return openable::cli::runTool({"openable_offline", false}, argc, argv,
                                [](int argc, char** argv)
                                {
                                  const Options options = parseArguments(argc, argv);
                                  if (!options.help)
                                    return run(options);
                                  std::cout << kUsage;
                                  return 0;
                                });
}
