#include "openable_ros/params.h"

#include <XmlRpcValue.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "openable/error.h"

namespace openable_ros
{
namespace
{
std::string valueText(XmlRpc::XmlRpcValue& value)
{
  switch (value.getType())
  {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return bool(value) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt:
      return std::to_string(int(value));
    case XmlRpc::XmlRpcValue::TypeDouble:
    {
      std::ostringstream out;
      out.precision(17);
      out << double(value);
      return out.str();
    }
    case XmlRpc::XmlRpcValue::TypeString:
      return std::string(value);
    default:
      return value.toXml();
  }
}

std::string typeName(XmlRpc::XmlRpcValue::Type type)
{
  switch (type)
  {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return "a bool";
    case XmlRpc::XmlRpcValue::TypeInt:
      return "an int";
    case XmlRpc::XmlRpcValue::TypeDouble:
      return "a double";
    case XmlRpc::XmlRpcValue::TypeString:
      return "a string";
    case XmlRpc::XmlRpcValue::TypeArray:
      return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "a mapping";
    default:
      return "another type";
  }
}

// The text form of a parameter for Config::set, accepting the conversions YAML users expect (an int
// where a double is wanted, a whole double where an int is wanted). Returns false with `problem` set
// when the value cannot be that type.
bool toText(XmlRpc::XmlRpcValue& value, const std::string& type, std::string& text, std::string& problem)
{
  const auto t = value.getType();
  if (type == "bool")
  {
    if (t == XmlRpc::XmlRpcValue::TypeBoolean)
    {
      text = bool(value) ? "true" : "false";
      return true;
    }
  }
  else if (type == "int")
  {
    if (t == XmlRpc::XmlRpcValue::TypeInt)
    {
      text = std::to_string(int(value));
      return true;
    }
    if (t == XmlRpc::XmlRpcValue::TypeDouble)
    {
      const double d = value;
      if (std::isfinite(d) && std::floor(d) == d && std::fabs(d) < 2e9)
      {
        text = std::to_string(int(d));
        return true;
      }
      problem = "is not a whole number";
      return false;
    }
  }
  else if (type == "double")
  {
    if (t == XmlRpc::XmlRpcValue::TypeDouble || t == XmlRpc::XmlRpcValue::TypeInt)
    {
      const double d = t == XmlRpc::XmlRpcValue::TypeInt ? double(int(value)) : double(value);
      if (!std::isfinite(d))
      {
        problem = "is not a finite number";
        return false;
      }
      text = valueText(value);
      return true;
    }
  }
  else if (type == "string")
  {
    if (t == XmlRpc::XmlRpcValue::TypeString)
    {
      text = std::string(value);
      return true;
    }
  }
  problem = "is " + typeName(t) + ", expected " + (type == "int" ? "an int" : "a " + type);
  return false;
}

/// A key's value for a message: numbers without the round-trip digits Config::get keeps (0.05, not
/// 0.050000000000000003).
std::string shown(const std::string& value)
{
  char* end = nullptr;
  const double number = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0')
    return value;
  std::ostringstream out;
  out.precision(15);
  out << number;
  return out.str();
}

}  // namespace

openable::Config loadCoreConfig(const ros::NodeHandle& private_nh, const openable::Config& defaults,
                                std::vector<std::string>& warnings)
{
  const std::string camera_type = defaults.camera_type;
  openable::Config config = defaults;
  for (const auto& key : openable::Config::keys())
  {
    XmlRpc::XmlRpcValue value;
    if (!private_nh.getParam(key.name, value))
    {
      continue;
    }
    std::string text;
    std::string problem;
    if (!toText(value, key.type, text, problem))
    {
      warnings.push_back("~" + key.name + ": value '" + valueText(value) + "' " + problem + "; using the default " +
                         defaults.get(key.name));
      continue;
    }
    try
    {
      config.set(key.name, text);
    }
    catch (const openable::Error& e)
    {
      warnings.push_back("~" + key.name + ": " + e.what() + "; using the default " + defaults.get(key.name));
    }
  }

  if (config.camera_type != camera_type)
  {
    warnings.push_back("~camera_type: value '" + config.camera_type + "' does not fit this nodelet; using '" +
                       camera_type + "'");
    config.camera_type = camera_type;
  }
  if (fallBackKeyByKey(config, defaults, "using", "the defaults", warnings))
  {
    return config;
  }
  warnings.push_back("the parameters still break a rule after falling back key by key; using every default");
  return defaults;
}

bool fallBackKeyByKey(openable::Config& config, const openable::Config& fallback, const std::string& verb,
                      const std::string& everything, std::vector<std::string>& messages)
{
  // The core repairs (Config::sanitized, rule by rule); here each repair is only worded. camera_type is the
  // nodelet's own and never falls back.
  std::vector<openable::ConfigRepair> repairs;
  config = config.sanitized(fallback, repairs, {"camera_type"});
  for (const auto& repair : repairs)
  {
    std::string fallbacks;
    for (const auto& key : repair.reset_keys)
      fallbacks += (fallbacks.empty() ? "" : ", ") + key + " = " + shown(fallback.get(key));
    messages.push_back("~" + repair.problem.message() + "; " + verb + " " + (fallbacks.empty() ? everything : fallbacks));
  }
  return config.problems().empty();
}

double readDouble(const ros::NodeHandle& private_nh, const std::string& name, double fallback, double min, double max,
                  const std::string& units, std::vector<std::string>& warnings)
{
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(name, value))
  {
    return fallback;
  }
  std::string text;
  std::string problem;
  if (!toText(value, "double", text, problem))
  {
    warnings.push_back("~" + name + ": value '" + valueText(value) + "' " + problem + "; using " +
                       std::to_string(fallback) + " " + units);
    return fallback;
  }
  const double d = value.getType() == XmlRpc::XmlRpcValue::TypeInt ? double(int(value)) : double(value);
  if (d < min || d > max)
  {
    std::ostringstream out;
    out << "~" << name << ": value '" << d << "' is out of range; expected [" << min << ", " << max << "] " << units
        << "; using " << fallback;
    warnings.push_back(out.str());
    return fallback;
  }
  return d;
}

int readInt(const ros::NodeHandle& private_nh, const std::string& name, int fallback, int min, int max,
            std::vector<std::string>& warnings)
{
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(name, value))
  {
    return fallback;
  }
  std::string text;
  std::string problem;
  if (!toText(value, "int", text, problem))
  {
    warnings.push_back("~" + name + ": value '" + valueText(value) + "' " + problem + "; using " +
                       std::to_string(fallback));
    return fallback;
  }
  const int i = std::stoi(text);
  if (i < min || i > max)
  {
    warnings.push_back("~" + name + ": value '" + text + "' is out of range; expected an integer in [" +
                       std::to_string(min) + ", " + std::to_string(max) + "]; using " + std::to_string(fallback));
    return fallback;
  }
  return i;
}

bool readBool(const ros::NodeHandle& private_nh, const std::string& name, bool fallback,
              std::vector<std::string>& warnings)
{
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(name, value))
  {
    return fallback;
  }
  std::string text;
  std::string problem;
  if (!toText(value, "bool", text, problem))
  {
    warnings.push_back("~" + name + ": value '" + valueText(value) + "' " + problem + "; using " +
                       (fallback ? "true" : "false"));
    return fallback;
  }
  return text == "true";
}

std::string readString(const ros::NodeHandle& private_nh, const std::string& name, const std::string& fallback,
                       std::vector<std::string>& warnings)
{
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(name, value))
  {
    return fallback;
  }
  if (value.getType() != XmlRpc::XmlRpcValue::TypeString)
  {
    warnings.push_back("~" + name + ": value '" + valueText(value) + "' is " + typeName(value.getType()) +
                       ", expected a string; using '" + fallback + "'");
    return fallback;
  }
  return std::string(value);
}

std::vector<std::string> readStringList(const ros::NodeHandle& private_nh, const std::string& name,
                                        std::vector<std::string>& warnings)
{
  std::vector<std::string> out;
  XmlRpc::XmlRpcValue value;
  if (!private_nh.getParam(name, value))
  {
    return out;
  }
  if (value.getType() != XmlRpc::XmlRpcValue::TypeArray)
  {
    warnings.push_back("~" + name + ": value '" + valueText(value) + "' is " + typeName(value.getType()) +
                       ", expected a list of strings; using an empty list");
    return out;
  }
  for (int i = 0; i < value.size(); ++i)
  {
    if (value[i].getType() != XmlRpc::XmlRpcValue::TypeString)
    {
      warnings.push_back("~" + name + "[" + std::to_string(i) + "]: value '" + valueText(value[i]) + "' is " +
                         typeName(value[i].getType()) + ", expected a string; using an empty list");
      return {};
    }
    out.push_back(std::string(value[i]));
  }
  return out;
}

}  // namespace openable_ros
