#include "openable/area_downsample.h"

#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "openable/error.h"

namespace openable
{
namespace
{
/// Sums kx column sums per output pixel and rounds their mean to 8 bits. The channel count is a template
/// parameter so that the inner loop is unrolled; the mean is a multiplication by the reciprocal in double,
/// exact here: a quotient n / count of integers below 2^32 is at least 1 / count away from the next integer,
/// far more than the rounding error of n * (1.0 / count).
template <int C, typename Sum>
void meanOfBlocks(const Sum* sums, int out_cols, int kx, uint32_t count, uint8_t* out)
{
  const double inverse = 1.0 / double(count);
  const uint32_t half = count / 2;
  for (int ox = 0; ox < out_cols; ++ox, sums += kx * C)
    for (int c = 0; c < C; ++c)
    {
      uint32_t s = half;
      for (int dx = 0; dx < kx; ++dx)
        s += sums[dx * C + c];
      out[ox * C + c] = static_cast<uint8_t>(double(s) * inverse);  // round half up
    }
}
}  // namespace

namespace
{
/// Column sums of each band of ky rows (a loop the compiler vectorises), then kx of them per pixel: every
/// input byte is read once and added once. Sum is uint16_t when ky * 255 fits it: twice the lanes per add.
template <typename Sum>
void decimateWith(const cv::Mat& image, int kx, int ky, cv::Mat& out)
{
  const int channels = image.channels();
  const int x0 = (image.cols - out.cols * kx) / 2;
  const int y0 = (image.rows - out.rows * ky) / 2;
  const int row_values = out.cols * kx * channels;
  const uint32_t count = uint32_t(kx) * uint32_t(ky);
  std::vector<Sum> column_sums(row_values);
  Sum* sums = column_sums.data();
  for (int oy = 0; oy < out.rows; ++oy)
  {
    const uint8_t* first = image.ptr<uint8_t>(y0 + oy * ky) + x0 * channels;
    for (int i = 0; i < row_values; ++i)
      sums[i] = first[i];
    for (int dy = 1; dy < ky; ++dy)
    {
      const uint8_t* in = image.ptr<uint8_t>(y0 + oy * ky + dy) + x0 * channels;
      for (int i = 0; i < row_values; ++i)
        sums[i] = static_cast<Sum>(sums[i] + in[i]);
    }
    uint8_t* o = out.ptr<uint8_t>(oy);
    switch (channels)
    {
      case 1:
        meanOfBlocks<1>(sums, out.cols, kx, count, o);
        break;
      case 2:
        meanOfBlocks<2>(sums, out.cols, kx, count, o);
        break;
      case 3:
        meanOfBlocks<3>(sums, out.cols, kx, count, o);
        break;
      default:
        meanOfBlocks<4>(sums, out.cols, kx, count, o);
        break;
    }
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
  if (ky * 255 <= UINT16_MAX)
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
