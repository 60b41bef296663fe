#pragma once

#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

#include "bit_oracle.h"  // randomWords, naiveBitCount

namespace openable_test
{
/// Real data beside the repository (../shared/data), as on developer machines and in CI.
inline std::string sharedData(const std::string& relative)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/../shared/data/" + relative;
}

/// Data bundled with the package (data/sample).
inline std::string sampleData(const std::string& relative)
{
  return std::string(OPENABLE_SOURCE_DIR) + "/data/sample/" + relative;
}

/// Gardens Point frame `index` of a traversal (day_left, day_right, night_right).
inline cv::Mat gardensPoint(const std::string& traversal, int index)
{
  char name[32];
  std::snprintf(name, sizeof(name), "/Image%03d.jpg", index);
  return cv::imread(sharedData("gardens_point/" + traversal + name), cv::IMREAD_COLOR);
}

}  // namespace openable_test
