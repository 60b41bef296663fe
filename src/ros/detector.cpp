#include "openable_ros/detector.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <sstream>

#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/description/input_contract.h"
#include "openable/view/trajectory_export.h"
#include "openable_ros/conversions.h"
#include "openable_ros/descriptor_publisher.h"
#include "openable_ros/live_reconfigure.h"
#include "openable_ros/map_services.h"
#include "openable_ros/params.h"

namespace openable_ros
{
namespace
{
const double kWarnPeriod = 5.0;  // seconds between two warnings of one kind

openable::OnlineOptions onlineOptions(const RosParameters& p)
{
  openable::OnlineOptions options;
  options.keyframe_distance = p.keyframe_distance;
  options.keyframe_angle = p.keyframe_angle;
  options.verify = p.verify;
  options.verify_required = p.verify_required;
  options.feature_bytes = size_t(p.verify_memory * 1024.0 * 1024.0);
  options.require_stamps = true;  // a header stamp of 0 is unset: a backend cannot place such a loop closure
  return options;
}

geometry_msgs::Point position(const std::array<double, 7>& pose)
{
  geometry_msgs::Point p;
  p.x = pose[0];
  p.y = pose[1];
  p.z = pose[2];
  return p;
}
}  // namespace

Detector::Detector(ros::NodeHandle nh, ros::NodeHandle pnh, std::string name, RosParameters parameters)
  : nh_(nh),
    pnh_(pnh),
    name_(std::move(name)),
    parameters_(std::move(parameters)),
    options_(onlineOptions(parameters_))
{
  // The default session name: the node and the wall time it started, unique across restarts.
  char started[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(started, sizeof(started), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  session_default_ = name_ + " " + started;
}

std::unique_ptr<openable::OnlineDetector> Detector::freshDetector(const openable::Config& config) const
{
  openable::SessionMap empty(openable::FrameDescriber(config).layout(), config.toYaml());
  return std::make_unique<openable::OnlineDetector>(config, std::move(empty), openable::MapMode::Continue,
                                                    openable::SessionInfo{sessionName(), parameters_.robot, 0.0},
                                                    options_);
}

Detector::~Detector()
{
  // Stop the timers before the members they touch go away.
  diagnostics_timer_.stop();
  sync_timer_.stop();
}

std::unique_ptr<Detector> Detector::create(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                                           const openable::Config& defaults, const RosParameters& parameters)
{
  std::vector<std::string> warnings;
  const openable::Config config = loadCoreConfig(pnh, defaults, warnings);
  warnUnknownParameters(pnh, warnings);
  for (const auto& warning : warnings)
    ROS_WARN_STREAM_NAMED(name, "parameter " << warning);

  std::unique_ptr<Detector> d(new Detector(nh, pnh, name, parameters));
  try
  {
    d->detector_ = d->freshDetector(config);
  }
  catch (const std::exception& e)
  {
    ROS_ERROR_STREAM_NAMED(name, "cannot build the detector: " << e.what() << "; this nodelet stays idle");
    return nullptr;
  }
  d->poses_ = std::make_unique<PoseLookup>(nh, parameters.fixed_frame, parameters.tf_timeout);
  d->matrix_ = std::make_unique<MatrixPublisher>(nh, parameters.matrix_rate, parameters.matrix_size,
                                                 parameters.matrix_mode, parameters.matrix_threshold_view);
  d->markers_ = std::make_unique<LoopMarkers>(nh, parameters.fixed_frame, parameters.markers_rate);
  const std::string& map_file = parameters.map_file;
  if (!map_file.empty())
  {
    std::string message;
    uint32_t frames = 0;
    if (!std::ifstream(map_file).good())
      ROS_INFO_STREAM_NAMED(name, "~map_file '" << map_file << "' does not exist yet; starting a new history "
                                                << "(~save_map writes it)");
    else if (d->loadMap(map_file, message, frames))
      ROS_INFO_STREAM_NAMED(name, message);
    else
      ROS_WARN_STREAM_NAMED(name, "~map_file: " << message << "; starting a new history instead");
  }
  // A stop's repeated loop closures go out together once its frame is confirmed (confirm_frames): the queue
  // holds the most a confirmation releases, so none is dropped.
  d->loop_pub_ = nh.advertise<LoopClosure>("loop_closures", openable::LoopConfirmation::kMaxRepeats + 100);
  d->decisions_pub_ = nh.advertise<LoopClosure>("decisions", 100);
  d->services_ = std::make_unique<MapServices>(pnh, *d);
  if (parameters.publish_descriptors)
    d->descriptors_ = std::make_unique<DescriptorPublisher>(nh, parameters.robot, parameters.session, config);
  d->restartGeoFile();
  d->fix_sub_ = nh.subscribe("fix", 10, &Detector::fixCallback, d.get());

  Detector* self = d.get();
  d->updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, name);
  d->updater_->setHardwareID(name);
  d->updater_->add("loop closure detector",
                   [self](diagnostic_updater::DiagnosticStatusWrapper& s) { self->diagnose(s); });
  d->diagnostics_timer_ =
      nh.createTimer(ros::Duration(0.1), [self](const ros::TimerEvent&) { self->updater_->update(); });
  // Last: the server calls applyLive() at once with the values in force.
  d->reconfigure_ = std::make_unique<LiveReconfigure>(pnh, *d, config, parameters);
  ROS_INFO_STREAM_NAMED(name, "openable " << config.camera_type << " detector ready: " << config.descriptor
                                          << ", patch " << config.patch_size << ", L = " << config.sequence_length
                                          << ", min_uniqueness = " << config.min_uniqueness
                                          << (d->detector_->localisationMode() ? ", localising against the map" : ""));
  return d;
}

openable::Config Detector::config()
{
  std::lock_guard<std::mutex> lock(mutex_);
  return detector_->config();
}

void Detector::warnThrottled(const std::string& key, double period, const std::string& message)
{
  if (throttle_.ready(key, ros::WallTime::now().toSec(), period))
    ROS_WARN_STREAM_NAMED(name_, message);
}

void Detector::refuse(const std::string& reason, const std::string& message)
{
  uint64_t held_back = 0;
  if (!counters_.refusals.note(reason, ros::WallTime::now().toSec(), held_back))
    return;
  std::ostringstream line;
  line << message << " (frame skipped: " << reason << ")";
  if (held_back > 0)
    line << "; " << held_back << " more '" << reason << "' since the last such warning";
  ROS_WARN_STREAM_NAMED(name_, line.str());
}

void Detector::reject(const std::string& reason, const std::string& message)
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.received;
  refuse(reason, message);
}

void Detector::reject(const openable::InputProblem& problem, const std::string& topic)
{
  reject(problem.reason, "'" + topic + "': " + problem.what);
}

void Detector::process(const std_msgs::Header& header, const std::string& topic, openable::FrameInput input)
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.received;
  input.stamp = header.stamp.toSec();
  input.session = uint32_t(parameters_.session);
  input.source = topic;
  std::string problem;
  input.has_pose = poses_->lookup(header, input.pose, problem);
  if (!problem.empty())
    warnThrottled("tf", kWarnPeriod, problem);
  input.has_geo = fixes_.nearest(input.stamp, parameters_.fix_tolerance, input.geo);

  openable::FrameOutcome outcome;
  try
  {
    outcome = detector_->process(input);
    if (!acceptStamp(header, topic, outcome, input))
      return;
  }
  catch (const openable::FrameRefused& e)
  {
    // The input contract (openable/input_contract.h): each reason counted and throttled on its own.
    refuse(e.reason(), "'" + topic + "': " + e.what());
    return;
  }
  catch (const openable::Error& e)
  {
    refuse("cannot describe", "'" + topic + "': " + e.what());
    return;
  }
  catch (const cv::Exception& e)
  {
    refuse("OpenCV error", "'" + topic + "': OpenCV: " + e.what());
    return;
  }
  catch (const std::exception& e)
  {
    // Anything else from the core must not unwind into the nodelet manager either.
    refuse("unexpected error", "'" + topic + "': " + e.what());
    return;
  }
  publish(header, outcome);
  if (!outcome.stored || !input.has_geo)
    return;
  ++counters_.frames_with_fix;
  if (geo_out_.is_open())
    geo_out_ << openable::geoPositionsCsvLine(outcome.query.id, input.geo) << std::flush;
}

void Detector::fixCallback(const sensor_msgs::NavSatFixConstPtr& msg)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (msg->status.status < sensor_msgs::NavSatStatus::STATUS_FIX || !std::isfinite(msg->latitude) ||
      !std::isfinite(msg->longitude) || std::abs(msg->latitude) > 90.0 || std::abs(msg->longitude) > 180.0)
  {
    warnThrottled("fix", kWarnPeriod,
                  "'" + fix_sub_.getTopic() + "': no usable fix (status " + std::to_string(int(msg->status.status)) +
                      ", latitude " + std::to_string(msg->latitude) + ", longitude " + std::to_string(msg->longitude) +
                      "); frames around it have no geographic position");
    return;
  }
  openable::GeoPosition fix;
  fix.latitude = msg->latitude;
  fix.longitude = msg->longitude;
  // NavSatFix allows an unknown (NaN) altitude; KML needs a number.
  fix.altitude = std::isfinite(msg->altitude) ? msg->altitude : 0.0;
  fix.stamp = msg->header.stamp.toSec();
  fixes_.add(fix);
  ++counters_.fixes;
}

void Detector::restartGeoFile()
{
  if (parameters_.geo_file.empty())
    return;
  geo_out_.close();
  geo_out_.clear();
  geo_out_.open(parameters_.geo_file, std::ios::trunc);
  if (geo_out_)
    geo_out_ << openable::geoPositionsCsvHeader() << std::flush;
  else
    ROS_ERROR_STREAM_NAMED(name_, "~geo_file: cannot write '" << parameters_.geo_file
                                                              << "'; the frames' fixes are not recorded");
}

bool Detector::acceptStamp(const std_msgs::Header& header, const std::string& topic, openable::FrameOutcome& outcome,
                           openable::FrameInput& input)
{
  if (outcome.status != openable::FrameStatus::TimeJump)
    return true;
  std::ostringstream what;
  what << "'" << topic << "': stamp " << header.stamp << " is before the previous frame's; expected increasing stamps";
  if (!parameters_.reset_on_time_jump)
  {
    refuse("stamp went backwards",
           what.str() + "; history kept (set ~reset_on_time_jump to start over instead)");
    return false;
  }
  warnThrottled("time jump reset", kWarnPeriod,
                what.str() + " (a bag restarted?): ~reset_on_time_jump is true, resetting the history");
  resetLocked();
  poses_->clear();
  outcome = detector_->process(input);
  return true;
}

void Detector::publish(const std_msgs::Header& header, const openable::FrameOutcome& outcome)
{
  ++counters_.statuses[openable::toString(outcome.status)];
  // Not a keyframe, or the camera stands still: nothing is stored, but the frame has its decision (a
  // standstill repeats the last one, a loop closure included, stamped with this frame), as offline.
  if (outcome.stored)
    recordStored(header, outcome);
  else
    ++counters_.skipped_keyframe;
  LoopClosurePtr msg = makeLoopClosure(header, outcome);
  if (decisions_pub_.getNumSubscribers() > 0)
    decisions_pub_.publish(LoopClosureConstPtr(msg));
  if (outcome.published())
    publishLoop(msg, outcome, outcome);
  // Loop closures of earlier frames that this one confirmed (confirm_frames): each with its own frame's stamp.
  // Their frames were counted pending (or, for the frames a run reached back to, as their status_before); they
  // count as decided now, as decisions.csv has them in the end.
  for (const openable::FrameOutcome& earlier : outcome.confirmed)
  {
    std_msgs::Header earlier_header = header;
    if (earlier.query.stamp > 0.0)
      earlier_header.stamp = ros::Time(earlier.query.stamp);
    moveStatus(earlier.status_before, earlier.status, 1);
    publishLoop(makeLoopClosure(earlier_header, earlier), earlier, outcome);
  }
  const uint64_t dropped = detector_->confirmation().dropped();
  if (dropped > counted_dropped_)
    moveStatus(openable::FrameStatus::Pending, openable::FrameStatus::Unconfirmed, dropped - counted_dropped_);
  counted_dropped_ = dropped;
  if (!outcome.stored)
    return;
  const std::string error = matrix_->publish(header, detector_->config());
  if (!error.empty())
    warnThrottled("render", kWarnPeriod, error);
  markers_->publish(header.stamp, outcome.published() || !outcome.confirmed.empty());
}

void Detector::moveStatus(openable::FrameStatus from, openable::FrameStatus to, uint64_t frames)
{
  uint64_t& pending = counters_.statuses[openable::toString(from)];
  pending -= std::min(pending, frames);
  counters_.statuses[openable::toString(to)] += frames;
}

void Detector::publishLoop(const LoopClosurePtr& msg, const openable::FrameOutcome& loop,
                           const openable::FrameOutcome& current)
{
  ++counters_.loops;
  loop_pub_.publish(LoopClosureConstPtr(msg));
  if (!current.stored || !loop.stored)
    return;  // a standstill's repeat: the loop is drawn once, with its stored frame
  // The matrix's last row is the current frame's; a confirmed loop's row is a few stored frames before it.
  matrix_->addLoop(loop.detection.best.id, current.query.id >= loop.query.id ? current.query.id - loop.query.id : 0);
  if (msg->has_poses)
    markers_->addLoop(msg->query_pose.position, msg->match_pose.position);
}

void Detector::recordStored(const std_msgs::Header& header, const openable::FrameOutcome& outcome)
{
  counters_.addTimes(outcome.times);
  if (descriptors_)
    descriptors_->publish(header, outcome, detector_->loopDetector());
  if (!detector_->localisationMode())
    ++counters_.stored;
  if (outcome.verified)
    ++counters_.verification["accepted"];
  else if (outcome.status == openable::FrameStatus::FailedVerification)
    ++counters_.verification[openable::toString(outcome.verification.status)];
  if (outcome.status == openable::FrameStatus::FailedVerification ||
      outcome.status == openable::FrameStatus::Unverified)
    warnThrottled("verification", kWarnPeriod,
                  "loop closure " + std::to_string(outcome.query.id) + " -> " +
                      std::to_string(outcome.detection.best.id) + " not published (" +
                      openable::toString(outcome.status) + "): " + outcome.verification_note);
  if (outcome.query.has_pose)
    markers_->addPosition(position(outcome.query.pose));
  if (matrix_->wanted())
  {
    detector_->loopDetector().lastRow(row_);
    matrix_->addRow(detector_->loopDetector().map().frames(0).firstId(), row_);
  }
}

void Detector::setCamera(const openable::PinholeCamera& camera)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!parameters_.verify)
    return;
  const bool first = !detector_->hasVerifier();
  try
  {
    if (!detector_->setCamera(camera))
      warnThrottled("camera changed", 60.0,
                    "camera_info changed after the verifier was built; keeping the first calibration");
    else if (first)
      ROS_INFO_STREAM_NAMED(name_, "geometric verification on: fx "
                                       << camera.fx << ", baseline " << camera.baseline << " m ("
                                       << (camera.stereo() ? "stereo PnP" : "mono essential") << ")");
  }
  catch (const openable::Error& e)
  {
    warnThrottled("camera", 10.0, std::string("~verify: camera_info cannot be used: ") + e.what());
  }
}

void Detector::watchSync(const std::vector<std::string>& topics, const std::string& advice)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const double timeout = parameters_.sync_warning_timeout;
  sync_ = std::make_unique<openable::SyncWatch>(topics, advice, timeout, ros::WallTime::now().toSec());
  if (timeout <= 0.0)
    return;
  sync_timer_ = nh_.createWallTimer(ros::WallDuration(timeout),
                                    [this](const ros::WallTimerEvent&)
                                    {
                                      std::lock_guard<std::mutex> lock(mutex_);
                                      const std::string warning = sync_->check(ros::WallTime::now().toSec());
                                      if (!warning.empty())
                                        ROS_WARN_STREAM_NAMED(name_, warning);
                                    });
}

void Detector::noteInput(size_t index, const std_msgs::Header& header)
{
  std::lock_guard<std::mutex> lock(mutex_);
  gaps_.note(index, header.seq, header.stamp.toSec());
  counters_.dropped_queue = gaps_.lost();
  if (sync_)
    sync_->noteInput(index);
}

void Detector::noteSet()
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (sync_)
    sync_->noteSet(ros::WallTime::now().toSec());
}

void Detector::noteDropped(size_t dropped)
{
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.dropped_by_synchroniser = dropped;
}

void Detector::resetLocked()
{
  detector_->reset();
  matrix_->clear();
  markers_->clear();
  fixes_.clear();
  restartGeoFile();
}

void Detector::applyLive(openable::Config& requested, RosParameters& display)
{
  std::lock_guard<std::mutex> lock(mutex_);
  try
  {
    detector_->updateConfig(requested);
  }
  catch (const openable::Error& e)
  {
    ROS_WARN_STREAM_NAMED(name_, "dynamic_reconfigure refused: " << e.what() << "; keeping the previous values");
  }
  requested = detector_->config();
  if (display.matrix_mode != "whole_history" && display.matrix_mode != "rolling_window")
  {
    ROS_WARN_STREAM_NAMED(name_, "dynamic_reconfigure refused: matrix_mode '"
                                     << display.matrix_mode << "' is not whole_history | rolling_window; keeping "
                                     << parameters_.matrix_mode);
    display.matrix_mode = parameters_.matrix_mode;
  }
  const std::string error =
      matrix_->setOptions(display.matrix_rate, display.matrix_size, display.matrix_mode, display.matrix_threshold_view);
  if (!error.empty())
    ROS_WARN_STREAM_NAMED(name_, error);
  parameters_.matrix_rate = display.matrix_rate;
  parameters_.matrix_size = display.matrix_size;
  parameters_.matrix_mode = display.matrix_mode;
  parameters_.matrix_threshold_view = display.matrix_threshold_view;
}

void Detector::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
{
  std::lock_guard<std::mutex> lock(mutex_);
  diagnostics_.fill(status, counters_, matrix_->published(), *detector_, parameters_);
}

}  // namespace openable_ros
