#include "openable/description/preprocessor.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "openable/description/area_downsample.h"
#include "openable/descriptors/descriptor_registry.h"
#include "openable/error.h"

namespace openable
{
namespace
{
std::string describeMat(const cv::Mat& m)
{
  static const char* depths[] = {"8U", "8S", "16U", "16S", "32S", "32F", "64F", "16F"};
  return std::to_string(m.cols) + "x" + std::to_string(m.rows) + " " + depths[m.depth()] + "C" +
         std::to_string(m.channels());
}

/// Log with zero treated as 1, so that black pixels are defined (see header).
inline float safeLog(float v)
{
  return std::log(v < 1.0f ? 1.0f : v);
}

/// One-channel CV_32F from an 8-bit grey/BGR/BGRA image: grey, or Eq. 6.
cv::Mat toOneChannel(const cv::Mat& image, bool invariant, double alpha)
{
  if (invariant)
    return illuminationInvariant(image, alpha);
  cv::Mat grey;
  if (image.channels() == 1)
    grey = image;
  else
    cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  cv::Mat out;
  grey.convertTo(out, CV_32F);
  return out;
}
}  // namespace

cv::Mat normalizeBlocks(const cv::Mat& image, int block)
{
  if (block <= 0)
    return image;
  cv::Mat out(image.size(), CV_32F);
  for (int y0 = 0; y0 < image.rows; y0 += block)
    for (int x0 = 0; x0 < image.cols; x0 += block)
    {
      const cv::Rect r(x0, y0, std::min(block, image.cols - x0), std::min(block, image.rows - y0));
      cv::Scalar mean, stddev;
      cv::meanStdDev(image(r), mean, stddev);
      // A flat block (sky, a wall in the dark) stays flat instead of amplifying noise to full contrast.
      const double scale = stddev[0] > 1e-3 ? 1.0 / stddev[0] : 0.0;
      cv::Mat dst = out(r);
      image(r).convertTo(dst, CV_32F, scale, -mean[0] * scale);
    }
  return out;
}

cv::Mat illuminationInvariant(const cv::Mat& bgr, double alpha)
{
  if (bgr.empty() || bgr.depth() != CV_8U || (bgr.channels() != 3 && bgr.channels() != 4))
    throw Error("illumination invariance needs an 8-bit colour image (BGR or BGRA), got " +
                (bgr.empty() ? std::string("an empty image") : describeMat(bgr)) +
                "; turn illumination_invariance off for grey cameras");
  const int channels = bgr.channels();
  const float a = static_cast<float>(alpha);
  cv::Mat out(bgr.size(), CV_32F);
  for (int y = 0; y < bgr.rows; ++y)
  {
    const uint8_t* in = bgr.ptr<uint8_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < bgr.cols; ++x, in += channels)
      o[x] = safeLog(in[1]) - a * safeLog(in[0]) - (1.0f - a) * safeLog(in[2]);  // Eq. 6: B G R order in memory
  }
  return out;
}

PreprocessOptions PreprocessOptions::from(const Config& config)
{
  PreprocessOptions o;
  o.camera = config.camera();
  o.description = config.description();
  o.grid_x = config.grid_x;
  o.grid_y = config.grid_y;
  o.panoramas = config.panoramas;
  o.patch_size = config.patch_size;
  o.patch_normalization = config.patch_normalization;
  o.illumination_invariance = config.illumination_invariance;
  o.alpha = config.alpha;
  o.lateral_shift = config.lateral_shift;
  if (const DescriptorInfo* row = findDescriptor(config.descriptor))
    o.min_patch_size = row->min_patch_size;
  return o;
}

int PreprocessOptions::patchSide(cv::Size image) const
{
  const int longer = std::max(image.width / std::max(1, cellsAcross()), image.height / std::max(1, cellsDown()));
  return longer >= patch_size ? patch_size : std::min(patch_size, std::max(longer, min_patch_size));
}

int PreprocessOptions::cellsAcross() const
{
  const int grid = description == DescriptionType::Grid ? grid_x : 1;
  return camera == CameraType::Panoramic ? panoramas * grid : grid;
}

int PreprocessOptions::cellsDown() const
{
  return description == DescriptionType::Grid ? grid_y : 1;
}

Preprocessor::Preprocessor(const PreprocessOptions& options) : options_(options) {}

Preprocessor::Preprocessor(const Config& config) : Preprocessor(PreprocessOptions::from(config)) {}

int Preprocessor::cellsAcross() const
{
  return options_.cellsAcross();
}

int Preprocessor::cellsDown() const
{
  return options_.cellsDown();
}

void Preprocessor::checkInput(const cv::Mat& image, const char* what) const
{
  if (image.empty())
    throw Error(std::string(what) + " is empty; expected an 8-bit grey, BGR or BGRA image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    throw Error(std::string(what) + " is " + describeMat(image) +
                "; expected 8-bit grey (mono8), BGR (bgr8) or BGRA (bgra8)");
  if (options_.illumination_invariance && image.channels() == 1)
    throw Error(std::string(what) +
                " is grey but illumination_invariance is on; Eq. 6 needs colour (BGR) input: send colour images or "
                "set illumination_invariance: false");
}

cv::Mat Preprocessor::intensity(const cv::Mat& image) const
{
  checkInput(image);
  return toOneChannel(image, options_.illumination_invariance, options_.alpha);
}

cv::Rect Preprocessor::viewOf(cv::Size image, View view) const
{
  // A crop of 1 - 2 x lateral_shift of the width: at the centre, or at either edge. A camera on the other side of a
  // path sees the scene shifted sideways by a tenth of the image or more (Gardens Point day_left against
  // night_right); the crops of the same width keep one scale, so a shifted view is compared cell for cell.
  const int margin = static_cast<int>(std::lround(options_.lateral_shift * image.width));
  const int width = image.width - 2 * margin;
  // Never a crop the patches would enlarge: Nordland's 64x32 frames cropped to 52x32 and stretched to a 64-pixel
  // patch (or described at 52, another HOG cell) published wrong loops where the whole frame published none.
  const int patch_columns = cellsAcross() * options_.patchSide(image);
  if (options_.lateral_shift <= 0.0 || options_.camera == CameraType::Panoramic || margin < 1 || width < patch_columns)
    return cv::Rect(0, 0, image.width, image.height);
  const int left = view == View::Left ? 0 : (view == View::Right ? 2 * margin : margin);
  return cv::Rect(left, 0, width, image.height);
}

bool Preprocessor::hasShiftedViews(cv::Size image) const
{
  return viewOf(image, View::Left) != viewOf(image, View::Right);
}

std::vector<Patch> Preprocessor::patches(const cv::Mat& image, View view) const
{
  checkInput(image);
  return wholePatches(image(viewOf(image.size(), view)), options_.patchSide(image.size()));
}

std::vector<Patch> Preprocessor::wholePatches(const cv::Mat& image, int p) const
{
  const int across = cellsAcross();
  const int down = cellsDown();
  if (image.cols < across || image.rows < down)
    throw Error("image of " + describeMat(image) + " is too small for " + std::to_string(across) + "x" +
                std::to_string(down) + " cells (panoramas x grid); expected at least one pixel per cell");
  // Area averaging of the pixels under each patch pixel, in two steps (area_downsample.h): the exact integer
  // decimation of the 8-bit image first, one pass over its bytes, converting to grey as it goes; then the
  // per-pixel work (logarithms) on the few pixels left, and the small area step to the patch size on one
  // channel.
  const cv::Size target(across * p, down * p);
  cv::Mat small = options_.illumination_invariance
                      ? illuminationInvariant(decimateTowards(image, target), options_.alpha)
                      : toOneChannel(decimateGreyTowards(image, target), false, options_.alpha);
  if (small.size() != target)
    small = areaResize(small, target);
  return split(normalizeBlocks(small, options_.patch_normalization), cv::Mat(), across, p);
}

std::vector<Patch> Preprocessor::patchesFromCameras(const std::vector<cv::Mat>& images) const
{
  if (options_.camera != CameraType::Panoramic)
    throw Error("a multi-camera frame needs camera_type panoramic");
  if (static_cast<int>(images.size()) != options_.panoramas)
    throw Error("a multi-camera frame has " + std::to_string(images.size()) + " images; expected panoramas = " +
                std::to_string(options_.panoramas) + " (one per camera, in ring order)");
  std::vector<Patch> out;
  PreprocessOptions single = options_;
  single.camera = CameraType::Mono;
  single.lateral_shift = 0.0;  // a ring is matched at every rotation: each camera's whole image
  const Preprocessor camera(single);
  for (size_t i = 0; i < images.size(); ++i)
  {
    const std::string what = "camera " + std::to_string(i) + " image";
    checkInput(images[i], what.c_str());
    auto cells = camera.patches(images[i]);
    out.insert(out.end(), cells.begin(), cells.end());
  }
  return out;
}

std::vector<Patch> Preprocessor::patchesWithDisparity(const cv::Mat& left, const cv::Mat& disparity) const
{
  checkInput(left, "left image");
  if (disparity.type() != CV_32FC1)
    throw Error("disparity is " + (disparity.empty() ? std::string("empty") : describeMat(disparity)) +
                "; expected CV_32F pixels (invalid as NaN or <= 0)");
  if (disparity.size() != left.size())
    throw Error("disparity of " + describeMat(disparity) + " does not match the left image " + describeMat(left));
  const int across = cellsAcross();
  const int down = cellsDown();
  const int p = options_.patchSide(left.size());
  const cv::Size target(across * p, down * p);

  const cv::Mat small = areaDownsample(left, target);
  const cv::Mat intensity = toOneChannel(small, options_.illumination_invariance, options_.alpha);

  // Average only valid disparities: invalid ones (NaN, <= 0) must not leak in as huge or zero values.
  cv::Mat valid = (disparity > 0.0f);  // NaN compares false
  cv::Mat values = cv::Mat::zeros(disparity.size(), CV_32F);
  disparity.copyTo(values, valid);
  cv::Mat valid_f;
  valid.convertTo(valid_f, CV_32F, 1.0 / 255.0);
  cv::Mat sum_small, weight_small;
  cv::resize(values, sum_small, target, 0, 0, cv::INTER_AREA);
  cv::resize(valid_f, weight_small, target, 0, 0, cv::INTER_AREA);
  // Disparities are in full-image pixels; express them in patch pixels so the descriptor does not depend on
  // the camera resolution.
  const float scale = static_cast<float>(target.width) / static_cast<float>(left.cols);
  cv::Mat disp_small(target, CV_32F, cv::Scalar(0));
  cv::Mat mask_small(target, CV_8U, cv::Scalar(0));
  for (int y = 0; y < target.height; ++y)
    for (int x = 0; x < target.width; ++x)
    {
      const float w = weight_small.at<float>(y, x);
      if (w >= 0.5f)  // most of the pixels under this patch pixel had a disparity
      {
        disp_small.at<float>(y, x) = scale * sum_small.at<float>(y, x) / w;
        mask_small.at<uint8_t>(y, x) = 255;
      }
    }
  std::vector<Patch> out = split(intensity, disp_small, across, p);
  // Masks follow the same cell layout.
  const std::vector<Patch> masks = split(mask_small, cv::Mat(), across, p);
  for (size_t i = 0; i < out.size(); ++i)
    out[i].valid = masks[i].intensity;
  return out;
}

std::vector<Patch> Preprocessor::split(const cv::Mat& intensity, const cv::Mat& disparity, int across, int p) const
{
  const int down = cellsDown();
  const int grid_x = options_.description == DescriptionType::Grid ? options_.grid_x : 1;
  const int blocks = across / grid_x;
  std::vector<Patch> out;
  out.reserve(across * down);
  for (int b = 0; b < blocks; ++b)
    for (int gy = 0; gy < down; ++gy)
      for (int gx = 0; gx < grid_x; ++gx)
      {
        const cv::Rect cell((b * grid_x + gx) * p, gy * p, p, p);
        Patch patch;
        patch.intensity = intensity(cell).clone();
        if (!disparity.empty())
          patch.disparity = disparity(cell).clone();
        out.push_back(patch);
      }
  return out;
}

}  // namespace openable
