#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace openable
{
namespace descriptors
{
/// Throws Error unless `intensity` is a finite one-channel CV_32F patch of patch_size x patch_size: every
/// extractor's pattern or window is scaled to the patch_size it was built for.
void checkIntensityPatch(const std::string& descriptor, const cv::Mat& intensity, int patch_size);

/// The 8-bit image OpenCV's extractors need, by one rule for grey and illumination-invariant patches alike:
/// a per-patch min-max stretch to 0..255, rounded to nearest. Grey values could be clipped, but Eq. 6
/// values are logarithm differences around 0 and would all clip to 0 or 1; stretching serves both, and
/// makes the descriptor independent of brightness offset and contrast, as the own binary descriptors are.
/// A flat patch gives all zeros.
cv::Mat toEightBit(const cv::Mat& intensity);

/// Mirror padding (cv::BORDER_REFLECT) of `margin` pixels on every side.
cv::Mat padReflect(const cv::Mat& image, int margin);

/// Copies a descriptor row of OpenCV bytes into 64-bit words, byte j to bits 8j..8j+7, rest zero.
void packBytes(const uint8_t* bytes, int count, uint64_t* words, int word_count);

}  // namespace descriptors
}  // namespace openable
