#include "openable_ros/ros_parameters.h"

#include <ros/param.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "openable/config.h"
#include "openable_ros/params.h"

namespace openable_ros
{
namespace
{
std::string text(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}

RosParameter number(const char* name, double RosParameters::*field, double value, double min, double max,
                    const char* units, const char* nodelets, const char* doc)
{
  return {name,
          "double",
          text(value),
          "[" + text(min) + ", " + text(max) + "]",
          units,
          nodelets,
          doc,
          [=](const ros::NodeHandle& nh, RosParameters& p, std::vector<std::string>& w)
          { p.*field = readDouble(nh, name, value, min, max, units, w); }};
}

RosParameter integer(const char* name, int RosParameters::*field, int value, int min, int max, const char* units,
                     const char* nodelets, const char* doc)
{
  return {name,
          "int",
          std::to_string(value),
          "[" + std::to_string(min) + ", " + std::to_string(max) + "]",
          units,
          nodelets,
          doc,
          [=](const ros::NodeHandle& nh, RosParameters& p, std::vector<std::string>& w)
          { p.*field = readInt(nh, name, value, min, max, w); }};
}

RosParameter flag(const char* name, bool RosParameters::*field, bool value, const char* nodelets, const char* doc)
{
  return {name,
          "bool",
          value ? "true" : "false",
          "",
          "",
          nodelets,
          doc,
          [=](const ros::NodeHandle& nh, RosParameters& p, std::vector<std::string>& w)
          { p.*field = readBool(nh, name, value, w); }};
}

RosParameter word(const char* name, std::string RosParameters::*field, const char* value, const char* choices,
                  const char* nodelets, const char* doc)
{
  return {name,
          "string",
          std::string("\"") + value + "\"",
          choices,
          "",
          nodelets,
          doc,
          [=](const ros::NodeHandle& nh, RosParameters& p, std::vector<std::string>& w)
          {
            std::string v = readString(nh, name, value, w);
            const std::string allowed = choices;
            if (!allowed.empty() && (" | " + allowed + " | ").find(" | " + v + " | ") == std::string::npos)
            {
              w.push_back("~" + std::string(name) + ": value '" + v + "' is not allowed; expected " + allowed +
                          "; using " + value);
              v = value;
            }
            p.*field = v;
          }};
}
}  // namespace

const std::vector<RosParameter>& rosParameterTable()
{
  static const std::vector<RosParameter> table = {
      integer("queue_size", &RosParameters::queue_size, 10, 1, 10000, "messages", "all",
              "subscriber queue and synchroniser queue"),
      number("sync_warning_timeout", &RosParameters::sync_warning_timeout, 5.0, 0.0, 3600.0, "s", "stereo, panoramic",
             "seconds without a synchronised set before a warning naming the topics (0 = never)"),
      flag("approximate_sync", &RosParameters::approximate_sync, false, "stereo, panoramic",
           "false: identical stamps (ExactTime); true: ApproximateTime (stereo) or stamps within max_skew (ring)"),
      flag("use_disparity", &RosParameters::use_disparity, false, "stereo",
           "subscribe disparity (stereo_msgs/DisparityImage) + left/image_rect instead of the pair"),
      {"cameras", "list", "[]", "", "", "panoramic", "camera topics in ring order, one sub-panorama each; empty: image",
       [](const ros::NodeHandle& nh, RosParameters& p, std::vector<std::string>& w)
       { p.cameras = readStringList(nh, "cameras", w); }},
      number("max_skew", &RosParameters::max_skew, 0.02, 0.0, 10.0, "s", "panoramic",
             "largest stamp difference within a ring set, with approximate_sync"),
      flag("reset_on_time_jump", &RosParameters::reset_on_time_jump, false, "all",
           "a stamp before the previous one: false = skip that frame, true = start a new history"),
      integer("session", &RosParameters::session, 0, 0, 1000000000, "", "all",
              "session id stored with every frame of this run"),
      word("map_file", &RosParameters::map_file, "", "", "all",
           "map loaded at start-up when the file exists (see map_mode); default path of the map services"),
      word("map_mode", &RosParameters::map_mode, "localise", "localise | continue", "all",
           "a loaded map: localise against it (nothing stored), or continue it as a new session"),
      word("session_name", &RosParameters::session_name, "", "", "all",
           "name of this run's session in a continued map; empty: the node name and the start time"),
      word("fixed_frame", &RosParameters::fixed_frame, "", "", "all",
           "frame of the poses (e.g. odom); empty: no tf, no markers, no keyframing"),
      number("tf_timeout", &RosParameters::tf_timeout, 0.05, 0.0, 10.0, "s", "all",
             "wait for the camera pose at an image's stamp; then the frame is kept without pose"),
      number("keyframe_distance", &RosParameters::keyframe_distance, 0.0, 0.0, 1e6, "m", "all",
             "> 0: a frame is stored only after the camera moved this far (or turned keyframe_angle)"),
      number("keyframe_angle", &RosParameters::keyframe_angle, 0.0, 0.0, M_PI, "rad", "all",
             "> 0: a turn this large makes a keyframe too"),
      number("fix_tolerance", &RosParameters::fix_tolerance, 0.5, 0.0, 3600.0, "s", "all",
             "a frame takes the ~fix nearest to its stamp when within this; else it has no geographic position"),
      word("geo_file", &RosParameters::geo_file, "", "", "all",
           "CSV of each stored frame's fix (frame,stamp,latitude,longitude,altitude), for openable_trajectory "
           "--geo; empty: not written"),
      number("markers_rate", &RosParameters::markers_rate, 1.0, 0.0, 30.0, "Hz", "all",
             "largest loop_markers publishing rate (also sent at once after a loop closure)"),
      number("matrix_rate", &RosParameters::matrix_rate, 2.0, 0.0, 30.0, "Hz", "all",
             "largest distance_matrix publishing rate; 0 = never render"),
      integer("matrix_size", &RosParameters::matrix_size, 512, 16, 4096, "pixels", "all",
              "largest side of the distance_matrix image"),
      word("matrix_mode", &RosParameters::matrix_mode, "whole_history", "whole_history | rolling_window", "all",
           "every frame, min-pooled, or the last matrix_size frames"),
      flag("matrix_threshold_view", &RosParameters::matrix_threshold_view, false, "all",
           "paper Eq. 9 view (black where distance < threshold) instead of colours"),
      flag("verify", &RosParameters::verify, false, "all",
           "geometric verification of candidate loops (needs camera_info); fills relative_pose"),
      flag("verify_required", &RosParameters::verify_required, true, "all",
           "with verify: only verified loops are published (else unverified ones go out flagged)"),
      number("verify_memory", &RosParameters::verify_memory, 256.0, 1.0, 65536.0, "MB", "all",
             "bound of the stored features of history frames"),
      flag("publish_descriptors", &RosParameters::publish_descriptors, false, "all",
           "publish every stored frame's descriptor on place_descriptors (PlaceDescriptor) for PlaceServers"),
      word("robot", &RosParameters::robot, "", "", "all",
           "robot name in place_descriptors (empty: the node's namespace; the session is robot[/session]) and "
           "stored with this run's session of the map"),
  };
  return table;
}

RosParameters readRosParameters(const ros::NodeHandle& private_nh, std::vector<std::string>& warnings)
{
  RosParameters p;
  for (const auto& parameter : rosParameterTable())
    parameter.read(private_nh, p, warnings);
  if ((p.keyframe_distance > 0.0 || p.keyframe_angle > 0.0) && p.fixed_frame.empty())
  {
    warnings.push_back(
        "~keyframe_distance / ~keyframe_angle need ~fixed_frame for the camera poses; ~fixed_frame is empty, so "
        "every frame is kept");
    p.keyframe_distance = 0.0;
    p.keyframe_angle = 0.0;
  }
  return p;
}

void warnUnknownParameters(const ros::NodeHandle& private_nh, std::vector<std::string>& warnings)
{
  std::vector<std::string> known;
  for (const auto& key : openable::Config::keys())
    known.push_back(key.name);
  for (const auto& parameter : rosParameterTable())
    known.push_back(parameter.name);
  // Read by libraries the nodelets use: image_transport, diagnostic_updater, dynamic_reconfigure.
  for (const char* other : {"image_transport", "diagnostic_period"})
    known.push_back(other);

  std::vector<std::string> names;
  if (!ros::param::getParamNames(names))
    return;
  const std::string prefix = private_nh.getNamespace() + "/";
  for (const auto& full : names)
  {
    if (full.compare(0, prefix.size(), prefix) != 0)
      continue;
    const std::string name = full.substr(prefix.size());
    if (name.find('/') != std::string::npos)
      continue;  // a sub-namespace (e.g. a transport's own parameters)
    bool found = false;
    for (const auto& k : known)
      found = found || k == name;
    if (!found)
      warnings.push_back("~" + name + " is not a parameter of this nodelet and is ignored; did you mean ~" +
                         openable::closestName(name, known) + "?");
  }
}

}  // namespace openable_ros

namespace openable_ros
{
std::string rosParameterProblem(const std::string& name, const std::string& value)
{
  for (const auto& parameter : rosParameterTable())
  {
    if (parameter.name != name || parameter.range.empty())
      continue;
    const std::string refused = "~" + name + ": value '" + value + "' is not allowed; expected ";
    if (parameter.range[0] != '[')
    {
      // Choices "a | b".
      if ((" | " + parameter.range + " | ").find(" | " + value + " | ") == std::string::npos)
        return refused + parameter.range;
      return "";
    }
    double min = 0.0, max = 0.0, v = 0.0;
    std::sscanf(parameter.range.c_str(), "[%lf, %lf]", &min, &max);
    char* end = nullptr;
    v = std::strtod(value.c_str(), &end);
    if (end != value.c_str() && *end == '\0' && v >= min && v <= max)  // false for NaN too
      return "";
    return refused + (parameter.type == "int" ? "an integer in " : "a number in ") + parameter.range +
           (parameter.units.empty() ? "" : " (" + parameter.units + ")");
  }
  return "";
}

}  // namespace openable_ros
