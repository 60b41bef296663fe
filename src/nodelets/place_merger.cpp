// openable_ros/PlaceMerger: the loop closures of several PlaceServers that split the sessions, as one
// server holding them all would publish them.
#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>

#include <algorithm>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>

#include "openable/server/answer_collector.h"
#include "openable/node_support/throttle.h"
#include "openable_ros/place_messages.h"
#include "openable_ros/params.h"

namespace openable_ros
{
class PlaceMerger : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::vector<std::string> warnings;
    // ~servers: the servers' namespaces (each publishes <ns>/candidates), or their count when they all
    // publish on this node's `candidates`.
    std::vector<std::string> topics;
    int count = 0;
    XmlRpc::XmlRpcValue servers;
    if (pnh.getParam("servers", servers) && servers.getType() == XmlRpc::XmlRpcValue::TypeArray)
    {
      for (const auto& ns : readStringList(pnh, "servers", warnings))
        topics.push_back(ns + "/candidates");
      count = int(topics.size());
    }
    else
    {
      count = readInt(pnh, "servers", 2, 1, 1000, warnings);
      topics.push_back("candidates");
    }
    const double wait = readDouble(pnh, "wait", 2.0, 0.01, 600.0, "s", warnings);
    openable::Config base;
    const std::string file = readString(pnh, "config", "", warnings);
    try
    {
      if (!file.empty())
        base = openable::Config::fromYamlFile(file);
      config_ = loadCoreConfig(pnh, base, warnings);
      merger_ = std::make_unique<openable::CandidateMerger>(config_);
    }
    catch (const std::exception& e)
    {
      NODELET_ERROR_STREAM("~config '" << file << "': " << e.what() << "; this merger stays idle");
      return;
    }
    for (const auto& w : warnings)
      NODELET_WARN_STREAM("parameter " << w);
    collector_ = std::make_unique<openable::AnswerCollector>(size_t(count), wait);
    loop_pub_ = nh.advertise<LoopClosure>("loop_closures", 100);
    decisions_pub_ = nh.advertise<LoopClosure>("decisions", 100);
    for (const auto& topic : topics)
      subscribers_.push_back(nh.subscribe(topic, 1000, &PlaceMerger::candidatesCallback, this));
    // Queries a server never answers leave after ~wait, counted.
    timer_ = nh.createWallTimer(ros::WallDuration(std::min(wait / 4.0, 0.1)), [this](const ros::WallTimerEvent&) {
      std::lock_guard<std::mutex> lock(mutex_);
      decide(collector_->expire(ros::WallTime::now().toSec()));
    });
    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
    updater_->setHardwareID(getName());
    updater_->add("place merger", [this](diagnostic_updater::DiagnosticStatusWrapper& s) { diagnose(s); });
    diagnostics_timer_ = nh.createTimer(ros::Duration(0.1), [this](const ros::TimerEvent&) { updater_->update(); });
    NODELET_INFO_STREAM("place merger ready: " << count << " servers, waiting at most " << wait << " s for each");
  }

  void candidatesCallback(const PlaceCandidatesConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    headers_[msg->query_session + "#" + std::to_string(msg->query_frame)] = msg->header;
    decide(collector_->add(fromMsg(*msg), ros::WallTime::now().toSec()));
  }

  void decide(const std::vector<std::vector<openable::ServerCandidates>>& queries)
  {
    for (const auto& answers : queries)
    {
      const std::string key = answers.front().query_session + "#" + std::to_string(answers.front().query_frame);
      const std_msgs::Header header = headers_[key];
      headers_.erase(key);
      try
      {
        const openable::MergedOutcome outcome = merger_->merge(answers);
        LoopClosurePtr loop = makeLoopClosure(header, outcome, *merger_);
        if (decisions_pub_.getNumSubscribers() > 0)
          decisions_pub_.publish(LoopClosureConstPtr(loop));
        if (outcome.published())
        {
          ++loops_;
          loop_pub_.publish(LoopClosureConstPtr(loop));
        }
        // Earlier queries this one confirmed (confirm_frames), each with its own stamp.
        for (const openable::MergedOutcome& earlier : outcome.confirmed)
        {
          std_msgs::Header earlier_header = header;
          earlier_header.stamp = ros::Time(std::max(0.0, earlier.query_stamp));
          ++loops_;
          loop_pub_.publish(LoopClosureConstPtr(makeLoopClosure(earlier_header, earlier, *merger_)));
        }
      }
      catch (const std::exception& e)
      {
        if (throttle_.ready("merge", ros::WallTime::now().toSec(), 5.0))
          NODELET_WARN_STREAM("cannot merge the answers to '" << key << "': " << e.what());
      }
    }
    if (collector_->incomplete() > warned_incomplete_ && throttle_.ready("missing", ros::WallTime::now().toSec(), 5.0))
    {
      warned_incomplete_ = collector_->incomplete();
      NODELET_WARN_STREAM(warned_incomplete_ << " queries decided without every server's answer (a server is "
                                                "missing or slower than ~wait)");
    }
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool missing = collector_->incomplete() > 0;
    status.summary(missing ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                   missing ? "queries decided without every server" : "merging");
    status.add("queries without every server", collector_->incomplete());
    status.add("answers too late", collector_->late());
    status.add("queries waiting", collector_->waiting());
    status.add("sessions", merger_->sessionNames().size());
    status.add("loop closures", loops_);
  }

  std::mutex mutex_;
  openable::Config config_;
  std::unique_ptr<openable::CandidateMerger> merger_;
  std::unique_ptr<openable::AnswerCollector> collector_;
  std::map<std::string, std_msgs::Header> headers_;  ///< the query's header, until it is decided
  std::vector<ros::Subscriber> subscribers_;
  ros::Publisher loop_pub_, decisions_pub_;
  ros::WallTimer timer_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Timer diagnostics_timer_;
  openable::Throttle throttle_;
  size_t loops_ = 0;
  size_t warned_incomplete_ = 0;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::PlaceMerger, nodelet::Nodelet)
