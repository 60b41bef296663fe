#include <algorithm>
#include <cmath>
#include <cstring>

#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "descriptors/patch_input.h"

namespace openable
{
namespace
{
/// xorshift64* (Marsaglia / Vigna): a tiny generator whose output is defined by integer arithmetic alone, so
/// the pattern is the same with every compiler and standard library (std::normal_distribution is not).
class PatternRandom
{
public:
  double uniform()  // [0, 1), exact: 53 random bits times 2^-53
  {
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return double((state_ * 0x2545F4914F6CDD1DULL) >> 11) * (1.0 / 9007199254740992.0);
  }
  /// Standard normal by Irwin-Hall (sum of 12 uniforms minus 6: mean 0, variance 1). Only additions, so no
  /// libm rounding differences between machines can change the pattern; its tails beyond 2.5 sigma, the
  /// only place it differs visibly from a Gaussian, are rejected below anyway.
  double gaussian()
  {
    double s = 0.0;
    for (int i = 0; i < 12; ++i)
      s += uniform();
    return s - 6.0;
  }

private:
  uint64_t state_ = 0x0DDB1A5E5BADC0DEULL;  // any constant non-zero seed; this one is the pattern
};

/// BRIEF paper, sampling strategy G II: both points i.i.d. isotropic Gaussian around the centre with
/// sigma = S / 5 (S the patch side). A coordinate outside the patch is drawn again instead of clipped, so no
/// tests pile up on the border row and column.
std::vector<float> makeUnitPattern()
{
  PatternRandom random;
  auto coordinate = [&random]
  {
    for (;;)
    {
      const double c = random.gaussian() / 5.0;
      if (c >= -0.5 && c < 0.5)
        return static_cast<float>(c);
    }
  };
  std::vector<float> pattern(4 * BriefExtractor::kBits);
  for (float& c : pattern)
    c = coordinate();
  return pattern;
}

/// Mirror index into [0, n), as cv::BORDER_REFLECT (fedcba|abcdef|fedcba).
int reflect(int i, int n)
{
  while (i < 0 || i >= n)
    i = i < 0 ? -i - 1 : 2 * n - i - 1;
  return i;
}
}  // namespace

const std::vector<float>& BriefExtractor::unitPattern()
{
  static const std::vector<float> pattern = makeUnitPattern();
  return pattern;
}

BriefExtractor::BriefExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("BRIEF needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
  const auto& unit = unitPattern();
  points_.resize(unit.size());
  const double centre = patch_size / 2.0;
  for (size_t i = 0; i < unit.size(); ++i)
    points_[i] = std::min(patch_size - 1, static_cast<int>(std::floor(centre + double(unit[i]) * patch_size)));

  // The BRIEF paper smooths its 48x48 patches with sigma 2; keep that ratio for any patch_size.
  const double sigma = patch_size / 24.0;
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  kernel_.resize(2 * radius + 1);
  double total = 0.0;
  for (int k = -radius; k <= radius; ++k)
    total += kernel_[k + radius] = std::exp(-0.5 * k * k / (sigma * sigma));
  for (double& w : kernel_)
    w /= total;
}

void BriefExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  descriptors::checkIntensityPatch(name(), patch.intensity, patch_size_);
  const cv::Mat& image = patch.intensity;
  const int n = patch_size_;
  const int radius = static_cast<int>(kernel_.size() / 2);

  // Separable Gaussian, written out rather than cv::GaussianBlur so that the summation order, and so every
  // bit, does not depend on which SIMD path OpenCV picks on this CPU. Rows for the whole patch, columns
  // only at the sampled points.
  std::vector<double> rows(size_t(n) * n);
  std::vector<double> line(n + 2 * radius);  // one mirrored row, so the inner loop needs no index mapping
  for (int y = 0; y < n; ++y)
  {
    const float* in = image.ptr<float>(y);
    for (int x = -radius; x < n + radius; ++x)
      line[x + radius] = in[reflect(x, n)];
    for (int x = 0; x < n; ++x)
    {
      double s = 0.0;
      for (int k = 0; k <= 2 * radius; ++k)
        s += kernel_[k] * line[x + k];
      rows[size_t(y) * n + x] = s;
    }
  }
  auto smoothed = [&](int x, int y)
  {
    double s = 0.0;
    for (int k = -radius; k <= radius; ++k)
      s += kernel_[k + radius] * rows[size_t(reflect(y + k, n)) * n + x];
    return s;
  };

  std::memset(words, 0, sizeof(uint64_t) * wordsForBits(kBits));
  for (int bit = 0; bit < kBits; ++bit)
  {
    const int* p = &points_[4 * bit];
    if (smoothed(p[0], p[1]) < smoothed(p[2], p[3]))
      words[bit >> 6] |= uint64_t(1) << (bit & 63);
  }
}

}  // namespace openable
