#include "descriptors/box_integral.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace openable
{
namespace descriptors
{
BoxIntegral::BoxIntegral(const cv::Mat& patch, int margin) : margin_(margin)
{
  cv::Mat padded;
  cv::copyMakeBorder(patch, padded, margin, margin, margin, margin, cv::BORDER_REFLECT);
  cv::integral(padded, integral_, CV_64F);
}

double BoxIntegral::at(double x, double y) const
{
  const double max_x = integral_.cols - 1, max_y = integral_.rows - 1;
  x = std::min(std::max(x + margin_, 0.0), max_x);
  y = std::min(std::max(y + margin_, 0.0), max_y);
  const int x0 = std::min(static_cast<int>(x), integral_.cols - 2);
  const int y0 = std::min(static_cast<int>(y), integral_.rows - 2);
  const double fx = x - x0, fy = y - y0;
  const double* top = integral_.ptr<double>(y0);
  const double* bottom = integral_.ptr<double>(y0 + 1);
  return (1.0 - fy) * ((1.0 - fx) * top[x0] + fx * top[x0 + 1]) + fy * ((1.0 - fx) * bottom[x0] + fx * bottom[x0 + 1]);
}

}  // namespace descriptors
}  // namespace openable
