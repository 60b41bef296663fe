#include "openable/description/area_downsample.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
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

/// columns[i] += a[i] + b[i] (b may be null; = instead of += for a band's first rows) and blocks[i] = sum over
/// dx < kx of columns[i + dx * step], for i < n, in groups of kLanes positions (the arrays are padded). Compiled
/// twice, for AVX2 and for any x86-64 (the package builds without -march), and chosen when the library loads:
/// twice the lanes per instruction on the two loops that read every byte of the image.
constexpr int kLanes = 32;

template <typename Sum>
inline void addRows(Sum* __restrict columns, const uint8_t* __restrict a, const uint8_t* __restrict b, int n,
                    bool first)
{
  // A band's first rows set the sums: no clearing pass over them before (a memset per band).
  if (first && b)
    for (int i = 0; i < n; ++i)
      columns[i] = static_cast<Sum>(a[i] + b[i]);
  else if (first)
    for (int i = 0; i < n; ++i)
      columns[i] = a[i];
  else if (b)
    for (int i = 0; i < n; ++i)
      columns[i] = static_cast<Sum>(columns[i] + a[i] + b[i]);
  else
    for (int i = 0; i < n; ++i)
      columns[i] = static_cast<Sum>(columns[i] + a[i]);
}

template <typename Sum>
inline void windowSums(const Sum* __restrict columns, int n, int kx, int step, Sum* __restrict blocks)
{
  // A 32-byte vector of sums held in a register across the kx terms (a plain array of them went through the
  // stack for every term).
  typedef Sum Vector __attribute__((vector_size(32)));
  constexpr int kVector = 32 / sizeof(Sum);
  static_assert(kLanes % kVector == 0, "the padding covers whole vectors");
  for (int i = 0; i < n; i += kVector)
  {
    Vector sum, term;
    std::memcpy(&sum, columns + i, sizeof(sum));
    for (int dx = 1; dx < kx; ++dx)
    {
      std::memcpy(&term, columns + i + dx * step, sizeof(term));
      sum += term;
    }
    std::memcpy(blocks + i, &sum, sizeof(sum));
  }
}

#if defined(__x86_64__) && defined(__GNUC__)
#define OPENABLE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define OPENABLE_CLONES
#endif
OPENABLE_CLONES void addRows16(uint16_t* columns, const uint8_t* a, const uint8_t* b, int n, bool first)
{
  addRows(columns, a, b, n, first);
}
OPENABLE_CLONES void addRows32(uint32_t* columns, const uint8_t* a, const uint8_t* b, int n, bool first)
{
  addRows(columns, a, b, n, first);
}
OPENABLE_CLONES void windowSums16(const uint16_t* columns, int n, int kx, int step, uint16_t* blocks)
{
  windowSums(columns, n, kx, step, blocks);
}
OPENABLE_CLONES void windowSums32(const uint32_t* columns, int n, int kx, int step, uint32_t* blocks)
{
  windowSums(columns, n, kx, step, blocks);
}
inline void addRowsTo(uint16_t* c, const uint8_t* a, const uint8_t* b, int n, bool first)
{
  addRows16(c, a, b, n, first);
}
inline void addRowsTo(uint32_t* c, const uint8_t* a, const uint8_t* b, int n, bool first)
{
  addRows32(c, a, b, n, first);
}
inline void windowSumsOf(const uint16_t* c, int n, int kx, int step, uint16_t* out)
{
  windowSums16(c, n, kx, step, out);
}
inline void windowSumsOf(const uint32_t* c, int n, int kx, int step, uint32_t* out)
{
  windowSums32(c, n, kx, step, out);
}

/// Every kx x ky block of pixels summed in Sum, wide enough for kx * ky * 255: uint16_t when it fits (twice the
/// lanes of uint32_t per vector add). Per band of ky rows: column sums first (two rows per pass), then the sums
/// of kx neighbouring values at every position, kLanes positions at a time in registers. emit(oy, blocks) then
/// reads the block of output pixel ox, channel c at blocks[ox * kx * channels + c].
template <typename Sum, typename Emit>
void blockSums(const cv::Mat& image, int kx, int ky, cv::Size out, Emit emit)
{
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
    int dy = 0;
    for (; dy + 1 < ky; dy += 2)
      addRowsTo(columns, row(dy), row(dy + 1), row_values, dy == 0);
    if (dy < ky)
      addRowsTo(columns, row(dy), nullptr, row_values, dy == 0);
    windowSumsOf(columns, window_values, kx, channels, blocks);
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

/// One source pixel's share of one target pixel along an axis.
struct AreaWeight
{
  int source;
  int target;
  float weight;
};

/// OpenCV's area weights along one axis (computeResizeAreaTab in its resize.cpp): for each target pixel, in
/// source order, the partial pixel before its cell, the whole ones, the partial one after; the overlap over the
/// cell width in double, rounded to float. The same table gives the same floats.
std::vector<AreaWeight> areaWeights(int source, int target, double scale)
{
  std::vector<AreaWeight> out;
  for (int t = 0; t < target; ++t)
  {
    const double begin = t * scale, end = begin + scale;
    const double width = std::min(scale, source - begin);
    const int last = std::min(cvFloor(end), source - 1);
    const int first = std::min(cvCeil(begin), last);
    if (first - begin > 1e-3)
      out.push_back({first - 1, t, float((first - begin) / width)});
    for (int s = first; s < last; ++s)
      out.push_back({s, t, float(1.0 / width)});
    if (end - last > 1e-3)
      out.push_back({last, t, float(std::min(std::min(end - last, 1.), width) / width)});
  }
  return out;
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

cv::Mat areaResize(const cv::Mat& image, cv::Size target)
{
  // OpenCV's choice of path (cv::resize, INTER_AREA): a true area resize when shrinking, its integer-ratio
  // fast path when both ratios are whole numbers.
  const double scale_x = 1. / (double(target.width) / image.cols), scale_y = 1. / (double(target.height) / image.rows);
  const bool integer_ratios = std::abs(scale_x - cv::saturate_cast<int>(scale_x)) < DBL_EPSILON &&
                              std::abs(scale_y - cv::saturate_cast<int>(scale_y)) < DBL_EPSILON;
  if (image.type() != CV_32FC1 || target.width <= 0 || target.height <= 0 || scale_x < 1 || scale_y < 1 ||
      integer_ratios)
  {
    cv::Mat out;
    cv::resize(image, out, target, 0, 0, cv::INTER_AREA);
    return out;
  }
  const std::vector<AreaWeight> columns = areaWeights(image.cols, target.width, scale_x);
  const std::vector<AreaWeight> rows = areaWeights(image.rows, target.height, scale_y);
  // Same width: every column weight is 1 and a source row is its own horizontal sum, a loop that vectorises.
  const bool same_width = image.cols == target.width;
  cv::Mat out(target, CV_32FC1);
  std::vector<float> row(target.width), sum(target.width, 0.f);
  int current = 0;
  // As OpenCV: each source row's horizontal sums, then added into its target row's sums, terms in table order;
  // each product rounded before its sum (no FMA: a baseline x86-64 build, as OpenCV's own).
  for (const AreaWeight& r : rows)
  {
    const float* s = image.ptr<float>(r.source);
    if (same_width)
      for (int x = 0; x < target.width; ++x)
        row[x] = 0.f + s[x];  // OpenCV's sums start at +0: -0 becomes +0
    else
    {
      std::fill(row.begin(), row.end(), 0.f);
      for (const AreaWeight& c : columns)
        row[c.target] += s[c.source] * c.weight;
    }
    if (r.target != current)
    {
      std::copy(sum.begin(), sum.end(), out.ptr<float>(current));
      for (int x = 0; x < target.width; ++x)
        sum[x] = r.weight * row[x];
      current = r.target;
    }
    else
      for (int x = 0; x < target.width; ++x)
        sum[x] += r.weight * row[x];
  }
  std::copy(sum.begin(), sum.end(), out.ptr<float>(current));
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
