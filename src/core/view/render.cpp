#include "openable/view/render.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"

namespace openable
{
cv::Mat normalizeByMax(const cv::Mat& distances)
{
  CV_Assert(distances.type() == CV_32FC1);
  float max_value = 0.0f;
  for (int y = 0; y < distances.rows; ++y)
  {
    const float* row = distances.ptr<float>(y);
    for (int x = 0; x < distances.cols; ++x)
      if (std::isfinite(row[x]) && row[x] > max_value)
        max_value = row[x];
  }
  cv::Mat out = distances.clone();
  if (max_value > 0.0f)
    out /= max_value;  // NaN / x stays NaN
  return out;
}

cv::Mat normalizeMinMax(const cv::Mat& distances)
{
  CV_Assert(distances.type() == CV_32FC1);
  float low = INFINITY, high = -INFINITY;
  for (int y = 0; y < distances.rows; ++y)
  {
    const float* row = distances.ptr<float>(y);
    for (int x = 0; x < distances.cols; ++x)
      if (std::isfinite(row[x]))
      {
        low = std::min(low, row[x]);
        high = std::max(high, row[x]);
      }
  }
  cv::Mat out = distances.clone();
  const float range = high > low ? high - low : 1.0f;  // all equal: every finite cell becomes 0
  for (int y = 0; y < out.rows; ++y)
  {
    float* row = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x)
      if (std::isfinite(row[x]))
        row[x] = (row[x] - low) / range;
  }
  return out;
}

cv::Mat thresholdView(const cv::Mat& normalized, double theta)
{
  CV_Assert(normalized.type() == CV_32FC1);
  cv::Mat out(normalized.size(), CV_8UC1);
  for (int y = 0; y < normalized.rows; ++y)
  {
    const float* in = normalized.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < normalized.cols; ++x)
      o[x] = (std::isfinite(in[x]) && in[x] < theta) ? 0 : 255;  // Eq. 9: 0 marks a loop
  }
  return out;
}

cv::Mat colorize(const cv::Mat& values, int color_map, const cv::Vec3b& nan_color)
{
  if (color_map < 0 || color_map >= kColorMapCount)
    throw Error("color_map " + std::to_string(color_map) + " is out of range; expected 0..11");
  CV_Assert(values.type() == CV_32FC1);
  cv::Mat grey(values.size(), CV_8UC1);
  cv::Mat nan_mask(values.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < values.rows; ++y)
  {
    const float* in = values.ptr<float>(y);
    uint8_t* g = grey.ptr<uint8_t>(y);
    uint8_t* m = nan_mask.ptr<uint8_t>(y);
    for (int x = 0; x < values.cols; ++x)
    {
      if (!std::isfinite(in[x]))
      {
        g[x] = 0;
        m[x] = 255;
        continue;
      }
      g[x] = static_cast<uint8_t>(std::lround(std::min(1.0f, std::max(0.0f, in[x])) * 255.0f));
    }
  }
  cv::Mat out;
  // OpenCV's first twelve colour maps (AUTUMN = 0 .. HOT = 11) are the twelve ranges OpenABLE offers.
  cv::applyColorMap(grey, out, color_map);
  out.setTo(cv::Scalar(nan_color[0], nan_color[1], nan_color[2]), nan_mask);
  return out;
}

}  // namespace openable
