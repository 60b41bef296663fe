#pragma once

#include <opencv2/core.hpp>

#include "openable/config.h"

namespace openable
{
/// Throws Error unless `left` and `right` are a usable rectified pair: both non-empty, 8-bit grey, BGR or
/// BGRA, of the same size and type. The message names both sizes / types.
void checkStereoPair(const cv::Mat& left, const cv::Mat& right);

/// Disparity of a rectified pair with OpenCV's StereoSGBM: CV_32F of the input's size, in pixels of the
/// input, NaN where SGBM found no valid match. Colour inputs are converted to grey first.
///
/// SGBM runs on the pair downscaled (area interpolation) to stereoWorkWidth(): D-LDB reads the disparity
/// averaged over patch pixels, so finer disparity maps are never used, and SGBM's cost grows with pixels
/// times disparities (752x480 EuRoC: about 7x faster at 320 px). The result is brought back to the input
/// size (nearest neighbour, so invalid pixels stay NaN) and to input pixels.
///
/// Parameters from the config: the search range stereo_num_disparities is given for a 640 px wide image and
/// scaled to the working width (rounded to a multiple of 16, at least 16), so the same config covers the same
/// depth range at any resolution; stereo_block_size as it is. Fixed choices: minimum disparity 0, P1 = 8 *
/// block^2 and P2 = 32 * block^2 (smoothness, the values OpenCV's documentation suggests for one channel),
/// uniqueness ratio 10 %, left-right check tolerance 1 px, speckle filter over windows of 100 px with range 2.
/// Throws Error (checkStereoPair; a working width not wider than the disparity range).
cv::Mat disparityFromPair(const cv::Mat& left, const cv::Mat& right, const Config& config);

/// Width SGBM works at: the described width (cells across * patch_size) times kStereoPixelsPerPatchPixel,
/// at least kMinStereoWorkWidth, at most the input width.
int stereoWorkWidth(const Config& config, int input_width);
constexpr int kStereoPixelsPerPatchPixel = 4;
constexpr int kMinStereoWorkWidth = 320;

/// The search range disparityFromPair uses at a working width of `width` pixels.
int scaledNumDisparities(const Config& config, int width);

/// A given disparity image as CV_32F pixels with NaN for invalid:
/// - CV_32F (e.g. stereo_msgs/DisparityImage): values as they are; non-finite or <= 0 is invalid;
/// - CV_16S: OpenCV's fixed point (StereoBM / StereoSGBM output), pixels * 16; <= 0 is invalid;
/// - CV_16U: the KITTI disparity PNG convention, pixels * 256; 0 is invalid.
/// One channel only. Throws Error for an empty image or any other type, listing the accepted ones.
cv::Mat disparityFromImage(const cv::Mat& disparity);

}  // namespace openable
