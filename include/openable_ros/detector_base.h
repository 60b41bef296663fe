#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/Point.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <array>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/distance_matrix_view.h"
#include "openable/geometric_verifier.h"
#include "openable/online_detector.h"
#include "openable_ros/DetectorConfig.h"
#include "openable_ros/LoadMap.h"
#include "openable_ros/LoopClosure.h"
#include "openable_ros/SaveMap.h"

namespace openable_ros
{
/// What the three detector nodelets share: the core OnlineDetector (the same pipeline openable_offline
/// runs), the outputs
/// (loop_closures, distance_matrix, loop_markers, diagnostics), the services (~save_map, ~load_map,
/// ~reset), dynamic_reconfigure, tf poses and keyframing. A derived nodelet only subscribes to its inputs
/// and, per synchronised input set, turns the messages into a descriptor through processFrame().
///
/// Threading: every entry point (frame callbacks, services, dynamic_reconfigure, diagnostics) takes
/// mutex_, so the nodelet is safe on a multi-threaded callback queue too.
class DetectorBase : public nodelet::Nodelet
{
public:
  DetectorBase();
  ~DetectorBase() override;

protected:
  /// Reads the parameters (core keys and ROS-only ones, explaining every fallback), builds the detector
  /// (from ~map_file when it exists), advertises outputs and services, starts dynamic_reconfigure and
  /// diagnostics. `defaults` is the nodelet's configuration before parameters (its camera_type...).
  /// Returns false after logging why when the detector cannot be built: the nodelet then stays loaded
  /// but idle (never throws: that would take the whole manager down).
  bool setupDetector(const openable::Config& defaults);

  /// One synchronised input set (images converted by the nodelet; stamp, session, source and pose are
  /// filled here): checks the stamp (time jumps), looks up the pose (tf), runs it through the core
  /// OnlineDetector (keyframe, describe, match, decide, verify), publishes the loop closure and the frame's
  /// decision, updates the distance matrix and markers. `topic` names the input in warnings. Never throws.
  void processFrame(const std_msgs::Header& header, const std::string& topic, openable::FrameInput input);

  /// With ~verify: builds the geometric verifier from the first valid camera (from camera_info). Later
  /// calls with the same camera do nothing; another camera is refused with a warning.
  void setCamera(const openable::PinholeCamera& camera);
  /// True when ~verify is on (the nodelet then subscribes camera_info and passes VerifyImages).
  bool verifyEnabled() const
  {
    return options_.verify;
  }

  /// Counts a rejected input under `reason` (shown in diagnostics) and warns, throttled per reason.
  void rejectFrame(const std::string& reason, const std::string& message);
  /// NODELET_WARN at most once per `period` seconds per `key` (members, not macro statics: several
  /// nodelets in one manager must not silence each other).
  void warnThrottled(const std::string& key, double period, const std::string& message);

  /// Watches synchronised inputs: warns every ~sync_warning_timeout seconds while messages arrive but no
  /// complete set does (or nothing ever arrived), naming each topic with the messages it received since the
  /// last set (rtabmap's SyncDiagnostic idea). A stream that stopped altogether is not warned about. Call noteInput()
  /// from each input's own callback and noteSynchronised() when a set is complete.
  void startSyncWatchdog(const std::vector<std::string>& topics, const std::string& advice);
  void noteInput(size_t index);
  void noteSynchronised();

  /// Input queue size for subscribers (~queue_size).
  int queueSize() const
  {
    return queue_size_;
  }
  /// The configuration in use (after parameter validation).
  const openable::Config& config() const
  {
    return config_;
  }
  /// Seconds without a complete input set after which derived nodelets warn (~sync_warning_timeout).
  double syncWarningTimeout() const
  {
    return sync_warning_timeout_;
  }

private:
  struct Latency
  {
    double last_ms = 0.0;
    double total_ms = 0.0;
    uint64_t count = 0;
    void add(double ms)
    {
      last_ms = ms;
      total_ms += ms;
      ++count;
    }
    double mean() const
    {
      return count ? total_ms / double(count) : 0.0;
    }
  };

  bool loadMapLocked(const std::string& path, std::string& message);
  bool checkTimeLocked(const std_msgs::Header& header, const std::string& topic);
  /// Camera pose in ~fixed_frame at the header's stamp; false (with a throttled warning) without tf.
  bool lookupPoseLocked(const std_msgs::Header& header, std::array<double, 7>& pose);
  void publishOutcomeLocked(const std_msgs::Header& header, const openable::FrameOutcome& outcome);
  void publishMatrixLocked(const std_msgs::Header& header);
  void publishMarkersLocked(const std_msgs::Header& header, bool force);
  void resetStreamLocked();
  void reconfigure(DetectorConfig& config, uint32_t level);
  /// Why a save/load request for `path` cannot run (empty when it can).
  std::string mapServiceRefusal(const std::string& path) const;
  bool saveMap(SaveMap::Request& request, SaveMap::Response& response);
  bool loadMap(LoadMap::Request& request, LoadMap::Response& response);
  bool reset(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  std::mutex mutex_;
  bool ready_ = false;
  openable::Config config_;
  openable::OnlineOptions options_;
  std::unique_ptr<openable::OnlineDetector> detector_;
  openable::DistanceMatrixView view_;

  // ROS-only parameters.
  std::string fixed_frame_;
  std::string map_file_;
  double tf_timeout_ = 0.05;
  bool reset_on_time_jump_ = false;
  double matrix_rate_ = 2.0;
  bool matrix_threshold_view_ = false;
  double markers_rate_ = 1.0;
  int queue_size_ = 10;
  double sync_warning_timeout_ = 5.0;
  uint32_t session_ = 0;
  std::map<std::string, uint64_t> statuses_;  ///< frames per decision status (diagnostics)

  // Outputs and services.
  ros::Publisher loop_pub_;
  ros::Publisher decisions_pub_;
  ros::Publisher markers_pub_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::Publisher matrix_pub_;
  ros::ServiceServer save_srv_;
  ros::ServiceServer load_srv_;
  ros::ServiceServer reset_srv_;
  std::unique_ptr<dynamic_reconfigure::Server<DetectorConfig>> reconfigure_server_;
  boost::recursive_mutex reconfigure_mutex_;  // dynamic_reconfigure wants a boost mutex
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Timer diagnostics_timer_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  // Stream state.
  ros::Time last_stamp_;
  ros::WallTime last_matrix_time_;
  ros::WallTime last_markers_time_;
  std::vector<float> row_;
  std::deque<geometry_msgs::Point> trajectory_;
  std::deque<std::pair<geometry_msgs::Point, geometry_msgs::Point>> loop_edges_;
  std::map<std::string, ros::WallTime> last_warning_;

  // Synchronisation watchdog.
  void checkSync();
  std::vector<std::string> sync_topics_;
  std::vector<uint64_t> sync_counts_;
  std::vector<uint64_t> sync_counts_at_last_set_;
  std::string sync_advice_;
  uint64_t sync_sets_ = 0;
  ros::WallTime last_sync_time_;
  ros::WallTimer sync_timer_;

  // Diagnostics counters.
  uint64_t frames_received_ = 0;
  uint64_t frames_stored_ = 0;
  uint64_t frames_skipped_keyframe_ = 0;
  uint64_t loops_accepted_ = 0;
  uint64_t matrix_published_ = 0;
  std::map<std::string, uint64_t> rejected_;
  uint64_t received_at_last_diagnostic_ = 0;
  uint64_t rejected_at_last_diagnostic_ = 0;
  ros::WallTime last_diagnostic_time_;
  Latency describe_latency_;
  Latency match_latency_;
};

}  // namespace openable_ros
