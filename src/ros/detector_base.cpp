#include "openable_ros/detector_base.h"

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2/exceptions.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "openable/error.h"
#include "openable_ros/LoopClosure.h"
#include "openable_ros/conversions.h"
#include "openable_ros/params.h"

namespace openable_ros
{
namespace
{
// Markers keep at most this many trajectory points and loop edges (oldest leave first), so publishing
// them stays bounded on a robot that runs for days.
const size_t kMaxTrajectoryPoints = 20000;
const size_t kMaxLoopEdges = 5000;
// Throttle period of input warnings (seconds).
const double kWarnPeriod = 5.0;

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

openable::DistanceMatrixView::Mode viewMode(const std::string& mode)
{
  return mode == "rolling_window" ? openable::DistanceMatrixView::Mode::kRollingWindow
                                  : openable::DistanceMatrixView::Mode::kWholeHistory;
}

geometry_msgs::Point position(const std::array<double, 7>& pose)
{
  geometry_msgs::Point p;
  p.x = pose[0];
  p.y = pose[1];
  p.z = pose[2];
  return p;
}

/// One marker of loop_markers: ADD when it has something to show, else DELETE (clears an old one in rviz).
visualization_msgs::Marker makeMarker(const std_msgs::Header& header, const std::string& ns, int id, int type,
                                      bool visible, double width, float r, float g, float b)
{
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visible ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
  m.pose.orientation.w = 1.0;
  m.scale.x = width;
  m.color.r = r;
  m.color.g = g;
  m.color.b = b;
  m.color.a = 1.0f;
  return m;
}
}  // namespace

DetectorBase::DetectorBase() : view_(512) {}

DetectorBase::~DetectorBase()
{
  // Stop the timer before the members it touches go away.
  diagnostics_timer_.stop();
}

bool DetectorBase::setupDetector(const openable::Config& defaults)
{
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  std::vector<std::string> warnings;
  openable::Config config = loadCoreConfig(pnh, defaults, warnings);

  fixed_frame_ = readString(pnh, "fixed_frame", "", warnings);
  map_file_ = readString(pnh, "map_file", "", warnings);
  tf_timeout_ = readDouble(pnh, "tf_timeout", 0.05, 0.0, 10.0, "s", warnings);
  options_.keyframe_distance = readDouble(pnh, "keyframe_distance", 0.0, 0.0, 1e6, "m", warnings);
  options_.keyframe_angle = readDouble(pnh, "keyframe_angle", 0.0, 0.0, M_PI, "rad", warnings);
  reset_on_time_jump_ = readBool(pnh, "reset_on_time_jump", false, warnings);
  matrix_rate_ = readDouble(pnh, "matrix_rate", 2.0, 0.0, 30.0, "Hz", warnings);
  markers_rate_ = readDouble(pnh, "markers_rate", 1.0, 0.0, 30.0, "Hz", warnings);
  queue_size_ = readInt(pnh, "queue_size", 10, 1, 10000, warnings);
  sync_warning_timeout_ = readDouble(pnh, "sync_warning_timeout", 5.0, 0.0, 3600.0, "s", warnings);
  session_ = uint32_t(readInt(pnh, "session", 0, 0, 1000000000, warnings));
  const int matrix_size = readInt(pnh, "matrix_size", 512, 16, 4096, warnings);
  // Off by default: the decision alone is measured trustworthy (doc/results.md). When on, a loop is only
  // published verified (or, with ~verify_required false, flagged as unverified: has_relative_pose false).
  options_.verify = readBool(pnh, "verify", false, warnings);
  options_.verify_required = readBool(pnh, "verify_required", true, warnings);
  const double verify_memory = readDouble(pnh, "verify_memory", 256.0, 1.0, 65536.0, "MB", warnings);
  options_.feature_bytes = size_t(verify_memory * 1024.0 * 1024.0);
  std::string matrix_mode = readString(pnh, "matrix_mode", "whole_history", warnings);
  const bool matrix_threshold_view = readBool(pnh, "matrix_threshold_view", false, warnings);
  if (matrix_mode != "whole_history" && matrix_mode != "rolling_window")
  {
    warnings.push_back("~matrix_mode: value '" + matrix_mode +
                       "' is not allowed; expected whole_history | rolling_window; using whole_history");
    matrix_mode = "whole_history";
  }
  if ((options_.keyframe_distance > 0.0 || options_.keyframe_angle > 0.0) && fixed_frame_.empty())
  {
    warnings.push_back(
        "~keyframe_distance / ~keyframe_angle need ~fixed_frame for the camera poses; "
        "~fixed_frame is empty, so every frame is kept");
    options_.keyframe_distance = 0.0;
    options_.keyframe_angle = 0.0;
  }
  for (const auto& warning : warnings)
  {
    NODELET_WARN_STREAM("parameter " << warning);
  }

  std::unique_lock<std::mutex> lock(mutex_);
  try
  {
    config_ = config;
    detector_ = std::make_unique<openable::OnlineDetector>(config_, options_);
  }
  catch (const openable::Error& e)
  {
    NODELET_ERROR_STREAM("cannot build the detector: " << e.what() << "; this nodelet stays idle");
    return false;
  }
  catch (const std::exception& e)
  {
    NODELET_ERROR_STREAM("cannot build the detector: " << e.what() << "; this nodelet stays idle");
    return false;
  }
  view_.setSize(matrix_size);
  view_.setMode(viewMode(matrix_mode));

  if (!map_file_.empty())
  {
    std::ifstream probe(map_file_);
    if (probe.good())
    {
      std::string message;
      if (loadMapLocked(map_file_, message))
      {
        NODELET_INFO_STREAM(message);
      }
      else
      {
        NODELET_WARN_STREAM("~map_file: " << message << "; starting a new history instead");
      }
    }
    else
    {
      NODELET_INFO_STREAM("~map_file '" << map_file_ << "' does not exist yet; starting a new history "
                                        << "(~save_map writes it)");
    }
  }

  if (!fixed_frame_.empty())
  {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }

  loop_pub_ = nh.advertise<LoopClosure>("loop_closures", 100);
  decisions_pub_ = nh.advertise<LoopClosure>("decisions", 100);
  markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("loop_markers", 1, true);
  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  matrix_pub_ = image_transport_->advertise("distance_matrix", 1);
  save_srv_ = pnh.advertiseService("save_map", &DetectorBase::saveMap, this);
  load_srv_ = pnh.advertiseService("load_map", &DetectorBase::loadMap, this);
  reset_srv_ = pnh.advertiseService("reset", &DetectorBase::reset, this);

  updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
  updater_->setHardwareID(getName());
  updater_->add("loop closure detector", this, &DetectorBase::diagnose);
  last_diagnostic_time_ = ros::WallTime::now();
  diagnostics_timer_ = nh.createTimer(ros::Duration(0.1), [this](const ros::TimerEvent&) { updater_->update(); });

  ready_ = true;
  NODELET_INFO_STREAM("openable " << config_.camera_type << " detector ready: " << config_.descriptor << ", patch "
                                  << config_.patch_size << ", L = " << config_.sequence_length
                                  << ", threshold = " << config_.threshold
                                  << (detector_->localisationMode() ? ", localising against the map" : ""));
  // dynamic_reconfigure starts from the parameter server: give it the validated values, not the raw ones
  // (a refused threshold of 5 would otherwise come back clamped to 1 and accept everything).
  pnh.setParam("threshold", config_.threshold);
  pnh.setParam("sequence_length", config_.sequence_length);
  pnh.setParam("min_sequence_length", config_.min_sequence_length);
  pnh.setParam("exclusion_window", config_.exclusion_window);
  pnh.setParam("top_k", config_.top_k);
  pnh.setParam("min_uniqueness", config_.min_uniqueness);
  pnh.setParam("uniqueness_window", config_.uniqueness_window);
  pnh.setParam("bidirectional", config_.bidirectional);
  pnh.setParam("color_map", config_.color_map);
  pnh.setParam("matrix_rate", matrix_rate_);
  pnh.setParam("matrix_size", matrix_size);
  pnh.setParam("matrix_mode", matrix_mode);
  pnh.setParam("matrix_threshold_view", matrix_threshold_view);
  lock.unlock();

  // The server reads its start values from the same private parameters (clamped to the .cfg ranges) and
  // calls reconfigure() at once, which takes mutex_: hence after the unlock.
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<DetectorConfig>>(reconfigure_mutex_, pnh);
  reconfigure_server_->setCallback([this](DetectorConfig& c, uint32_t level) { reconfigure(c, level); });
  return true;
}

void DetectorBase::startSyncWatchdog(const std::vector<std::string>& topics, const std::string& advice)
{
  std::lock_guard<std::mutex> lock(mutex_);
  sync_topics_ = topics;
  sync_counts_.assign(topics.size(), 0);
  sync_counts_at_last_set_.assign(topics.size(), 0);
  sync_advice_ = advice;
  last_sync_time_ = ros::WallTime::now();
  if (sync_warning_timeout_ > 0.0)
  {
    sync_timer_ = getNodeHandle().createWallTimer(ros::WallDuration(sync_warning_timeout_),
                                                  [this](const ros::WallTimerEvent&) { checkSync(); });
  }
}

void DetectorBase::noteInput(size_t index)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (index < sync_counts_.size())
  {
    ++sync_counts_[index];
  }
}

void DetectorBase::noteSynchronised()
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++sync_sets_;
  last_sync_time_ = ros::WallTime::now();
  sync_counts_at_last_set_ = sync_counts_;
}

void DetectorBase::checkSync()
{
  std::lock_guard<std::mutex> lock(mutex_);
  const double quiet = (ros::WallTime::now() - last_sync_time_).toSec();
  if (quiet < sync_warning_timeout_)
  {
    return;
  }
  // Messages that arrived since the last complete set: some but no set means they do not pair up; none at
  // all since the start means nothing is connected. A stream that simply stopped stays silent.
  uint64_t since = 0;
  uint64_t total = 0;
  std::ostringstream counts;
  for (size_t i = 0; i < sync_topics_.size(); ++i)
  {
    const uint64_t n = sync_counts_[i] - sync_counts_at_last_set_[i];
    counts << (i ? "," : "") << " '" << sync_topics_[i] << "' " << n;
    since += n;
    total += sync_counts_[i];
  }
  if (since == 0 && total > 0)
  {
    return;
  }
  std::ostringstream what;
  what << "no synchronised input set for " << int(quiet) << " s (" << sync_sets_
       << " sets so far). Received since the last set:" << counts.str() << " messages.";
  if (since > 0)
  {
    what << " " << sync_advice_;
  }
  else
  {
    what << " Check that the topics are published and remapped.";
  }
  NODELET_WARN_STREAM(what.str());
}

void DetectorBase::warnThrottled(const std::string& key, double period, const std::string& message)
{
  const ros::WallTime now = ros::WallTime::now();
  auto it = last_warning_.find(key);
  if (it != last_warning_.end() && (now - it->second).toSec() < period)
  {
    return;
  }
  last_warning_[key] = now;
  NODELET_WARN_STREAM(message);
}

void DetectorBase::rejectFrame(const std::string& reason, const std::string& message)
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejected_[reason];
  warnThrottled("reject " + reason, kWarnPeriod, message + " (frame skipped)");
}

bool DetectorBase::checkTimeLocked(const std_msgs::Header& header, const std::string& topic)
{
  if (last_stamp_.isZero() || header.stamp >= last_stamp_)
  {
    last_stamp_ = header.stamp;
    return true;
  }
  std::ostringstream what;
  what << "'" << topic << "': stamp " << header.stamp << " is before the previous frame's " << last_stamp_
       << "; expected increasing stamps";
  if (reset_on_time_jump_)
  {
    warnThrottled("time jump", kWarnPeriod,
                  what.str() + " (a bag restarted?): ~reset_on_time_jump is true, resetting the history");
    resetStreamLocked();
    if (tf_buffer_)
    {
      tf_buffer_->clear();
    }
    last_stamp_ = header.stamp;
    return true;
  }
  ++rejected_["stamp went backwards"];
  warnThrottled("time jump", kWarnPeriod,
                what.str() + "; frame skipped, history kept (set ~reset_on_time_jump to start over instead)");
  return false;
}

bool DetectorBase::lookupPoseLocked(const std_msgs::Header& header, std::array<double, 7>& pose)
{
  if (!tf_buffer_)
  {
    return false;
  }
  if (header.frame_id.empty())
  {
    warnThrottled("tf frame", kWarnPeriod,
                  "the input's header.frame_id is empty: no camera pose in '" + fixed_frame_ +
                      "' can be looked up; frames are kept without pose");
    return false;
  }
  try
  {
    const geometry_msgs::TransformStamped t =
        tf_buffer_->lookupTransform(fixed_frame_, header.frame_id, header.stamp, ros::Duration(tf_timeout_));
    pose = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z, t.transform.rotation.x,
            t.transform.rotation.y,    t.transform.rotation.z,    t.transform.rotation.w};
    return true;
  }
  catch (const tf2::TransformException& e)
  {
    std::ostringstream what;
    what << "no transform '" << fixed_frame_ << "' <- '" << header.frame_id << "' at " << header.stamp
         << " within ~tf_timeout " << tf_timeout_ << " s (" << e.what() << "); frame kept without pose";
    warnThrottled("tf", kWarnPeriod, what.str());
    return false;
  }
}

void DetectorBase::setCamera(const openable::PinholeCamera& camera)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!options_.verify || !ready_)
  {
    return;
  }
  const bool first = !detector_->hasVerifier();
  try
  {
    if (!detector_->setCamera(camera))
    {
      warnThrottled("camera changed", 60.0,
                    "camera_info changed after the verifier was built; keeping the first calibration");
    }
    else if (first)
    {
      NODELET_INFO_STREAM("geometric verification on: fx " << camera.fx << ", baseline " << camera.baseline
                                                           << " m (" << (camera.stereo() ? "stereo PnP" : "mono essential")
                                                           << ")");
    }
  }
  catch (const openable::Error& e)
  {
    warnThrottled("camera", 10.0, std::string("~verify: camera_info cannot be used: ") + e.what());
  }
}

void DetectorBase::processFrame(const std_msgs::Header& header, const std::string& topic, openable::FrameInput input)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!ready_)
  {
    return;
  }
  ++frames_received_;
  if (!checkTimeLocked(header, topic))
  {
    return;
  }
  input.stamp = header.stamp.toSec();
  input.session = session_;
  input.source = topic;
  input.has_pose = lookupPoseLocked(header, input.pose);

  openable::FrameOutcome outcome;
  try
  {
    outcome = detector_->process(input);
  }
  catch (const openable::Error& e)
  {
    ++rejected_["cannot describe"];
    warnThrottled("describe", kWarnPeriod, "'" + topic + "': " + e.what() + " (frame skipped)");
    return;
  }
  catch (const cv::Exception& e)
  {
    ++rejected_["OpenCV error"];
    warnThrottled("opencv", kWarnPeriod, "'" + topic + "': OpenCV: " + e.what() + " (frame skipped)");
    return;
  }
  catch (const std::exception& e)
  {
    // Anything else from the core must not unwind into the nodelet manager either.
    ++rejected_["unexpected error"];
    warnThrottled("exception", kWarnPeriod, "'" + topic + "': " + e.what() + " (frame skipped)");
    return;
  }
  ++statuses_[openable::toString(outcome.status)];
  if (!outcome.stored)
  {
    ++frames_skipped_keyframe_;
    return;
  }
  describe_latency_.add(outcome.times.preprocess_ms + outcome.times.describe_ms);
  match_latency_.add(outcome.times.match_ms);
  if (!detector_->localisationMode())
  {
    ++frames_stored_;
  }
  if (outcome.status == openable::FrameStatus::FailedVerification ||
      outcome.status == openable::FrameStatus::Unverified)
  {
    warnThrottled("verification", kWarnPeriod,
                  "loop closure " + std::to_string(outcome.query.id) + " -> " +
                      std::to_string(outcome.detection.best.id) + " not published (" +
                      openable::toString(outcome.status) + "): " + outcome.verification_note);
  }
  if (input.has_pose)
  {
    trajectory_.push_back(position(input.pose));
    while (trajectory_.size() > kMaxTrajectoryPoints)
    {
      trajectory_.pop_front();
    }
  }
  if (matrix_rate_ > 0.0)
  {
    detector_->loopDetector().lastRow(row_);
    view_.addRow(detector_->loopDetector().database().firstId(), row_);
  }
  publishOutcomeLocked(header, outcome);
  publishMatrixLocked(header);
  publishMarkersLocked(header, outcome.published());
}

void DetectorBase::publishOutcomeLocked(const std_msgs::Header& header, const openable::FrameOutcome& outcome)
{
  LoopClosurePtr msg = makeLoopClosure(header, outcome);
  if (decisions_pub_.getNumSubscribers() > 0)
  {
    decisions_pub_.publish(LoopClosureConstPtr(msg));
  }
  if (!outcome.published())
  {
    return;
  }
  ++loops_accepted_;
  if (matrix_rate_ > 0.0)
  {
    view_.addLoop(outcome.detection.best.id);
  }
  if (msg->has_poses)
  {
    loop_edges_.emplace_back(msg->query_pose.position, msg->match_pose.position);
    while (loop_edges_.size() > kMaxLoopEdges)
    {
      loop_edges_.pop_front();
    }
  }
  loop_pub_.publish(LoopClosureConstPtr(msg));
}

void DetectorBase::publishMatrixLocked(const std_msgs::Header& header)
{
  // Rendering is the expensive part: only while someone watches, and at most matrix_rate Hz.
  if (matrix_rate_ <= 0.0 || matrix_pub_.getNumSubscribers() == 0)
  {
    return;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (!last_matrix_time_.isZero() && (now - last_matrix_time_).toSec() < 1.0 / matrix_rate_)
  {
    return;
  }
  openable::DistanceMatrixView::RenderOptions options;
  options.color_map = config_.color_map;
  // display_normalization: minmax stretches the shown distances over the colour map, max is paper Eq. 5.
  options.stretch = config_.display_normalization != "max";
  if (matrix_threshold_view_)
  {
    options.threshold = std::max(0.0, config_.threshold);
  }
  cv::Mat picture;
  try
  {
    picture = view_.render(options);
  }
  catch (const openable::Error& e)
  {
    warnThrottled("render", kWarnPeriod, std::string("distance_matrix: ") + e.what());
    return;
  }
  if (picture.empty())
  {
    return;
  }
  last_matrix_time_ = now;
  sensor_msgs::ImagePtr msg = cv_bridge::CvImage(header, sensor_msgs::image_encodings::BGR8, picture).toImageMsg();
  matrix_pub_.publish(msg);
  ++matrix_published_;
}

void DetectorBase::publishMarkersLocked(const std_msgs::Header& header, bool force)
{
  if (fixed_frame_.empty() || markers_pub_.getNumSubscribers() == 0 || markers_rate_ <= 0.0)
  {
    return;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (!force && !last_markers_time_.isZero() && (now - last_markers_time_).toSec() < 1.0 / markers_rate_)
  {
    return;
  }
  last_markers_time_ = now;
  auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
  std_msgs::Header marker_header;
  marker_header.frame_id = fixed_frame_;
  marker_header.stamp = header.stamp;
  using visualization_msgs::Marker;

  Marker trajectory =
      makeMarker(marker_header, "trajectory", 0, Marker::LINE_STRIP, trajectory_.size() >= 2, 0.05, 0.2f, 0.6f, 1.0f);
  trajectory.points.assign(trajectory_.begin(), trajectory_.end());
  markers->markers.push_back(trajectory);

  Marker loops =
      makeMarker(marker_header, "loop_closures", 1, Marker::LINE_LIST, !loop_edges_.empty(), 0.08, 1.0f, 0.0f, 1.0f);
  for (const auto& edge : loop_edges_)
  {
    loops.points.push_back(edge.first);
    loops.points.push_back(edge.second);
  }
  markers->markers.push_back(loops);

  Marker current = makeMarker(marker_header, "current", 2, Marker::SPHERE, !trajectory_.empty(), 0.3, 1.0f, 0.8f, 0.0f);
  if (!trajectory_.empty())
  {
    current.pose.position = trajectory_.back();
  }
  current.scale.y = current.scale.z = 0.3;
  markers->markers.push_back(current);
  markers_pub_.publish(visualization_msgs::MarkerArrayConstPtr(markers));
}

void DetectorBase::resetStreamLocked()
{
  detector_->reset();
  view_.clear();
  trajectory_.clear();
  loop_edges_.clear();
  last_stamp_ = ros::Time();
}

bool DetectorBase::loadMapLocked(const std::string& path, std::string& message)
{
  openable::PlaceDatabase map = [&]()
  {
    try
    {
      return openable::PlaceDatabase::load(path);
    }
    catch (const openable::Error& e)
    {
      message = "map '" + path + "' refused: " + e.what();
      return openable::PlaceDatabase(detector_->describer().layout());
    }
  }();
  if (!message.empty())
  {
    return false;
  }
  // The map is only comparable when it was described exactly as this detector describes.
  openable::Config map_config;
  try
  {
    map_config = openable::Config::fromYamlString(map.configYaml());
  }
  catch (const openable::Error& e)
  {
    message = "map '" + path + "' refused: its configuration cannot be read (" + e.what() + ")";
    return false;
  }
  if (map.configYaml().empty())
  {
    message = "map '" + path + "' refused: it carries no configuration, so its descriptors cannot be checked";
    return false;
  }
  std::string differences;
  for (const auto& key : openable::Config::descriptorKeys())
  {
    if (map_config.get(key) != config_.get(key))
    {
      differences += (differences.empty() ? "" : ", ") + key + " '" + map_config.get(key) + "' (running '" +
                     config_.get(key) + "')";
    }
  }
  if (!differences.empty())
  {
    message = "map '" + path + "' refused: it was built with an incompatible configuration: " + differences;
    return false;
  }
  if (map.layout() != detector_->describer().layout())
  {
    message = "map '" + path + "' refused: its descriptor layout differs from this detector's";
    return false;
  }
  try
  {
    const size_t frames = map.size();
    auto detector = std::make_unique<openable::OnlineDetector>(config_, std::move(map), options_);
    detector_ = std::move(detector);
    message = "map '" + path + "' loaded: " + std::to_string(frames) + " frames; localising against it";
  }
  catch (const openable::Error& e)
  {
    message = "map '" + path + "' refused: " + e.what();
    return false;
  }
  view_.clear();
  trajectory_.clear();
  loop_edges_.clear();
  return true;
}

std::string DetectorBase::mapServiceRefusal(const std::string& path) const
{
  if (!ready_)
    return "the detector is not running (see the start-up errors)";
  if (path.empty())
    return "no path given and ~map_file is empty";
  return "";
}

bool DetectorBase::saveMap(SaveMap::Request& request, SaveMap::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = request.path.empty() ? map_file_ : request.path;
  response.message = mapServiceRefusal(path);
  if (!response.message.empty())
  {
    response.success = false;
    return true;
  }
  try
  {
    detector_->loopDetector().database().save(path);
    response.success = true;
    response.frames = uint32_t(detector_->loopDetector().database().size());
    response.message = "saved " + std::to_string(response.frames) + " frames to '" + path + "'";
    NODELET_INFO_STREAM(response.message);
  }
  catch (const openable::Error& e)
  {
    response.success = false;
    response.message = "cannot save the map to '" + path + "': " + e.what();
    NODELET_WARN_STREAM(response.message);
  }
  return true;
}

bool DetectorBase::loadMap(LoadMap::Request& request, LoadMap::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = request.path.empty() ? map_file_ : request.path;
  response.message = mapServiceRefusal(path);
  if (!response.message.empty())
  {
    response.success = false;
    return true;
  }
  std::string message;
  response.success = loadMapLocked(path, message);
  response.message = message;
  response.frames = response.success ? uint32_t(detector_->loopDetector().database().size()) : 0;
  if (response.success)
  {
    NODELET_INFO_STREAM(message);
  }
  else
  {
    NODELET_WARN_STREAM(message << "; the current state is kept");
  }
  return true;
}

bool DetectorBase::reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!ready_)
  {
    response.success = false;
    response.message = "the detector is not running (see the start-up errors)";
    return true;
  }
  resetStreamLocked();
  response.success = true;
  response.message =
      detector_->localisationMode() ? "query sequences restarted; the reference map is kept" : "history cleared";
  NODELET_INFO_STREAM("reset: " << response.message);
  return true;
}

void DetectorBase::reconfigure(DetectorConfig& config, uint32_t /*level*/)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!ready_)
  {
    return;
  }
  openable::Config next = config_;
  next.threshold = config.threshold;
  next.sequence_length = config.sequence_length;
  next.min_sequence_length = config.min_sequence_length;
  next.exclusion_window = config.exclusion_window;
  next.top_k = config.top_k;
  next.min_uniqueness = config.min_uniqueness;
  next.uniqueness_window = config.uniqueness_window;
  next.bidirectional = config.bidirectional;
  next.color_map = config.color_map;
  try
  {
    detector_->updateConfig(next);
    config_ = next;
  }
  catch (const openable::Error& e)
  {
    NODELET_WARN_STREAM("dynamic_reconfigure refused: " << e.what() << "; keeping the previous values");
  }
  // Write back what is in force, so rqt_reconfigure shows the truth.
  config.threshold = config_.threshold;
  config.sequence_length = config_.sequence_length;
  config.min_sequence_length = config_.min_sequence_length;
  config.exclusion_window = config_.exclusion_window;
  config.top_k = config_.top_k;
  config.min_uniqueness = config_.min_uniqueness;
  config.uniqueness_window = config_.uniqueness_window;
  config.bidirectional = config_.bidirectional;
  config.color_map = config_.color_map;

  const double old_rate = matrix_rate_;
  matrix_rate_ = config.matrix_rate;
  matrix_threshold_view_ = config.matrix_threshold_view;
  try
  {
    view_.setSize(config.matrix_size);
  }
  catch (const openable::Error& e)
  {
    NODELET_WARN_STREAM("matrix_size: " << e.what());
  }
  view_.setMode(viewMode(config.matrix_mode));
  if (old_rate <= 0.0 && matrix_rate_ > 0.0)
  {
    // The view was not kept while off: start a fresh picture rather than a misleading one.
    view_.clear();
  }
}

void DetectorBase::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = std::max(1e-6, (now - last_diagnostic_time_).toSec());
  const double rate = double(frames_received_ - received_at_last_diagnostic_) / elapsed;
  uint64_t rejected_total = 0;
  for (const auto& r : rejected_)
  {
    rejected_total += r.second;
  }
  const uint64_t rejected_recently = rejected_total - rejected_at_last_diagnostic_;
  received_at_last_diagnostic_ = frames_received_;
  rejected_at_last_diagnostic_ = rejected_total;
  last_diagnostic_time_ = now;

  if (!ready_)
  {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "detector not running (see the start-up errors)");
    return;
  }
  if (rejected_recently > 0)
  {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%lu input frames rejected since the last report",
                    static_cast<unsigned long>(rejected_recently));
  }
  else
  {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, detector_->localisationMode() ? "localising" : "running");
  }
  status.add("mode", detector_->localisationMode() ? "localisation (query stream vs loaded map)"
                                                   : "loop closure (stream vs its own history)");
  status.add("input rate (Hz)", rate);
  status.add("frames received", frames_received_);
  status.add("frames stored", frames_stored_);
  status.add("frames skipped (not a keyframe)", frames_skipped_keyframe_);
  status.add("frames rejected", rejected_total);
  for (const auto& r : rejected_)
  {
    status.add("rejected: " + r.first, r.second);
  }
  // What is in force (dynamic_reconfigure may have changed it).
  status.add("threshold", config_.threshold);
  status.add("sequence length", config_.sequence_length);
  status.add("exclusion window", config_.exclusion_window);
  status.add("history size", detector_->loopDetector().database().size());
  status.add("history bytes", detector_->loopDetector().database().bytes());
  status.add("describe latency last (ms)", describe_latency_.last_ms);
  status.add("describe latency mean (ms)", describe_latency_.mean());
  status.add("match latency last (ms)", match_latency_.last_ms);
  status.add("match latency mean (ms)", match_latency_.mean());
  status.add("loop closures", loops_accepted_);
  status.add("distance_matrix images published", matrix_published_);
  if (options_.verify)
  {
    status.add("verification", detector_->hasVerifier() ? "on" : "waiting for camera_info");
  }
  for (const auto& r : statuses_)
  {
    status.add("frames " + r.first, r.second);
  }
}

}  // namespace openable_ros
