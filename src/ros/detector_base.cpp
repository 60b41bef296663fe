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
  keyframe_distance_ = readDouble(pnh, "keyframe_distance", 0.0, 0.0, 1e6, "m", warnings);
  keyframe_angle_ = readDouble(pnh, "keyframe_angle", 0.0, 0.0, M_PI, "rad", warnings);
  reset_on_time_jump_ = readBool(pnh, "reset_on_time_jump", false, warnings);
  matrix_rate_ = readDouble(pnh, "matrix_rate", 2.0, 0.0, 30.0, "Hz", warnings);
  markers_rate_ = readDouble(pnh, "markers_rate", 1.0, 0.0, 30.0, "Hz", warnings);
  queue_size_ = readInt(pnh, "queue_size", 10, 1, 10000, warnings);
  sync_warning_timeout_ = readDouble(pnh, "sync_warning_timeout", 5.0, 0.0, 3600.0, "s", warnings);
  session_ = uint32_t(readInt(pnh, "session", 0, 0, 1000000000, warnings));
  const int matrix_size = readInt(pnh, "matrix_size", 512, 16, 4096, warnings);
  // On by default: it only runs once camera_info arrives; until then loops go out unverified.
  verify_ = readBool(pnh, "verify", true, warnings);
  verify_required_ = readBool(pnh, "verify_required", true, warnings);
  const double verify_memory = readDouble(pnh, "verify_memory", 256.0, 1.0, 65536.0, "MB", warnings);
  features_ = openable::FeatureStore(size_t(verify_memory * 1024.0 * 1024.0));
  std::string matrix_mode = readString(pnh, "matrix_mode", "whole_history", warnings);
  const bool matrix_threshold_view = readBool(pnh, "matrix_threshold_view", false, warnings);
  if (matrix_mode != "whole_history" && matrix_mode != "rolling_window")
  {
    warnings.push_back("~matrix_mode: value '" + matrix_mode +
                       "' is not allowed; expected whole_history | rolling_window; using whole_history");
    matrix_mode = "whole_history";
  }
  if ((keyframe_distance_ > 0.0 || keyframe_angle_ > 0.0) && fixed_frame_.empty())
  {
    warnings.push_back(
        "~keyframe_distance / ~keyframe_angle need ~fixed_frame for the camera poses; "
        "~fixed_frame is empty, so every frame is kept");
    keyframe_distance_ = 0.0;
    keyframe_angle_ = 0.0;
  }
  for (const auto& warning : warnings)
  {
    NODELET_WARN_STREAM("parameter " << warning);
  }

  std::unique_lock<std::mutex> lock(mutex_);
  try
  {
    describer_ = std::make_unique<openable::FrameDescriber>(config);
    config_ = config;
    detector_ = std::make_unique<openable::LoopDetector>(config_);
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

bool DetectorBase::isKeyframeLocked(bool has_pose, const std::array<double, 7>& pose)
{
  if (keyframe_distance_ <= 0.0 && keyframe_angle_ <= 0.0)
  {
    return true;
  }
  // Without a pose the motion is unknown: keeping the frame loses nothing, skipping it could.
  if (!has_pose)
  {
    return true;
  }
  if (!has_keyframe_pose_)
  {
    has_keyframe_pose_ = true;
    keyframe_pose_ = pose;
    return true;
  }
  const double dx = pose[0] - keyframe_pose_[0];
  const double dy = pose[1] - keyframe_pose_[1];
  const double dz = pose[2] - keyframe_pose_[2];
  const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
  const tf2::Quaternion a(keyframe_pose_[3], keyframe_pose_[4], keyframe_pose_[5], keyframe_pose_[6]);
  const tf2::Quaternion b(pose[3], pose[4], pose[5], pose[6]);
  const double angle = a.normalized().angleShortestPath(b.normalized());
  const bool moved = (keyframe_distance_ > 0.0 && distance >= keyframe_distance_) ||
                     (keyframe_angle_ > 0.0 && angle >= keyframe_angle_);
  if (moved)
  {
    keyframe_pose_ = pose;
  }
  return moved;
}

void DetectorBase::setCamera(const openable::PinholeCamera& camera)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!verify_ || !ready_)
  {
    return;
  }
  if (verifier_)
  {
    const openable::PinholeCamera& c = verifier_->camera();
    if (c.fx != camera.fx || c.fy != camera.fy || c.cx != camera.cx || c.cy != camera.cy ||
        c.baseline != camera.baseline)
    {
      warnThrottled("camera changed", 60.0,
                    "camera_info changed after the verifier was built; keeping the first calibration");
    }
    return;
  }
  try
  {
    verifier_ = std::make_unique<openable::GeometricVerifier>(camera);
    NODELET_INFO_STREAM("geometric verification on: fx " << camera.fx << ", baseline " << camera.baseline << " m ("
                                                         << (camera.stereo() ? "stereo PnP" : "mono essential") << ")");
  }
  catch (const openable::Error& e)
  {
    warnThrottled("camera", 10.0, std::string("~verify: camera_info cannot be used: ") + e.what());
  }
}

bool DetectorBase::verifyLoopLocked(const openable::Detection& detection, const openable::FrameFeatures* query,
                                    LoopClosure& msg)
{
  if (!verify_)
  {
    return true;
  }
  std::string outcome;
  if (!verifier_)
  {
    outcome = "no camera_info yet";
  }
  else if (!query)
  {
    outcome = "no query features";
  }
  else
  {
    const openable::FrameFeatures* match = features_.find(detection.best.id);
    if (!match)
    {
      outcome = "match frame has no features (map or evicted)";
    }
    else
    {
      const openable::Verification v = verifier_->verify(*match, *query);
      outcome = openable::toString(v.status);
      if (v.accepted())
      {
        msg.has_relative_pose = true;
        msg.relative_pose.pose.position.x = v.translation[0];
        msg.relative_pose.pose.position.y = v.translation[1];
        msg.relative_pose.pose.position.z = v.translation[2];
        tf2::Matrix3x3 rotation(v.rotation(0, 0), v.rotation(0, 1), v.rotation(0, 2), v.rotation(1, 0),
                                v.rotation(1, 1), v.rotation(1, 2), v.rotation(2, 0), v.rotation(2, 1),
                                v.rotation(2, 2));
        tf2::Quaternion q;
        rotation.getRotation(q);
        msg.relative_pose.pose.orientation.x = q.x();
        msg.relative_pose.pose.orientation.y = q.y();
        msg.relative_pose.pose.orientation.z = q.z();
        msg.relative_pose.pose.orientation.w = q.w();
        for (int r = 0; r < 6; ++r)
        {
          for (int c = 0; c < 6; ++c)
          {
            msg.relative_pose.covariance[size_t(r * 6 + c)] = v.covariance(r, c);
          }
        }
        ++verification_results_["accepted"];
        return true;
      }
      outcome += v.reason.empty() ? "" : " (" + v.reason + ")";
      ++verification_results_[openable::toString(v.status)];
      if (verify_required_)
      {
        warnThrottled("verification", kWarnPeriod,
                      "loop closure " + std::to_string(detection.query_id) + " -> " +
                          std::to_string(detection.best.id) + " not published: geometric verification " + outcome);
        return false;
      }
      return true;
    }
  }
  // Verification could not run: the loop goes out unverified (has_relative_pose false).
  ++verification_results_[outcome];
  warnThrottled("verification unavailable", 30.0, "~verify: loop closure published unverified: " + outcome);
  return true;
}

void DetectorBase::processFrame(const std_msgs::Header& header, const std::string& topic,
                                const DescribeFunction& describe, const VerifyImages& verify_images)
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

  openable::FrameInfo info;
  info.stamp = header.stamp.toSec();
  info.session = session_;
  info.source = topic;
  info.has_pose = lookupPoseLocked(header, info.pose);
  if (!isKeyframeLocked(info.has_pose, info.pose))
  {
    ++frames_skipped_keyframe_;
    return;
  }

  openable::FrameDescriptor descriptor;
  openable::Detection detection;
  try
  {
    const auto start_describe = std::chrono::steady_clock::now();
    descriptor = describe(*describer_);
    describe_latency_.add(millisecondsSince(start_describe));
    const auto start_match = std::chrono::steady_clock::now();
    detection = detector_->process(descriptor, info);
    match_latency_.add(millisecondsSince(start_match));
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
  if (!detector_->localisationMode())
  {
    ++frames_stored_;
  }
  // Features of this frame for verifying its loops (and, stored, the loops of later frames to it).
  std::unique_ptr<openable::FrameFeatures> features;
  if (verifier_ && !verify_images.left.empty())
  {
    try
    {
      features = std::make_unique<openable::FrameFeatures>(
          verifier_->extract(verify_images.left, verify_images.right, detection.query_id));
    }
    catch (const openable::Error& e)
    {
      warnThrottled("features", kWarnPeriod, "'" + topic + "': no features for verification: " + e.what());
    }
    catch (const cv::Exception& e)
    {
      warnThrottled("features", kWarnPeriod, "'" + topic + "': no features for verification (OpenCV): " + e.what());
    }
  }
  if (info.has_pose)
  {
    trajectory_.push_back(position(info.pose));
    while (trajectory_.size() > kMaxTrajectoryPoints)
    {
      trajectory_.pop_front();
    }
  }

  if (matrix_rate_ > 0.0)
  {
    detector_->lastRow(row_);
    view_.addRow(detector_->database().firstId(), row_);
  }
  if (detection.accepted)
  {
    publishLoopLocked(header, detection, info, features.get());
  }
  if (features && !detector_->localisationMode())
  {
    features_.insert(std::move(*features));
  }
  publishMatrixLocked(header);
  publishMarkersLocked(header, detection.accepted);
}

void DetectorBase::publishLoopLocked(const std_msgs::Header& header, const openable::Detection& detection,
                                     const openable::FrameInfo& query, const openable::FrameFeatures* features)
{
  // Positions shift when the history evicts its oldest frames while storing the query: find the match
  // by id. An evicted match still gives a message, without its stamp and pose.
  const openable::PlaceDatabase& database = detector_->database();
  const openable::FrameInfo* match = nullptr;
  if (detection.best.id >= database.firstId() && detection.best.id - database.firstId() < database.size())
  {
    match = &database.info(size_t(detection.best.id - database.firstId()));
  }
  LoopClosurePtr msg = makeLoopClosure(header, detection, query, match);
  if (!verifyLoopLocked(detection, features, *msg))
  {
    return;
  }
  ++loops_accepted_;
  if (matrix_rate_ > 0.0)
  {
    view_.addLoop(detection.best.id);
  }
  if (msg->has_poses)
  {
    geometry_msgs::Point a = msg->query_pose.position;
    geometry_msgs::Point b = msg->match_pose.position;
    loop_edges_.emplace_back(a, b);
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
  features_.clear();
  has_keyframe_pose_ = false;
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
      return openable::PlaceDatabase(describer_->layout());
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
  if (map.layout() != describer_->layout())
  {
    message = "map '" + path + "' refused: its descriptor layout differs from this detector's";
    return false;
  }
  try
  {
    const size_t frames = map.size();
    auto detector = std::make_unique<openable::LoopDetector>(config_, std::move(map));
    detector_ = std::move(detector);
    message = "map '" + path + "' loaded: " + std::to_string(frames) + " frames; localising against it";
  }
  catch (const openable::Error& e)
  {
    message = "map '" + path + "' refused: " + e.what();
    return false;
  }
  features_.clear();
  view_.clear();
  trajectory_.clear();
  loop_edges_.clear();
  has_keyframe_pose_ = false;
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
    detector_->database().save(path);
    response.success = true;
    response.frames = uint32_t(detector_->database().size());
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
  response.frames = response.success ? uint32_t(detector_->database().size()) : 0;
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
    detector_->updateMatching(next);
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
  status.add("history size", detector_->database().size());
  status.add("history bytes", detector_->database().bytes());
  status.add("describe latency last (ms)", describe_latency_.last_ms);
  status.add("describe latency mean (ms)", describe_latency_.mean());
  status.add("match latency last (ms)", match_latency_.last_ms);
  status.add("match latency mean (ms)", match_latency_.mean());
  status.add("loop closures", loops_accepted_);
  status.add("distance_matrix images published", matrix_published_);
  if (verify_)
  {
    status.add("verification", verifier_ ? "on" : "waiting for camera_info");
    status.add("verification features bytes", features_.bytes());
    for (const auto& r : verification_results_)
    {
      status.add("verification: " + r.first, r.second);
    }
  }
}

}  // namespace openable_ros
