#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <sensor_msgs/NavSatFix.h>
#include <std_msgs/Header.h>

#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "openable/description/input_contract.h"
#include "openable/detection/online_detector.h"
#include "openable/node_support/sync_watch.h"
#include "openable/node_support/throttle.h"
#include "openable_ros/LoopClosure.h"
#include "openable_ros/detector_diagnostics.h"
#include "openable/node_support/fix_history.h"
#include "openable_ros/loop_markers.h"
#include "openable_ros/matrix_publisher.h"
#include "openable_ros/pose_lookup.h"
#include "openable_ros/ros_parameters.h"
#include "openable/node_support/sequence_gaps.h"

namespace openable_ros
{
class MapServices;
class LiveReconfigure;
class DescriptorPublisher;

/// What the three detector nodelets share, by composition: the core OnlineDetector (the pipeline
/// openable_offline runs too) and the ROS pieces around it — pose lookup (tf), loop_closures / decisions,
/// the distance matrix, markers, diagnostics, map services, dynamic_reconfigure and the sync watchdog.
/// A nodelet owns one, converts its messages into an openable::FrameInput and calls process().
///
/// A frame's way: the nodelet's callback -> process() -> OnlineDetector::process() -> publish().
/// Threading: every entry point takes mutex_, so a multi-threaded callback queue is safe.
class Detector
{
public:
  /// Reads the parameters (explaining every fallback), builds the core detector (from ~map_file when it
  /// exists) and the outputs, then starts the services, dynamic_reconfigure and diagnostics. `defaults`
  /// is the nodelet's configuration before parameters (its camera_type). Returns nullptr after logging
  /// why when the detector cannot run; never throws (a throw would take the whole manager down).
  static std::unique_ptr<Detector> create(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                                          const openable::Config& defaults, const RosParameters& parameters);
  ~Detector();

  /// One synchronised input set. `topic` names the input in warnings and in the stored frame's source.
  void process(const std_msgs::Header& header, const std::string& topic, openable::FrameInput input);
  /// Counts an input refused before the core saw it (size mismatch, uncalibrated camera...) under `reason`
  /// and warns, throttled per reason.
  void reject(const std::string& reason, const std::string& message);
  /// The same for an image the conversion refused (toCoreImage, toDisparity): its reason, "'topic': what".
  void reject(const openable::InputProblem& problem, const std::string& topic);
  /// The camera for geometric verification (~verify), from camera_info.
  void setCamera(const openable::PinholeCamera& camera);
  /// Warns while synchronised inputs arrive without pairing up (or nothing ever arrives).
  void watchSync(const std::vector<std::string>& topics, const std::string& advice);
  /// A message reached input `index` (its header's seq and stamp, for the frames lost in queues:
  /// SequenceGaps).
  void noteInput(size_t index, const std_msgs::Header& header);
  void noteSet();
  void noteDropped(size_t dropped);

  const RosParameters& parameters() const
  {
    return parameters_;
  }
  /// The configuration in force (dynamic_reconfigure may change it).
  openable::Config config();

  // For the services, dynamic_reconfigure and diagnostics.
  bool saveMap(const std::string& path, std::string& message, uint32_t& frames);
  bool loadMap(const std::string& path, std::string& message, uint32_t& frames);
  std::string reset();
  /// New live values (core keys flagged live, and the display parameters); refused ones are reverted in
  /// `requested` and logged. Returns what is in force.
  void applyLive(openable::Config& requested, RosParameters& display);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

private:
  Detector(ros::NodeHandle nh, ros::NodeHandle pnh, std::string name, RosParameters parameters);
  void publish(const std_msgs::Header& header, const openable::FrameOutcome& outcome);
  /// Frames counted under `from` that turned out `to` (a pending loop closure confirmed or dropped).
  void moveStatus(openable::FrameStatus from, openable::FrameStatus to, uint64_t frames);
  /// One loop closure out: the topic, the counters, the matrix and the markers (`current`: the frame being handled).
  void publishLoop(const LoopClosurePtr& msg, const openable::FrameOutcome& loop, const openable::FrameOutcome& current);
  /// The bookkeeping of a stored frame: counters, descriptors out, markers, the distance matrix's row.
  void recordStored(const std_msgs::Header& header, const openable::FrameOutcome& outcome);
  bool acceptStamp(const std_msgs::Header& header, const std::string& topic, openable::FrameOutcome& outcome,
                   openable::FrameInput& input);
  void resetLocked();
  /// A detector with an empty map whose one session is this run's (sessionName(), ~robot).
  std::unique_ptr<openable::OnlineDetector> freshDetector(const openable::Config& config) const;
  /// ~session_name, or "<node name> <start time>" when it is empty.
  std::string sessionName() const;
  /// Gives `next` the camera the current detector verifies with (a reset or a map keeps it).
  void keepCamera(openable::OnlineDetector& next) const;
  /// ~fix: kept for the frames around its stamp (FixHistory).
  void fixCallback(const sensor_msgs::NavSatFixConstPtr& msg);
  /// (Re)starts ~geo_file with its header: frame ids start again after a reset or a map load.
  void restartGeoFile();
  void warnThrottled(const std::string& key, double period, const std::string& message);
  /// Every refusal goes here (mutex_ held): counted under `reason` (diagnostics `rejected: <reason>`) and
  /// warned with the reason's own throttle, so one reason never silences another.
  void refuse(const std::string& reason, const std::string& message);

  std::mutex mutex_;
  ros::NodeHandle nh_, pnh_;
  std::string name_;
  RosParameters parameters_;
  std::string session_default_;
  openable::OnlineOptions options_;
  std::unique_ptr<openable::OnlineDetector> detector_;
  std::unique_ptr<PoseLookup> poses_;
  std::unique_ptr<MatrixPublisher> matrix_;
  std::unique_ptr<LoopMarkers> markers_;
  ros::Publisher loop_pub_;
  ros::Publisher decisions_pub_;
  FrameCounters counters_;
  uint64_t counted_dropped_ = 0;  ///< detector_->confirmation().dropped() already moved to "unconfirmed"
  openable::SequenceGaps gaps_;
  openable::FixHistory fixes_;
  ros::Subscriber fix_sub_;
  std::ofstream geo_out_;
  DetectorDiagnostics diagnostics_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Timer diagnostics_timer_;
  std::unique_ptr<MapServices> services_;
  std::unique_ptr<DescriptorPublisher> descriptors_;  ///< place_descriptors, with ~publish_descriptors
  std::unique_ptr<LiveReconfigure> reconfigure_;
  std::unique_ptr<openable::SyncWatch> sync_;
  ros::WallTimer sync_timer_;
  openable::Throttle throttle_;
  std::vector<float> row_;
};

}  // namespace openable_ros
