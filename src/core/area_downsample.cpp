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
/// Every kx x ky block of pixels summed in Sum, wide enough for kx * ky * 255: uint16_t when it fits (twice the
/// lanes of uint32_t per vector add). Per band of ky rows: column sums first, then, still one vectorised pass
/// per dx, the sums of kx neighbouring pixels at every position; each output pixel takes the one at its
/// block's start. The mean is a multiplication by the reciprocal in double, exact here: a quotient of integers
/// below 2^32 is at least 1 / count away from the next integer, far more than the rounding error.
template <typename Sum>
void decimateWith(const cv::Mat& image, int kx, int ky, cv::Mat& out)
{
  const int channels = image.channels();
  const int x0 = (image.cols - out.cols * kx) / 2;
  const int y0 = (image.rows - out.rows * ky) / 2;
  const int row_values = out.cols * kx * channels;
  const int window_values = row_values - (kx - 1) * channels;  // positions with kx pixels to their right
  const uint32_t count = uint32_t(kx) * uint32_t(ky);
  const double inverse = 1.0 / double(count);
  std::vector<Sum> column_sums(row_values), block_sums(window_values);
  Sum* columns = column_sums.data();
  Sum* blocks = block_sums.data();
  for (int oy = 0; oy < out.rows; ++oy)
  {
    const uint8_t* first = image.ptr<uint8_t>(y0 + oy * ky) + x0 * channels;
    for (int i = 0; i < row_values; ++i)
      columns[i] = first[i];
    for (int dy = 1; dy < ky; ++dy)
    {
      const uint8_t* in = image.ptr<uint8_t>(y0 + oy * ky + dy) + x0 * channels;
      for (int i = 0; i < row_values; ++i)
        columns[i] = static_cast<Sum>(columns[i] + in[i]);
    }
    for (int i = 0; i < window_values; ++i)
      blocks[i] = columns[i];
    for (int dx = 1; dx < kx; ++dx)
    {
      const Sum* shifted = columns + dx * channels;
      for (int i = 0; i < window_values; ++i)
        blocks[i] = static_cast<Sum>(blocks[i] + shifted[i]);
    }
    uint8_t* o = out.ptr<uint8_t>(oy);
    for (int ox = 0; ox < out.cols; ++ox)
      for (int c = 0; c < channels; ++c)  // round half up
        o[ox * channels + c] = static_cast<uint8_t>(double(blocks[ox * kx * channels + c] + count / 2) * inverse);
  }
}
}  // namespace

cv::Mat decimate(const cv::Mat& image, int kx, int ky)
{
  if (image.empty() || image.depth() != CV_8U || image.channels() > 4)
    throw Error("decimate needs an 8-bit image of 1 to 4 channels");
  if (kx < 1 || ky < 1 || kx > image.cols || ky > image.rows)
    throw Error("decimate needs block sides between 1 and the image size");
  cv::Mat out(image.rows / ky, image.cols / kx, image.type());
  if (uint64_t(kx) * uint64_t(ky) * 255 + uint64_t(kx) * uint64_t(ky) / 2 <= UINT16_MAX)
    decimateWith<uint16_t>(image, kx, ky, out);
  else
    decimateWith<uint32_t>(image, kx, ky, out);
  return out;
}

cv::Mat decimateTowards(const cv::Mat& image, cv::Size target)
{
  if (target.width <= 0 || target.height <= 0)
    throw Error("area downsampling needs a positive target size");
  const int kx = std::max(1, image.cols / target.width);
  const int ky = std::max(1, image.rows / target.height);
  return kx == 1 && ky == 1 ? image : decimate(image, kx, ky);
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
