// ORB, BRISK and SIFT from OpenCV's features2d, computed for one keypoint at the patch centre.
#include <cstring>
#include <opencv2/features2d.hpp>

#include "descriptors/descriptor_implementations.h"
#include "openable/error.h"
#include "descriptors/patch_input.h"

namespace openable
{
namespace
{
/// Mirror margin around the patch for ORB and BRISK: OpenCV drops a keypoint whose sampling pattern would
/// leave the image, and both patterns here span the whole patch. Half a patch on each side puts the centre a
/// full patch away from every border, more than either pattern (with its smoothing) reaches.
int marginFor(int patch_size)
{
  return patch_size / 2 + 2;
}

/// SIFT keeps its keypoint at any distance from the border (it skips samples outside the image), but its 4x4
/// histograms interpolate half a bin (patch_size / 8) beyond the patch and need one more pixel for the
/// gradient: that much real (mirrored) data is enough. A smaller image matters for SIFT, whose Gaussian
/// pyramid costs time in proportion to the pixels.
int siftMarginFor(int patch_size)
{
  return patch_size / 8 + 2;
}

/// Describes the keypoint `key` of `image` (8-bit, padded) and returns the one descriptor row. Throws rather
/// than silently returning nothing when OpenCV dropped the keypoint.
cv::Mat computeOne(cv::Feature2D& extractor, const cv::Mat& image, const cv::KeyPoint& key, const std::string& name,
                   int patch_size)
{
  std::vector<cv::KeyPoint> keys{key};
  cv::Mat out;
  extractor.compute(image, keys, out);
  if (keys.size() != 1 || out.rows != 1)
    throw Error(name + ": OpenCV dropped the centre keypoint of a " + std::to_string(patch_size) + "x" +
                std::to_string(patch_size) + " patch; use a larger patch_size");
  return out;
}

cv::KeyPoint centreKey(int patch_size, int margin, float size)
{
  // Pixel centres are at integer coordinates, so the centre of a patch_size-wide patch is (patch_size - 1) / 2.
  const float centre = static_cast<float>(margin) + 0.5f * (patch_size - 1);
  return cv::KeyPoint(centre, centre, size, 0.0f /* upright */, 0.0f, 0 /* octave 0, layer 0 */);
}

cv::Mat paddedEightBit(const Patch& patch, const std::string& name, int patch_size, int margin)
{
  descriptors::checkIntensityPatch(name, patch.intensity, patch_size);
  return descriptors::padReflect(descriptors::toEightBit(patch.intensity), margin);
}
}  // namespace

// ----------------------------------------------------------------------------------------------------------
OrbExtractor::OrbExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("ORB needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
  // One pyramid level (fixed scale). patchSize = patch_size makes the 256 tests span the whole patch (OpenCV
  // then uses its own fixed-seed pattern instead of the learned 31x31 one, which would only cover the middle
  // of a 64 px patch). A provided keypoint keeps its angle: 0, so ORB stays upright.
  orb_ = cv::ORB::create(1, 1.2f, 1, patch_size / 2 + 1, 0, 2, cv::ORB::HARRIS_SCORE, patch_size);
}

void OrbExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  const int margin = marginFor(patch_size_);
  const cv::Mat image = paddedEightBit(patch, name(), patch_size_, margin);
  const cv::Mat d = computeOne(*orb_, image, centreKey(patch_size_, margin, float(patch_size_)), name(), patch_size_);
  if (d.cols * 8 != length())
    throw Error("ORB returned " + std::to_string(d.cols * 8) + " bits; expected 256");
  descriptors::packBytes(d.ptr<uint8_t>(), d.cols, words, wordsForBits(length()));
}

// ----------------------------------------------------------------------------------------------------------
BriskExtractor::BriskExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("BRISK needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
  // BRISK's own sampling pattern (60 points: 1, 10, 14, 15 and 20 on concentric rings; short pairs closer than
  // 5.85 / 9.18 of the outer radius), scaled so that the outer ring plus its smoothing (1.3 r sin(pi / 20))
  // reaches the patch border.
  const float unit = 0.85f;
  const std::vector<float> shape = {0.0f, 2.9f * unit, 4.9f * unit, 7.4f * unit, 10.8f * unit};
  const float sin_pi_20 = 0.156434465f;  // sin(pi / 20) as a literal: no libm rounding in the pattern
  const float outer_extent = shape.back() * (1.0f + 1.3f * sin_pi_20);
  const float k = 0.5f * patch_size / outer_extent;
  std::vector<float> radii;
  for (float r : shape)
    radii.push_back(k * r);
  // OpenCV 4 always estimates an orientation from the "long" pairs, even for given keypoints (measured: with
  // the default pairs a half-turned patch gets angles 295 / 123 degrees and differs by only 40 of 512 bits).
  // With dMin beyond any distance in the pattern there are no long pairs, the estimated gradient is (0, 0),
  // atan2 gives 0 and the descriptor is upright, as the paper's global description wants (267 bits apart).
  const float no_long_pairs = 1e6f;
  brisk_ = cv::BRISK::create(radii, std::vector<int>{1, 10, 14, 15, 20}, 5.85f * k, no_long_pairs);
  if (brisk_->descriptorSize() * 8 != length())
    throw Error("BRISK pattern for patch_size " + std::to_string(patch_size) + " gives " +
                std::to_string(brisk_->descriptorSize() * 8) + " bits; expected 512");
}

void BriskExtractor::describeBinary(const Patch& patch, uint64_t* words) const
{
  const int margin = marginFor(patch_size_);
  const cv::Mat image = paddedEightBit(patch, name(), patch_size_, margin);
  // Size 1 selects BRISK's finest scale, the one its pattern was scaled for above.
  const cv::Mat d = computeOne(*brisk_, image, centreKey(patch_size_, margin, 1.0f), name(), patch_size_);
  descriptors::packBytes(d.ptr<uint8_t>(), d.cols, words, wordsForBits(length()));
}

// ----------------------------------------------------------------------------------------------------------
SiftExtractor::SiftExtractor(int patch_size) : patch_size_(patch_size)
{
  if (patch_size < minPatchSize())
    throw Error("SIFT needs patch_size >= " + std::to_string(minPatchSize()) + ", got " + std::to_string(patch_size));
  // One layer per octave: only the base layer (sigma 1.6) is used for a keypoint of octave 0, layer 0, and
  // fewer layers make OpenCV build less of a pyramid that would go unused.
  sift_ = cv::SIFT::create(0, 1);
}

void SiftExtractor::describeFloat(const Patch& patch, float* values) const
{
  const int margin = siftMarginFor(patch_size_);
  const cv::Mat image = paddedEightBit(patch, name(), patch_size_, margin);
  // SIFT's 4x4 histograms are 3 * size / 2 pixels wide each: size = patch_size / 6 makes them tile the patch.
  const cv::Mat d = computeOne(*sift_, image, centreKey(patch_size_, margin, patch_size_ / 6.0f), name(), patch_size_);
  if (d.cols != length() || d.type() != CV_32F)
    throw Error("SIFT returned " + std::to_string(d.cols) + " values; expected 128 floats");
  std::memcpy(values, d.ptr<float>(), sizeof(float) * length());
}

}  // namespace openable
