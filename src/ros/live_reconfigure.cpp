#include "openable_ros/live_reconfigure.h"

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "openable_ros/detector.h"
#include "openable_ros/params.h"

namespace openable_ros
{
namespace
{
bool isLive(const std::string& name)
{
  const auto& live = openable::Config::liveKeys();
  return std::find(live.begin(), live.end(), name) != live.end();
}

std::string text(double v)
{
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

/// The display parameters of the request, each checked against the ROS parameter table; a refused one
/// keeps the value in force (`current`) and is explained in `refused`.
void readDisplay(const DetectorConfig& c, RosParameters& p, const RosParameters& current,
                 std::vector<std::string>& refused)
{
  auto allowed = [&refused](const std::string& name, const std::string& value, const std::string& kept)
  {
    const std::string problem = rosParameterProblem(name, value);
    if (!problem.empty())
      refused.push_back(problem + "; keeping " + name + " = " + kept);
    return problem.empty();
  };
  p.matrix_rate = allowed("matrix_rate", text(c.matrix_rate), text(current.matrix_rate)) ? c.matrix_rate
                                                                                           : current.matrix_rate;
  p.matrix_size = allowed("matrix_size", std::to_string(c.matrix_size), std::to_string(current.matrix_size))
                      ? c.matrix_size
                      : current.matrix_size;
  p.matrix_mode = allowed("matrix_mode", c.matrix_mode, current.matrix_mode) ? c.matrix_mode : current.matrix_mode;
  p.matrix_threshold_view = c.matrix_threshold_view;
}

void writeDisplay(const RosParameters& p, DetectorConfig& c)
{
  c.matrix_rate = p.matrix_rate;
  c.matrix_size = p.matrix_size;
  c.matrix_mode = p.matrix_mode;
  c.matrix_threshold_view = p.matrix_threshold_view;
}
}  // namespace

void LiveReconfigure::toCore(const dynamic_reconfigure::Config& message, openable::Config& config)
{
  for (const auto& b : message.bools)
    if (isLive(b.name))
      config.set(b.name, b.value ? "true" : "false");
  for (const auto& i : message.ints)
    if (isLive(i.name))
      config.set(i.name, std::to_string(i.value));
  for (const auto& d : message.doubles)
    if (isLive(d.name))
      config.set(d.name, text(d.value));
  for (const auto& s : message.strs)
    if (isLive(s.name))
      config.set(s.name, s.value);
}

void LiveReconfigure::fromCore(const openable::Config& config, dynamic_reconfigure::Config& message)
{
  for (auto& b : message.bools)
    if (isLive(b.name))
      b.value = config.get(b.name) == "true";
  for (auto& i : message.ints)
    if (isLive(i.name))
      i.value = std::stoi(config.get(i.name));
  for (auto& d : message.doubles)
    if (isLive(d.name))
      d.value = std::stod(config.get(d.name));
  for (auto& s : message.strs)
    if (isLive(s.name))
      s.value = config.get(s.name);
}

LiveReconfigure::LiveReconfigure(ros::NodeHandle& pnh, Detector& detector, const openable::Config& config,
                                 const RosParameters& parameters)
  : detector_(detector), server_(mutex_, pnh)
{
  DetectorConfig start;
  dynamic_reconfigure::Config message;
  start.__toMessage__(message);
  fromCore(config, message);
  start.__fromMessage__(message);
  writeDisplay(parameters, start);
  server_.updateConfig(start);
  server_.setCallback([this](DetectorConfig& c, uint32_t level) { callback(c, level); });
}

void LiveReconfigure::callback(DetectorConfig& requested, uint32_t /*level*/)
{
  dynamic_reconfigure::Config message;
  requested.__toMessage__(message);
  const openable::Config in_force = detector_.config();
  openable::Config config = in_force;
  RosParameters display = detector_.parameters();
  std::vector<std::string> refused;
  try
  {
    toCore(message, config);
    // The cfg gives these keys no min/max, so the server passes values as sent (it would clamp them
    // silently otherwise: threshold 5 would become 1, which accepts everything). The core's key table
    // judges them here, as it judges private parameters; each refused key keeps its value in force.
    if (!fallBackKeyByKey(config, in_force, "keeping", "the previous values", refused))
      config = in_force;
  }
  catch (const std::exception& e)
  {
    refused.push_back(std::string(e.what()) + "; keeping the previous values");
    config = in_force;
  }
  readDisplay(requested, display, detector_.parameters(), refused);
  for (const auto& problem : refused)
    ROS_ERROR_STREAM("dynamic_reconfigure refused " << problem);
  detector_.applyLive(config, display);
  // Write back what is in force, so rqt_reconfigure (and the caller of set_parameters) sees the truth.
  fromCore(config, message);
  requested.__fromMessage__(message);
  writeDisplay(display, requested);
}

}  // namespace openable_ros
