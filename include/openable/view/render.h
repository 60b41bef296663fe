#pragma once

#include <opencv2/core.hpp>

namespace openable
{
/// Paper Eq. 5: M' = M / max(M) on a CV_32F matrix; NaN cells stay NaN. An all-zero matrix stays zero.
cv::Mat normalizeByMax(const cv::Mat& distances);

/// Contrast stretch for display: (M - min) / (max - min) over the finite cells; NaN stays NaN. Distances of
/// real images often span a narrow band (e.g. 0.18 .. 0.30), which Eq. 5 leaves washed out.
cv::Mat normalizeMinMax(const cv::Mat& distances);

/// Paper Eq. 9: 0 where M' < theta (a loop), 1 elsewhere; CV_8U 0 / 255 for display (NaN -> 255).
cv::Mat thresholdView(const cv::Mat& normalized, double theta);

/// Number of OpenABLE colour maps (color_map 0 .. 11: OpenCV's AUTUMN, BONE, JET, WINTER, RAINBOW, OCEAN,
/// SUMMER, SPRING, COOL, HSV, PINK, HOT).
constexpr int kColorMapCount = 12;

/// A CV_32F matrix of values in [0, 1] as a BGR image through colour map `color_map`; NaN cells are drawn
/// in `nan_color`. Throws Error for a colour map outside 0..11.
cv::Mat colorize(const cv::Mat& values, int color_map, const cv::Vec3b& nan_color = cv::Vec3b(40, 40, 40));

}  // namespace openable
