// The key table of Config, private to src/core: config_keys.cpp holds the rows (how each key is read and
// written, its range and flags), config.cpp what is built on them (validation, YAML in and out).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "openable/config.h"

namespace openable
{
namespace config_keys
{
/// One row per key: its schema and how to read and write it. Keeping every key in one table means YAML,
/// --set, ROS parameters and the documentation can never disagree about names or types.
struct KeyAccess
{
  Config::Key key;
  std::function<void(Config&, const std::string&)> set;
  std::function<std::string(const Config&)> get;

  KeyAccess range(double low, double high)
  {
    key.min = low;
    key.max = high;
    key.has_range = true;
    return *this;
  }
  /// The range's low end itself is not allowed: (low, high].
  KeyAccess aboveMin()
  {
    key.min_exclusive = true;
    return *this;
  }
  /// A range [-1, high] whose -1 means off: the numbers between -1 and 0 are not allowed.
  KeyAccess minusOneIsOff()
  {
    key.minus_one_is_off = true;
    return *this;
  }
  /// The range's high end itself is not allowed: [low, high).
  KeyAccess belowMax()
  {
    key.max_exclusive = true;
    return *this;
  }
  KeyAccess live()
  {
    key.live = true;
    return *this;
  }
  KeyAccess describes()
  {
    key.describes = true;
    return *this;
  }
};

/// Every key, in documentation order.
const std::vector<KeyAccess>& table();
/// The row of `name`. Throws Error for an unknown key, naming the closest known one and listing them all.
const KeyAccess& find(const std::string& name);

/// `text` without leading and trailing white space.
std::string trim(const std::string& text);
/// A double with 17 significant digits, so its text reads back to the same value.
std::string formatDouble(double value);

}  // namespace config_keys
}  // namespace openable
