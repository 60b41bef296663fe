#include "openable/descriptors/ldb.h"

#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"

namespace openable
{
namespace
{
/// Sums over rectangles from an integral image (CV_64F, (rows + 1) x (cols + 1)).
class BoxSums
{
public:
  explicit BoxSums(const cv::Mat& integral) : integral_(integral) {}
  double sum(int x0, int y0, int x1, int y1) const
  {
    return at(y1, x1) - at(y0, x1) - at(y1, x0) + at(y0, x0);
  }

private:
  double at(int y, int x) const
  {
    return integral_.at<double>(y, x);
  }
  const cv::Mat& integral_;
};

/// Mean value over [x0, x1) x [y0, y1); with a mask, over the valid pixels only (0 when there are none).
struct MeanOver
{
  const BoxSums& values;
  const BoxSums* counts;  // null: every pixel valid

  double operator()(int x0, int y0, int x1, int y1) const
  {
    const double s = values.sum(x0, y0, x1, y1);
    const double n = counts ? counts->sum(x0, y0, x1, y1) : double(x1 - x0) * double(y1 - y0);
    return n > 0 ? s / n : 0.0;
  }
};

}  // namespace

void computeLdb(const cv::Mat& values, const cv::Mat& mask, uint64_t* words)
{
  if (values.empty() || values.channels() != 1 || (values.depth() != CV_32F && values.depth() != CV_8U))
    throw Error("LDB needs a one-channel CV_32F or CV_8U patch");
  if (values.rows < 10 || values.cols < 10)
    throw Error("LDB needs a patch of at least 10x10 pixels (two pixels per cell of its 5x5 grid), got " +
                std::to_string(values.cols) + "x" + std::to_string(values.rows) + "; raise patch_size");
  if (!mask.empty() && (mask.size() != values.size() || mask.type() != CV_8UC1))
    throw Error("LDB mask must be CV_8U of the patch size");

  cv::Mat value_integral, count_integral;
  if (mask.empty())
  {
    cv::integral(values, value_integral, CV_64F);
  }
  else
  {
    cv::Mat masked = cv::Mat::zeros(values.size(), CV_32F);
    values.convertTo(masked, CV_32F);
    masked.setTo(0.0f, mask == 0);
    cv::integral(masked, value_integral, CV_64F);
    cv::integral(mask != 0, count_integral, CV_64F);
    count_integral /= 255.0;  // mask != 0 gives 255 per valid pixel
  }
  const BoxSums value_sums(value_integral);
  const BoxSums count_sums(count_integral);
  const MeanOver mean{value_sums, mask.empty() ? nullptr : &count_sums};

  std::memset(words, 0, sizeof(uint64_t) * wordsForBits(kLdbBits));
  int bit = 0;
  double features[25][3];
  for (int n = 2; n <= 5; ++n)
  {
    // Cell borders at round(i * size / n), so the grid always covers the whole patch.
    int xs[6], ys[6];
    for (int i = 0; i <= n; ++i)
    {
      xs[i] = static_cast<int>(std::lround(double(i) * values.cols / n));
      ys[i] = static_cast<int>(std::lround(double(i) * values.rows / n));
    }
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
      {
        const int x0 = xs[c], x1 = xs[c + 1], y0 = ys[r], y1 = ys[r + 1];
        const int xm = (x0 + x1) / 2, ym = (y0 + y1) / 2;
        double* f = features[r * n + c];
        f[0] = mean(x0, y0, x1, y1);
        f[1] = mean(xm, y0, x1, y1) - mean(x0, y0, xm, y1);  // right half minus left half
        f[2] = mean(x0, ym, x1, y1) - mean(x0, y0, x1, ym);  // bottom half minus top half
      }
    const int cells = n * n;
    for (int a = 0; a < cells; ++a)
      for (int b = a + 1; b < cells; ++b)
        for (int k = 0; k < 3; ++k, ++bit)
          if (features[a][k] < features[b][k])  // paper Eq. 1
            words[bit >> 6] |= uint64_t(1) << (bit & 63);
  }
}

void LdbExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  computeLdb(patch.intensity, cv::Mat(), words);
}

}  // namespace openable
