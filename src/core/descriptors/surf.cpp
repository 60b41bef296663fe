#include <cmath>

#include "descriptors/box_integral.h"
#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "descriptors/patch_input.h"

namespace openable
{
namespace
{
/// SURF (Bay et al. 2008, section 4.2) in units of the scale s: a 20s x 20s window of 4 x 4 subregions, each
/// sampled at 5 x 5 points spaced s apart, Haar wavelets of side 2s, weighted by a Gaussian of sigma 3.3s
/// centred at the keypoint.
constexpr int kSamples = 20;
constexpr int kPerSubregion = 5;
constexpr double kWeightSigma = 3.3;

/// The Gaussian weight of sample (i, j) depends on the indices only, not on the patch size.
const std::vector<double>& sampleWeights()
{
  static const std::vector<double> weights = []
  {
    std::vector<double> w(kSamples * kSamples);
    for (int j = 0; j < kSamples; ++j)
      for (int i = 0; i < kSamples; ++i)
      {
        const double u = i - 9.5, v = j - 9.5;
        w[j * kSamples + i] = std::exp(-(u * u + v * v) / (2.0 * kWeightSigma * kWeightSigma));
      }
    return w;
  }();
  return weights;
}
}  // namespace

SurfExtractor::SurfExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("SURF needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
}

void SurfExtractor::describeFloat(const Patch& patch, float* values) const
{
  descriptors::checkIntensityPatch(name(), patch.intensity, patch_size_);
  const double s = patch_size_ / double(kSamples);  // the window is the patch
  const double centre = patch_size_ / 2.0;
  // Samples reach 9.5s from the centre and their wavelets s further: 0.525 patch sides, so a mirrored border
  // of 2.5 % of the patch (plus rounding) keeps every wavelet on real data.
  const int margin = static_cast<int>(std::ceil(0.025 * patch_size_)) + 2;
  // Fractional boxes: the wavelets have exactly side 2s at every patch_size, where SURF on an image pyramid
  // rounds them to whole pixels.
  const descriptors::BoxIntegral integral(patch.intensity, margin);
  const auto& weights = sampleWeights();
  const double area = 2.0 * s * s;  // each half of a wavelet; responses become mean differences

  double out[kLength] = {};
  for (int j = 0; j < kSamples; ++j)
    for (int i = 0; i < kSamples; ++i)
    {
      const double x = centre + (i - 9.5) * s, y = centre + (j - 9.5) * s;
      const double w = weights[j * kSamples + i] / area;
      const double dx = w * (integral.sum(x, y - s, x + s, y + s) - integral.sum(x - s, y - s, x, y + s));
      const double dy = w * (integral.sum(x - s, y, x + s, y + s) - integral.sum(x - s, y - s, x + s, y));
      double* sub = out + 4 * ((j / kPerSubregion) * 4 + i / kPerSubregion);  // subregions row by row
      sub[0] += dx;
      sub[1] += std::abs(dx);
      sub[2] += dy;
      sub[3] += std::abs(dy);
    }
  // Unit length, as SURF specifies (contrast invariance); a flat patch stays all zero.
  double norm = 0.0;
  for (double v : out)
    norm += v * v;
  norm = std::sqrt(norm);
  for (int k = 0; k < kLength; ++k)
    values[k] = static_cast<float>(norm > 0.0 ? out[k] / norm : 0.0);
}

}  // namespace openable
