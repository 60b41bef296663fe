#include "openable_ros/live_reconfigure.h"

#include <algorithm>
#include <sstream>

#include "openable_ros/detector.h"

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

void readDisplay(const DetectorConfig& c, RosParameters& p)
{
  p.matrix_rate = c.matrix_rate;
  p.matrix_size = c.matrix_size;
  p.matrix_mode = c.matrix_mode;
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
  openable::Config config = detector_.config();
  RosParameters display = detector_.parameters();
  try
  {
    toCore(message, config);
  }
  catch (const std::exception& e)
  {
    ROS_WARN_STREAM("dynamic_reconfigure: " << e.what() << "; keeping the previous values");
    config = detector_.config();
  }
  readDisplay(requested, display);
  detector_.applyLive(config, display);
  // Write back what is in force, so rqt_reconfigure shows the truth.
  fromCore(config, message);
  requested.__fromMessage__(message);
  writeDisplay(display, requested);
}

}  // namespace openable_ros
