#pragma once

#include <opencv2/core.hpp>

namespace openable
{
/// Area-averaging downsampling of an 8-bit image (1 to 4 channels) to `target`, in two steps:
///
/// 1. Exact integer decimation: every kx x ky block of pixels becomes its mean, rounded to 8 bits, with
///    kx = cols / target.width and ky = rows / target.height (integer division, at least 1). When cols is
///    not a multiple of kx (rows of ky), the cols % kx leftover columns (rows % ky rows) are split evenly
///    between both borders and left out: at most kx - 1 pixels of the whole width.
/// 2. OpenCV's area interpolation from the decimated image (less than twice the target per side) to
///    `target`.
///
/// The same as one area resize up to the rounding of step 1 and the left-out border pixels, but step 1
/// is a single pass over the image with integer sums where OpenCV's non-integer area resize spends most of
/// a frame's description time (doc/performance.md). A target as large as the image or larger goes to
/// OpenCV's area resize directly.
cv::Mat areaDownsample(const cv::Mat& image, cv::Size target);

/// Step 1 alone: the kx x ky block means of `image`, leftover border pixels left out as above.
cv::Mat decimate(const cv::Mat& image, int kx, int ky);

/// decimate() of a grey, BGR or BGRA image, converted to grey as cv::cvtColor does (8-bit BGR(A) -> grey):
/// the same pixels as cvtColor(decimate(image, kx, ky)), with the conversion done on the decimated pixels
/// only and no colour image in between. A grey image is decimate()'s.
cv::Mat decimateGrey(const cv::Mat& image, int kx, int ky);

/// Step 1 with the largest factors that keep at least `target` (the image itself when they are 1), for
/// callers that do per-pixel work between the two steps.
cv::Mat decimateTowards(const cv::Mat& image, cv::Size target);

/// decimateTowards(), converted to grey as decimateGrey() does (cvtColor when the factors are 1).
cv::Mat decimateGreyTowards(const cv::Mat& image, cv::Size target);

/// cv::resize(image, out, target, 0, 0, cv::INTER_AREA), the same floats bit for bit, for the small area step
/// of a one-channel float image (step 2 above): OpenCV's weight tables and order of additions, without its
/// per-row walk of the column table when the width does not change. Other types, enlargements and
/// whole-number ratios go to cv::resize itself.
cv::Mat areaResize(const cv::Mat& image, cv::Size target);

}  // namespace openable
