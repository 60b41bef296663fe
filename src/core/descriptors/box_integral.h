#pragma once

#include <opencv2/core.hpp>

namespace openable
{
namespace descriptors
{
/// Exact sums of a patch over axis-aligned boxes with fractional corners. Pixel (x, y) covers the square
/// [x, x + 1) x [y, y + 1) and is constant over it, so the integral image is bilinear inside every pixel:
/// interpolating it bilinearly gives the exact area integral of any box. That lets patterns scale
/// continuously with patch_size instead of snapping to whole pixels. The patch is mirror-padded (as
/// cv::BORDER_REFLECT) by `margin` pixels so boxes may reach that far outside; beyond, corners are clamped.
class BoxIntegral
{
public:
  BoxIntegral(const cv::Mat& patch, int margin);

  /// Integral over [x0, x1) x [y0, y1), patch coordinates.
  double sum(double x0, double y0, double x1, double y1) const
  {
    return at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0);
  }
  /// Mean over the box of half side `half` centred at (x, y).
  double mean(double x, double y, double half) const
  {
    return sum(x - half, y - half, x + half, y + half) / (4.0 * half * half);
  }

private:
  double at(double x, double y) const;
  cv::Mat integral_;  ///< CV_64F, (rows + 1) x (cols + 1) of the padded patch
  int margin_;
};

}  // namespace descriptors
}  // namespace openable
