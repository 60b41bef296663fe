#include "openable/area_downsample.h"

#include <algorithm>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "openable/error.h"

namespace openable
{
namespace
{
/// The rounded mean (sum + count / 2) / count of a block, by a multiplication where the sums are 16-bit: with
/// m = 2^32 / count + 1 the error of x m / 2^32 against x / count is below x / 2^32 < 1 / count (x count < 2^32
/// for x < 2^16 and count < 2^16), too small to cross an integer, so the floor is exact.
template <typename Sum>
struct RoundedMean
{
  explicit RoundedMean(uint32_t count) : count(count), multiplier((uint64_t(1) << 32) / count + 1) {}
  uint8_t operator()(Sum sum) const
  {
    const uint64_t x = uint64_t(sum) + count / 2;
    return static_cast<uint8_t>(sizeof(Sum) == 2 ? (x * multiplier) >> 32 : x / count);
  }
  uint32_t count;
  uint64_t multiplier;
};

/// OpenCV's 8-bit BGR -> grey conversion (cv::cvtColor, COLOR_BGR2GRAY, OpenCV 4): Rec. 601 weights in 15-bit
/// fixed point, rounded. The same numbers as cvtColor for every colour (test_preprocessor checks all 2^24).
inline uint8_t grey(uint32_t b, uint32_t g, uint32_t r)
{
  return static_cast<uint8_t>((b * 3735 + g * 19235 + r * 9798 + (1 << 14)) >> 15);
}

/// Every kx x ky block of pixels summed in Sum, wide enough for kx * ky * 255: uint16_t when it fits (twice the
/// lanes of uint32_t per vector add). Per band of ky rows: column sums first (two rows per pass), then the sums
/// of kx neighbouring values at every position, kLanes positions at a time in registers. emit(oy, blocks) then
/// reads the block of output pixel ox, channel c at blocks[ox * kx * channels + c].
template <typename Sum, typename Emit>
void blockSums(const cv::Mat& image, int kx, int ky, cv::Size out, Emit emit)
{
  constexpr int kLanes = 32;
  const int channels = image.channels();
  const int x0 = (image.cols - out.width * kx) / 2;
  const int y0 = (image.rows - out.height * ky) / 2;
  const int row_values = out.width * kx * channels;
  const int window_values = row_values - (kx - 1) * channels;  // positions with kx pixels to their right
  // Padded so that the last group of kLanes positions reads and writes inside (the padding is never emitted).
  std::vector<Sum> column_sums(row_values + kLanes, 0), block_sums(window_values + kLanes);
  Sum* columns = column_sums.data();
  Sum* blocks = block_sums.data();
  for (int oy = 0; oy < out.height; ++oy)
  {
    const auto row = [&](int dy) { return image.ptr<uint8_t>(y0 + oy * ky + dy) + x0 * channels; };
    const uint8_t* first = row(0);
    for (int i = 0; i < row_values; ++i)
      columns[i] = first[i];
    int dy = 1;
    for (; dy + 1 < ky; dy += 2)
    {
      const uint8_t* a = row(dy);
      const uint8_t* b = row(dy + 1);
      for (int i = 0; i < row_values; ++i)
        columns[i] = static_cast<Sum>(columns[i] + a[i] + b[i]);
    }
    if (dy < ky)
    {
      const uint8_t* a = row(dy);
      for (int i = 0; i < row_values; ++i)
        columns[i] = static_cast<Sum>(columns[i] + a[i]);
    }
    for (int i = 0; i < window_values; i += kLanes)
    {
      Sum sum[kLanes];
      for (int j = 0; j < kLanes; ++j)
        sum[j] = columns[i + j];
      for (int dx = 1; dx < kx; ++dx)
      {
        const Sum* shifted = columns + i + dx * channels;
        for (int j = 0; j < kLanes; ++j)
          sum[j] = static_cast<Sum>(sum[j] + shifted[j]);
      }
      for (int j = 0; j < kLanes; ++j)
        blocks[i + j] = sum[j];
    }
    emit(oy, static_cast<const Sum*>(blocks));
  }
}

template <typename Sum>
void decimateWith(const cv::Mat& image, int kx, int ky, cv::Mat& out)
{
  const int channels = image.channels();
  const RoundedMean<Sum> mean(uint32_t(kx) * uint32_t(ky));
  blockSums<Sum>(image, kx, ky, out.size(),
                 [&](int oy, const Sum* blocks)
                 {
                   uint8_t* o = out.ptr<uint8_t>(oy);
                   for (int ox = 0; ox < out.cols; ++ox)
                     for (int c = 0; c < channels; ++c)
                       o[ox * channels + c] = mean(blocks[ox * kx * channels + c]);
                 });
}

/// decimateWith, then grey: the per-pixel conversion on the few pixels left, without the colour image.
template <typename Sum>
void decimateGreyWith(const cv::Mat& image, int kx, int ky, cv::Mat& out)
{
  const int step = kx * image.channels();
  const RoundedMean<Sum> mean(uint32_t(kx) * uint32_t(ky));
  blockSums<Sum>(image, kx, ky, out.size(),
                 [&](int oy, const Sum* blocks)
                 {
                   uint8_t* o = out.ptr<uint8_t>(oy);
                   for (int ox = 0; ox < out.cols; ++ox, blocks += step)
                     o[ox] = grey(mean(blocks[0]), mean(blocks[1]), mean(blocks[2]));
                 });
}

void checkDecimation(const cv::Mat& image, int kx, int ky)
{
  if (image.empty() || image.depth() != CV_8U || image.channels() > 4)
    throw Error("decimate needs an 8-bit image of 1 to 4 channels");
  if (kx < 1 || ky < 1 || kx > image.cols || ky > image.rows)
    throw Error("decimate needs block sides between 1 and the image size");
}

bool fitsSixteenBits(int kx, int ky)
{
  return uint64_t(kx) * uint64_t(ky) * 255 + uint64_t(kx) * uint64_t(ky) / 2 <= UINT16_MAX;
}

/// The largest block sides that keep at least `target` pixels.
cv::Size factorsTowards(const cv::Mat& image, cv::Size target)
{
  if (target.width <= 0 || target.height <= 0)
    throw Error("area downsampling needs a positive target size");
  return cv::Size(std::max(1, image.cols / target.width), std::max(1, image.rows / target.height));
}
}  // namespace

cv::Mat decimate(const cv::Mat& image, int kx, int ky)
{
  checkDecimation(image, kx, ky);
  cv::Mat out(image.rows / ky, image.cols / kx, image.type());
  if (fitsSixteenBits(kx, ky))
    decimateWith<uint16_t>(image, kx, ky, out);
  else
    decimateWith<uint32_t>(image, kx, ky, out);
  return out;
}

cv::Mat decimateGrey(const cv::Mat& image, int kx, int ky)
{
  checkDecimation(image, kx, ky);
  if (image.channels() == 1)
    return decimate(image, kx, ky);
  if (image.channels() == 2)
    throw Error("decimateGrey needs a grey, BGR or BGRA image");
  cv::Mat out(image.rows / ky, image.cols / kx, CV_8UC1);
  if (fitsSixteenBits(kx, ky))
    decimateGreyWith<uint16_t>(image, kx, ky, out);
  else
    decimateGreyWith<uint32_t>(image, kx, ky, out);
  return out;
}

cv::Mat decimateTowards(const cv::Mat& image, cv::Size target)
{
  const cv::Size k = factorsTowards(image, target);
  return k.width == 1 && k.height == 1 ? image : decimate(image, k.width, k.height);
}

cv::Mat decimateGreyTowards(const cv::Mat& image, cv::Size target)
{
  const cv::Size k = factorsTowards(image, target);
  if (k.width > 1 || k.height > 1)
    return decimateGrey(image, k.width, k.height);
  if (image.channels() == 1)
    return image;
  cv::Mat out;
  cv::cvtColor(image, out, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return out;
}

cv::Mat areaDownsample(const cv::Mat& image, cv::Size target)
{
  const cv::Mat decimated = decimateTowards(image, target);
  if (decimated.size() == target)
    return decimated;
  cv::Mat out;
  cv::resize(decimated, out, target, 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace openable
