#include <algorithm>
#include <cmath>
#include <cstring>
#include <tuple>

#include "descriptors/box_integral.h"
#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "descriptors/patch_input.h"

namespace openable
{
namespace
{
constexpr int kRings = 7;
constexpr int kPerRing = 6;
/// Radii grow geometrically from the centre outwards, as receptive fields do across the retina (FREAK
/// paper, Fig. 3), and every field's smoothing is half its radius so neighbouring fields overlap.
constexpr double kRingRatio = 1.5;
constexpr double kSigmaPerRadius = 0.5;
/// Outer radius (in half patch sides) such that the outermost fields, radius plus smoothing, touch the
/// patch border: r * (1 + 0.5) = 1.
constexpr double kOuterRadius = 1.0 / (1.0 + kSigmaPerRadius);

/// cos and sin of multiples of 30 degrees, from exact arithmetic only (sqrt is correctly rounded), so the
/// field positions are bit-identical on every machine.
void unitCircle(int step30, double* c, double* s)
{
  const double h = std::sqrt(3.0) / 2.0;
  static const double cosines[12] = {1.0, h, 0.5, 0.0, -0.5, -h, -1.0, -h, -0.5, 0.0, 0.5, h};
  *c = cosines[step30 % 12];
  *s = cosines[(step30 + 9) % 12];  // sin(a) = cos(a - 90 degrees)
}

int ringOf(int field)
{
  return field == 0 ? 0 : 1 + (field - 1) / kPerRing;
}

/// The pairs, chosen by geometry alone (no training data to overfit): every pair of fields whose rings are
/// at most two apart, i.e. of comparable smoothing, so each test compares structure at one scale. That is
/// 513 pairs; they are ordered coarse to fine like FREAK's learned pairs (outermost ring of the pair first,
/// then rings of the same ring before neighbouring rings, then field indices), and the last, finest one is
/// dropped to make 512.
std::vector<std::pair<int, int>> makePairs()
{
  std::vector<std::tuple<int, int, int, int>> keyed;  // -coarser ring, ring distance, a, b
  for (int a = 0; a < FreakExtractor::kFields; ++a)
    for (int b = a + 1; b < FreakExtractor::kFields; ++b)
    {
      const int ra = ringOf(a), rb = ringOf(b);
      if (std::abs(ra - rb) <= 2)
        keyed.emplace_back(-std::max(ra, rb), std::abs(ra - rb), a, b);
    }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < FreakExtractor::kBits; ++i)
    pairs.emplace_back(std::get<2>(keyed[i]), std::get<3>(keyed[i]));
  return pairs;
}
}  // namespace

const std::vector<std::pair<int, int>>& FreakExtractor::pairs()
{
  static const std::vector<std::pair<int, int>> pairs = makePairs();
  return pairs;
}

FreakExtractor::FreakExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("FREAK needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
  const double half = patch_size / 2.0;
  // Innermost ring radius: the outer one divided by the ratio six times.
  double radius = kOuterRadius * half;
  for (int r = 1; r < kRings; ++r)
    radius /= kRingRatio;
  fields_.push_back({half, half, kSigmaPerRadius * radius, 0});  // centre field, as fine as ring 1
  for (int ring = 1; ring <= kRings; ++ring, radius *= kRingRatio)
    for (int j = 0; j < kPerRing; ++j)
    {
      // Alternate rings are turned by half a step (30 degrees) so fields of neighbouring rings interleave.
      double c, s;
      unitCircle(2 * j + (ring % 2), &c, &s);
      fields_.push_back({half + radius * c, half + radius * s, kSigmaPerRadius * radius, ring});
    }
}

void FreakExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  descriptors::checkIntensityPatch(name(), patch.intensity, patch_size_);
  // Each receptive field is the mean over a box of half side sigma (a box approximates the Gaussian, as
  // FREAK's own implementation does); fractional boxes keep the pattern exact at any patch_size.
  const descriptors::BoxIntegral integral(patch.intensity, 2);
  double response[kFields];
  for (int i = 0; i < kFields; ++i)
    response[i] = integral.mean(fields_[i].x, fields_[i].y, fields_[i].sigma);

  std::memset(words, 0, sizeof(uint64_t) * wordsForBits(kBits));
  const auto& list = pairs();
  for (int bit = 0; bit < kBits; ++bit)
    if (response[list[bit].first] < response[list[bit].second])
      words[bit >> 6] |= uint64_t(1) << (bit & 63);
}

}  // namespace openable
