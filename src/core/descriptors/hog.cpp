#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "descriptors/patch_input.h"

namespace openable
{
/// The window's layout as OpenCV's HOG cache lays it out: 2x2-cell blocks moved by one cell, and for every
/// pixel of a block the cells it votes in with their weights (Gaussian window times bilinear cell weight).
/// Pixels are kept in OpenCV's order (those voting in one cell, then two, then four; columns of the block
/// outer, rows inner) because each histogram bin is a float sum, and the order of its terms decides its
/// last bits.
struct HogExtractor::Blocks
{
  struct Pixel
  {
    int x, y;
    int offset;        ///< of its gradient pair in the block's first row (the window is continuous)
    int cells;         ///< 1, 2 or 4
    int histogram[4];  ///< offset of each cell's 9 bins in the block histogram
    float weight[4];   ///< Gaussian weight times the cell's bilinear weight (the float product OpenCV forms)
  };
  cv::HOGDescriptor hog;  ///< OpenCV's gradients and orientation bins
  int window = 0;
  int cell = 0;
  std::vector<Pixel> pixels;
  size_t ends[3] = {0, 0, 0};  ///< where the pixels voting in 1, 2 and 4 cells end

  explicit Blocks(int window)
    : hog(cv::Size(window, window), cv::Size(window / 2, window / 2), cv::Size(window / 4, window / 4),
          cv::Size(window / 4, window / 4), kBins),
      window(window),
      cell(window / 4)
  {
    const int block = 2 * cell;
    // Gaussian window over the block, sigma = block / 4 (OpenCV's default: (width + height) / 8).
    const float sigma = static_cast<float>(hog.getWinSigma());
    const float scale = 1.f / (sigma * sigma * 2);
    const float half = block * 0.5f;
    std::vector<Pixel> by_cells[3];  // voting in 1, 2, 4 cells
    for (int x = 0; x < block; ++x)
      for (int y = 0; y < block; ++y)
      {
        const float dx = (float(x) - half) * (float(x) - half), dy = (float(y) - half) * (float(y) - half);
        const float gaussian = std::exp(-(dy + dx) * scale);
        // Bilinear weights between the centres of the two cells around the pixel, per axis; a pixel outside
        // the centres of the outer cells votes in the nearest cell only (with weight 1 - its distance).
        struct Axis
        {
          int votes;
          int cell[2];
          float weight[2];
        };
        const auto axis = [&](int i)
        {
          float f = (i + 0.5f) / cell - 0.5f;
          const int c = cvFloor(f);
          f -= c;
          if (c >= 0 && c + 1 < 2)
            return Axis{2, {c, c + 1}, {1.f - f, f}};
          return c >= 0 ? Axis{1, {c, 0}, {1.f - f, 0.f}} : Axis{1, {c + 1, 0}, {f, 0.f}};
        };
        const Axis ax = axis(x), ay = axis(y);
        Pixel p{x, y, 2 * (y * window + x), 0, {0, 0, 0, 0}, {0, 0, 0, 0}};
        // OpenCV's order of the votes: x-major within each y (00, 10, 01, 11).
        for (int j = 0; j < ay.votes; ++j)
          for (int i = 0; i < ax.votes; ++i)
          {
            p.histogram[p.cells] = (ax.cell[i] * 2 + ay.cell[j]) * kBins;
            p.weight[p.cells] = gaussian * (ax.weight[i] * ay.weight[j]);
            ++p.cells;
          }
        by_cells[p.cells == 1 ? 0 : p.cells == 2 ? 1 : 2].push_back(p);
      }
    for (int group = 0; group < 3; ++group)
    {
      pixels.insert(pixels.end(), by_cells[group].begin(), by_cells[group].end());
      ends[group] = pixels.size();
    }
  }

  /// The votes of pixels [begin, end), all voting in `Cells` cells: a fixed inner loop.
  template <int Cells>
  void vote(const float* grad, const uint8_t* qangle, size_t begin, size_t end, float* hist) const
  {
    for (size_t i = begin; i < end; ++i)
    {
      const Pixel& p = pixels[i];
      const float a0 = grad[p.offset], a1 = grad[p.offset + 1];
      const int h0 = qangle[p.offset], h1 = qangle[p.offset + 1];
      for (int k = 0; k < Cells; ++k)
      {
        // Each product rounded before the sum, as OpenCV computes it (no FMA in a baseline x86-64 build).
        const float t0 = a0 * p.weight[k], t1 = a1 * p.weight[k];
        hist[p.histogram[k] + h0] += t0;
        hist[p.histogram[k] + h1] += t1;
      }
    }
  }

  /// One block's 36 values: votes summed as OpenCV sums them, then L2-Hys (L2, clip at 0.2, L2 again) with
  /// OpenCV's four partial sums of squares.
  void block(const cv::Mat& grad, const cv::Mat& qangle, int x0, int y0, float* hist) const
  {
    constexpr int kSize = 4 * kBins;
    std::fill(hist, hist + kSize, 0.f);
    const int origin = 2 * (y0 * window + x0);
    const float* g = grad.ptr<float>() + origin;
    const uint8_t* q = qangle.ptr<uint8_t>() + origin;
    vote<1>(g, q, 0, ends[0], hist);
    vote<2>(g, q, ends[0], ends[1], hist);
    vote<4>(g, q, ends[1], ends[2], hist);
    const auto sumOfSquares = [&]()
    {
      float part[4] = {0.f, 0.f, 0.f, 0.f};
      for (int i = 0; i < kSize; i += 4)
        for (int j = 0; j < 4; ++j)
          part[j] = i == 0 ? hist[j] * hist[j] : part[j] + hist[i + j] * hist[i + j];
      return (part[0] + part[1]) + (part[2] + part[3]);
    };
    float scale = 1.f / (std::sqrt(sumOfSquares()) + kSize * 0.1f);
    const float threshold = static_cast<float>(hog.L2HysThreshold);
    for (int i = 0; i < kSize; ++i)
      hist[i] = std::min(hist[i] * scale, threshold);
    scale = 1.f / (std::sqrt(sumOfSquares()) + 1e-3f);
    for (int i = 0; i < kSize; ++i)
      hist[i] *= scale;
  }
};

HogExtractor::HogExtractor(int patch_size) : patch_size_(patch_size), window_(patch_size / kCells * kCells)
{
  if (patch_size < minPatchSize())
    throw Error("HOG needs patch_size >= " + std::to_string(minPatchSize()) + " (4x4 cells of 2 pixels), got " +
                std::to_string(patch_size));
  blocks_ = std::make_shared<const Blocks>(window_);
}

void HogExtractor::describeFloat(const Patch& patch, float* values) const
{
  descriptors::checkIntensityPatch(name(), patch.intensity, patch_size_);
  cv::Mat image = descriptors::toEightBit(patch.intensity);
  if (window_ != patch_size_)
    cv::resize(image, image, cv::Size(window_, window_), 0, 0, cv::INTER_AREA);
  // The patch is the detection window: 4x4 cells, Dalal and Triggs' 2x2-cell blocks with a one-cell stride,
  // 9 unsigned bins, L2-Hys block normalisation (OpenCV's defaults for the rest). Blocks in OpenCV's order:
  // columns outer, rows inner.
  cv::Mat grad, qangle;
  blocks_->hog.computeGradient(image, grad, qangle);
  if (!grad.isContinuous() || !qangle.isContinuous() || grad.cols != window_ || qangle.cols != window_)
    throw Error("HOG: unexpected gradient layout from OpenCV");
  const int cell = blocks_->cell;
  for (int bx = 0; bx < kCells - 1; ++bx)
    for (int by = 0; by < kCells - 1; ++by, values += 4 * kBins)
      blocks_->block(grad, qangle, bx * cell, by * cell, values);
}

}  // namespace openable
