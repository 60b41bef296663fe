#include "openable_ros/place_server_host.h"

#include <algorithm>
#include <fstream>

#include "openable_ros/place_messages.h"
#include "openable_ros/params.h"

namespace openable_ros
{
namespace
{
const double kWarnPeriod = 5.0;  // seconds between two warnings of one kind

/// "robot1" -> "robot1/place_descriptors"; a full topic name stays as it is.
std::string descriptorTopic(const std::string& entry)
{
  const std::string suffix = "place_descriptors";
  if (entry.size() >= suffix.size() && entry.compare(entry.size() - suffix.size(), suffix.size(), suffix) == 0)
    return entry;
  return entry + "/" + suffix;
}

/// ~config (a YAML file) under the core keys set as private parameters.
bool readConfig(const ros::NodeHandle& pnh, const std::string& name, openable::Config& config)
{
  std::vector<std::string> warnings;
  const std::string file = readString(pnh, "config", "", warnings);
  openable::Config base;
  if (!file.empty())
  {
    try
    {
      base = openable::Config::fromYamlFile(file);
    }
    catch (const std::exception& e)
    {
      ROS_ERROR_STREAM_NAMED(name, "~config '" << file << "': " << e.what() << "; this server stays idle");
      return false;
    }
  }
  config = loadCoreConfig(pnh, base, warnings);
  for (const auto& w : warnings)
    ROS_WARN_STREAM_NAMED(name, "parameter " << w);
  return true;
}
}  // namespace

PlaceServerHost::PlaceServerHost(ros::NodeHandle nh, ros::NodeHandle pnh, std::string name)
  : nh_(nh), pnh_(pnh), name_(std::move(name))
{
}

PlaceServerHost::~PlaceServerHost()
{
  diagnostics_timer_.stop();
}

std::unique_ptr<PlaceServerHost> PlaceServerHost::create(ros::NodeHandle nh, ros::NodeHandle pnh,
                                                         const std::string& name)
{
  std::unique_ptr<PlaceServerHost> h(new PlaceServerHost(nh, pnh, name));
  openable::Config config;
  if (!readConfig(pnh, name, config))
    return nullptr;
  std::vector<std::string> warnings;
  const std::vector<std::string> robots = readStringList(pnh, "robots", warnings);
  const std::vector<std::string> sessions = readStringList(pnh, "sessions", warnings);
  h->publish_candidates_ = readBool(pnh, "publish_candidates", !sessions.empty(), warnings);
  const int queue = readInt(pnh, "queue_size", 1000, 1, 100000, warnings);
  h->map_file_ = readString(pnh, "map_file", "", warnings);
  for (const auto& w : warnings)
    ROS_WARN_STREAM_NAMED(name, "parameter " << w);
  try
  {
    // The server's name orders equal distances in a merger: the node's name is unique on a ROS network.
    h->server_ = std::make_unique<openable::PlaceServer>(config, sessions, name);
    // Holding every session, this server decides alone; splitting them, only a merger can.
    if (sessions.empty())
      h->merger_ = std::make_unique<openable::CandidateMerger>(config);
  }
  catch (const std::exception& e)
  {
    ROS_ERROR_STREAM_NAMED(name, "cannot build the place server: " << e.what() << "; this server stays idle");
    return nullptr;
  }
  if (!h->map_file_.empty() && std::ifstream(h->map_file_).good())
  {
    try
    {
      h->server_->load(h->map_file_);
      ROS_INFO_STREAM_NAMED(name, "~map_file '" << h->map_file_ << "': " << h->server_->map().sessionCount()
                                                << " sessions, " << h->server_->map().frameCount() << " frames");
    }
    catch (const std::exception& e)
    {
      ROS_WARN_STREAM_NAMED(name, "~map_file: " << e.what() << "; starting with an empty map");
    }
  }

  PlaceServerHost* self = h.get();
  if (h->merger_)
  {
    h->loop_pub_ = nh.advertise<LoopClosure>("loop_closures", 100);
    h->decisions_pub_ = nh.advertise<LoopClosure>("decisions", 100);
  }
  if (h->publish_candidates_)
    h->candidates_pub_ = nh.advertise<PlaceCandidates>("candidates", 1000);
  for (const std::string& entry : robots.empty() ? std::vector<std::string>{""} : robots)
  {
    const std::string topic = entry.empty() ? "place_descriptors" : descriptorTopic(entry);
    // One topic per robot: its messages must name that robot (the detector's default name, from its
    // namespace). The single topic without ~robots carries every robot: not checked.
    const std::string robot = entry.empty() ? "" : openable::robotOfTopic(nh.resolveName(topic));
    h->subscribers_.push_back(nh.subscribe<PlaceDescriptor>(
        topic, uint32_t(queue),
        [self, topic, robot](const PlaceDescriptorConstPtr& msg) { self->descriptorCallback(msg, topic, robot); }));
  }
  h->save_srv_ = pnh.advertiseService("save_map", &PlaceServerHost::save, self);
  h->load_srv_ = pnh.advertiseService("load_map", &PlaceServerHost::load, self);
  h->updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, name);
  h->updater_->setHardwareID(name);
  h->updater_->add("place server", [self](diagnostic_updater::DiagnosticStatusWrapper& s) { self->diagnose(s); });
  h->diagnostics_timer_ =
      nh.createTimer(ros::Duration(0.1), [self](const ros::TimerEvent&) { self->updater_->update(); });

  std::string owned;
  for (const auto& s : sessions)
    owned += (owned.empty() ? "" : ", ") + s;
  ROS_INFO_STREAM_NAMED(name, "place server ready: " << config.descriptor << ", patch " << config.patch_size
                                                     << ", L = " << config.sequence_length << ", configuration hash 0x"
                                                     << std::hex << h->server_->configHash() << std::dec << "; "
                                                     << robots.size() << " robot topics; sessions: "
                                                     << (owned.empty() ? "all" : owned)
                                                     << (h->publish_candidates_ ? "; publishing candidates" : ""));
  return h;
}

void PlaceServerHost::descriptorCallback(const PlaceDescriptorConstPtr& msg, const std::string& topic,
                                         const std::string& robot)
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
  openable::ServerCandidates answer;
  try
  {
    openable::PlaceDescriptorInput input = toInput(*msg);
    input.topic_robot = robot;
    answer = server_->process(input);
  }
  catch (const openable::DescriptorRefused& e)
  {
    ++refused_by_robot_[msg->robot];
    if (throttle_.ready(msg->robot + " " + e.reason(), ros::WallTime::now().toSec(), kWarnPeriod))
      ROS_WARN_STREAM_NAMED(name_, "'" << topic << "': " << e.what() << " (descriptor refused)");
    return;
  }
  catch (const std::exception& e)
  {
    // Nothing from the core may unwind into the nodelet manager.
    if (throttle_.ready("exception", ros::WallTime::now().toSec(), kWarnPeriod))
      ROS_WARN_STREAM_NAMED(name_, "'" << topic << "': " << e.what() << " (descriptor skipped)");
    return;
  }
  stored_ += answer.stored;
  if (publish_candidates_)
    candidates_pub_.publish(PlaceCandidatesConstPtr(toMsg(msg->header, answer)));
  if (!merger_)
    return;
  const openable::MergedOutcome outcome = merger_->merge({answer});
  LoopClosurePtr loop = makeLoopClosure(msg->header, outcome, *merger_);
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
    std_msgs::Header header = msg->header;
    header.stamp = ros::Time(std::max(0.0, earlier.query_stamp));
    ++loops_;
    loop_pub_.publish(LoopClosureConstPtr(makeLoopClosure(header, earlier, *merger_)));
  }
}

bool PlaceServerHost::save(SaveMap::Request& request, SaveMap::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = request.path.empty() ? map_file_ : request.path;
  response.success = false;
  if (path.empty())
  {
    response.message = "no path given and ~map_file is empty";
    return true;
  }
  try
  {
    server_->save(path);
    response.frames = uint32_t(server_->map().frameCount());
    response.success = true;
    response.message = "saved " + std::to_string(server_->map().sessionCount()) + " sessions, " +
                       std::to_string(response.frames) + " frames to '" + path + "'";
  }
  catch (const std::exception& e)
  {
    response.message = "cannot save the map to '" + path + "': " + e.what();
  }
  return true;
}

bool PlaceServerHost::load(LoadMap::Request& request, LoadMap::Response& response)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = request.path.empty() ? map_file_ : request.path;
  response.success = false;
  try
  {
    server_->load(path);
    if (merger_)
      merger_ = std::make_unique<openable::CandidateMerger>(server_->config());
    response.frames = uint32_t(server_->map().frameCount());
    response.success = true;
    response.message = "map '" + path + "' loaded: " + std::to_string(server_->map().sessionCount()) +
                       " sessions, " + std::to_string(response.frames) + " frames; robots continue their sessions";
  }
  catch (const std::exception& e)
  {
    response.message = e.what();
  }
  return true;
}

void PlaceServerHost::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status)
{
  std::lock_guard<std::mutex> lock(mutex_);
  size_t refused = 0;
  for (const auto& r : server_->refused())
    refused += r.second;
  if (refused > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, std::to_string(refused) + " descriptors refused");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "serving");
  status.add("descriptors received", received_);
  status.add("descriptors refused", refused);
  for (const auto& r : server_->refused())
    status.add("refused: " + r.first, r.second);
  for (const auto& r : refused_by_robot_)
    status.add("refused from robot " + r.first, r.second);
  status.add("frames stored", stored_);
  status.add("sessions", server_->map().sessionCount());
  status.add("frames in map", server_->map().frameCount());
  status.add("map bytes", server_->map().bytes());
  status.add("loop closures", loops_);
}

}  // namespace openable_ros
