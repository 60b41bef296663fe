#include "descriptors/patch_input.h"

#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>

#include "openable/error.h"

namespace openable
{
namespace descriptors
{
void checkIntensityPatch(const std::string& descriptor, const cv::Mat& intensity, int patch_size)
{
  if (intensity.empty() || intensity.type() != CV_32FC1)
    throw Error(descriptor + " needs a one-channel CV_32F intensity patch, got " +
                (intensity.empty() ? std::string("an empty image") : "type " + std::to_string(intensity.type())));
  if (intensity.cols != patch_size || intensity.rows != patch_size)
    throw Error(descriptor + " was built for patch_size " + std::to_string(patch_size) + " and got a " +
                std::to_string(intensity.cols) + "x" + std::to_string(intensity.rows) + " patch; expected " +
                std::to_string(patch_size) + "x" + std::to_string(patch_size));
  // NaN or infinity: every exponent bit set. Checked on the bits so that the loop vectorises (cv::checkRange
  // took ~10 us a patch, a tenth of describing it).
  uint32_t all_ones = 0;
  for (int y = 0; y < intensity.rows; ++y)
  {
    const float* row = intensity.ptr<float>(y);
    for (int x = 0; x < intensity.cols; ++x)
    {
      uint32_t bits;
      std::memcpy(&bits, row + x, sizeof(bits));
      all_ones |= uint32_t((bits & 0x7f800000u) == 0x7f800000u);
    }
  }
  if (all_ones)
    throw Error(descriptor + " got a patch with NaN or infinite values; expected finite intensities");
}

cv::Mat toEightBit(const cv::Mat& intensity)
{
  double low = 0.0, high = 0.0;
  cv::minMaxLoc(intensity, &low, &high);
  cv::Mat out(intensity.size(), CV_8UC1, cv::Scalar(0));
  const double range = high - low;
  if (!(range > 0.0))
    return out;
  const double scale = 255.0 / range;
  for (int y = 0; y < intensity.rows; ++y)
  {
    const float* in = intensity.ptr<float>(y);
    uint8_t* o = out.ptr<uint8_t>(y);
    for (int x = 0; x < intensity.cols; ++x)
      o[x] = static_cast<uint8_t>(int((double(in[x]) - low) * scale + 0.5));  // >= 0.5: truncation is floor
  }
  return out;
}

cv::Mat padReflect(const cv::Mat& image, int margin)
{
  cv::Mat out;
  cv::copyMakeBorder(image, out, margin, margin, margin, margin, cv::BORDER_REFLECT);
  return out;
}

void packBytes(const uint8_t* bytes, int count, uint64_t* words, int word_count)
{
  std::memset(words, 0, sizeof(uint64_t) * word_count);
  for (int j = 0; j < count && j < word_count * 8; ++j)
    words[j / 8] |= uint64_t(bytes[j]) << (8 * (j % 8));
}

}  // namespace descriptors
}  // namespace openable
