#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "openable/config.h"
#include "openable/descriptors/descriptor_extractor.h"

namespace openable
{
/// Paper Eq. 6 on a BGR (or BGRA) 8-bit image: I = log G - alpha log B - (1 - alpha) log R, as CV_32F.
/// Zero-valued channels are treated as 1 (log 0 is undefined; 1 is the smallest positive 8-bit value),
/// so a black pixel gives 0 and every other pixel gives exactly Eq. 6.
cv::Mat illuminationInvariant(const cv::Mat& bgr, double alpha);

/// Patch normalisation (as in SeqSLAM): every `block` x `block` block of a one-channel image is shifted and
/// scaled to zero mean and unit standard deviation, so that local contrast, not absolute brightness, is
/// described. Flat blocks become 0. block <= 0 returns the image unchanged.
cv::Mat normalizeBlocks(const cv::Mat& image, int block);

/// What Preprocessor reads of a Config (the keys of the same names; camera_type and description_type parsed).
struct PreprocessOptions
{
  CameraType camera;
  DescriptionType description;
  int grid_x;
  int grid_y;
  int panoramas;
  int patch_size;
  int patch_normalization;
  bool illumination_invariance;
  double alpha;
  double lateral_shift = 0.0;  ///< Config::lateral_shift: the views are crops of 1 - 2 x this of the width
  /// The descriptor's smallest patch (descriptor_registry.h): a small image's patch is never below it.
  int min_patch_size = 1;

  /// Throws Error for a camera_type or description_type that is not one of the words.
  static PreprocessOptions from(const Config& config);
  /// The side of the patches of an image of `image` pixels: patch_size, unless each cell of the image is smaller
  /// than that along both axes; then the cell's longer side (at least min_patch_size). See Preprocessor.
  int patchSide(cv::Size image) const;
  /// Cells across one image (grid columns, times the sub-panoramas) and down it.
  int cellsAcross() const;
  int cellsDown() const;
};

/// Turns a camera image into the patches to describe.
///
/// Input: 8-bit grey, BGR or BGRA, any size. The image is first reduced to one channel (grey, or Eq. 6
/// when illumination_invariance is on, which needs colour input), then downsampled with area
/// interpolation so that every cell becomes a patch_size x patch_size patch: global description gives one
/// patch; grid description splits the image into grid_x x grid_y cells; panoramic images are split into
/// `panoramas` vertical sub-panoramas (each of them split into the grid). Cells are returned row by row,
/// sub-panorama by sub-panorama (sub-panorama-major). Patches are CV_32F.
///
/// A cell smaller than patch_size along both axes is not enlarged to it: its patch is as large as its longer
/// side (PreprocessOptions::patchSide), so that a small image gives as much detail as it has and no more.
/// Enlarged by area interpolation, each pixel becomes a block, and HOG describes the blocks' edges: Nordland's
/// 64x32 frames at patch 128 (config/gardens_point.yaml) published 795 loops, 31 of them wrong (recall 0.424),
/// against 1,416 and 8 (0.782) at the frames' own 64 (doc/results.md). A cell enlarged along one axis only (64x32
/// at patch 64, every configuration's Nordland figures) is described as before.
class Preprocessor
{
public:
  explicit Preprocessor(const PreprocessOptions& options);
  /// Shorthand: Preprocessor(PreprocessOptions::from(config)).
  explicit Preprocessor(const Config& config);

  const PreprocessOptions& options() const
  {
    return options_;
  }

  /// Cells across and down the whole image (panoramas * grid_x, grid_y).
  int cellsAcross() const;
  int cellsDown() const;
  int cellCount() const
  {
    return cellsAcross() * cellsDown();
  }

  /// One-channel CV_32F image (grey 0..255, or Eq. 6). Throws Error on empty, wrong depth or channel count,
  /// grey input with invariance on, or an image smaller than the cell layout.
  cv::Mat intensity(const cv::Mat& image) const;

  /// Where an image is seen from (PreprocessOptions::lateral_shift): its centre, what a place stores, or the crop
  /// of the same width at its left or right edge, a query's shifted views.
  enum class View
  {
    Centre,
    Left,
    Right
  };
  /// The part of an image of `image` pixels that `view` describes: with lateral_shift > 0 on a mono image, a crop of
  /// 1 - 2 x lateral_shift of its width at the centre or at an edge, unless the patches would enlarge it (a small
  /// image keeps its whole frame); otherwise the whole image.
  cv::Rect viewOf(cv::Size image, View view) const;
  /// Whether an image of `image` pixels has shifted views (viewOf() differs between them).
  bool hasShiftedViews(cv::Size image) const;
  /// The patches of one image, in the order described above, of viewOf()'s part of it, each cell at the whole
  /// image's patch side. Throws Error as intensity().
  std::vector<Patch> patches(const cv::Mat& image, View view = View::Centre) const;

  /// The patches of one frame of a multi-camera ring (one image per sub-panorama, in ring order).
  std::vector<Patch> patchesFromCameras(const std::vector<cv::Mat>& images) const;

  /// Stereo: patches of the left image with the disparity (CV_32F pixels of the full-size image,
  /// invalid <= 0 or non-finite) attached, scaled to the patch.
  std::vector<Patch> patchesWithDisparity(const cv::Mat& left, const cv::Mat& disparity) const;

  /// Throws Error naming what is wrong when `image` cannot be used as input.
  void checkInput(const cv::Mat& image, const char* what = "image") const;

private:
  /// patches() of the whole of `image` (a view's crop), each cell downsampled to `side` x `side`.
  std::vector<Patch> wholePatches(const cv::Mat& image, int side) const;
  std::vector<Patch> split(const cv::Mat& intensity, const cv::Mat& disparity, int across, int side) const;
  PreprocessOptions options_;
};

}  // namespace openable
