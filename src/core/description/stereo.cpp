#include "openable/description/stereo.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"
#include "openable/description/preprocessor.h"

namespace openable
{
namespace
{
std::string describe(const cv::Mat& m)
{
  if (m.empty())
    return "empty";
  static const char* depths[] = {"8U", "8S", "16U", "16S", "32S", "32F", "64F", "16F"};
  return std::to_string(m.cols) + "x" + std::to_string(m.rows) + " " + depths[m.depth()] + "C" +
         std::to_string(m.channels());
}

cv::Mat toGrey(const cv::Mat& image)
{
  if (image.channels() == 1)
    return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

constexpr float kInvalid = std::numeric_limits<float>::quiet_NaN();
}  // namespace

void checkStereoPair(const cv::Mat& left, const cv::Mat& right)
{
  for (const cv::Mat* image : {&left, &right})
  {
    const char* what = image == &left ? "left image" : "right image";
    if (image->empty())
      throw Error(std::string("stereo pair: the ") + what + " is empty; expected an 8-bit grey, BGR or BGRA image");
    if (image->depth() != CV_8U || (image->channels() != 1 && image->channels() != 3 && image->channels() != 4))
      throw Error(std::string("stereo pair: the ") + what + " is " + describe(*image) +
                  "; expected 8-bit grey, BGR or BGRA");
  }
  if (left.size() != right.size() || left.type() != right.type())
    throw Error("stereo pair: left image is " + describe(left) + " but right image is " + describe(right) +
                "; expected a rectified pair of the same size and type");
}

int scaledNumDisparities(const Config& config, int width)
{
  const double scaled = config.stereo_num_disparities * double(width) / 640.0;
  return std::max(16, static_cast<int>(std::lround(scaled / 16.0)) * 16);
}

int stereoWorkWidth(const Config& config, int input_width)
{
  const int described_width = Preprocessor(config).cellsAcross() * config.patch_size;
  return std::min(input_width, std::max(kMinStereoWorkWidth, kStereoPixelsPerPatchPixel * described_width));
}

cv::Mat disparityFromPair(const cv::Mat& left, const cv::Mat& right, const Config& config)
{
  checkStereoPair(left, right);
  if (config.stereo_block_size < 1 || config.stereo_block_size % 2 == 0)
    throw Error("stereo_block_size " + std::to_string(config.stereo_block_size) + " is not allowed; expected odd");
  const int width = stereoWorkWidth(config, left.cols);
  const int height = std::max(1, static_cast<int>(std::lround(double(left.rows) * width / left.cols)));
  const int block = config.stereo_block_size;
  const int range = scaledNumDisparities(config, width);
  if (range >= width)
    throw Error("stereo pair of " + describe(left) + " is too narrow for a disparity range of " +
                std::to_string(range) + " px; lower stereo_num_disparities");
  cv::Mat left_work = toGrey(left), right_work = toGrey(right);
  if (width != left.cols)
  {
    cv::resize(left_work, left_work, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    cv::resize(right_work, right_work, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  auto sgbm = cv::StereoSGBM::create(0, range, block, 8 * block * block, 32 * block * block, 1, 0, 10, 100, 2,
                                     cv::StereoSGBM::MODE_SGBM);
  cv::Mat fixed;
  sgbm->compute(left_work, right_work, fixed);
  cv::Mat disparity = disparityFromImage(fixed);
  if (width == left.cols)
    return disparity;
  // Back to the input's size and pixels. Nearest neighbour keeps NaN (invalid) pixels NaN instead of
  // blending them into their neighbours.
  cv::Mat full;
  cv::resize(disparity, full, left.size(), 0, 0, cv::INTER_NEAREST);
  full *= double(left.cols) / width;
  return full;
}

cv::Mat disparityFromImage(const cv::Mat& disparity)
{
  if (disparity.empty())
    throw Error(
        "disparity image is empty; expected one channel CV_32F (pixels), CV_16S (pixels * 16) or CV_16U "
        "(pixels * 256)");
  if (disparity.channels() != 1 ||
      (disparity.depth() != CV_32F && disparity.depth() != CV_16S && disparity.depth() != CV_16U))
    throw Error("disparity image is " + describe(disparity) +
                "; expected one channel CV_32F (pixels), CV_16S (OpenCV fixed point, pixels * 16) or CV_16U "
                "(KITTI PNG, pixels * 256)");
  cv::Mat out(disparity.size(), CV_32F);
  for (int y = 0; y < disparity.rows; ++y)
  {
    float* o = out.ptr<float>(y);
    switch (disparity.depth())
    {
      case CV_32F:
      {
        const float* in = disparity.ptr<float>(y);
        for (int x = 0; x < disparity.cols; ++x)
          o[x] = std::isfinite(in[x]) && in[x] > 0.0f ? in[x] : kInvalid;
        break;
      }
      case CV_16S:
      {
        const int16_t* in = disparity.ptr<int16_t>(y);
        for (int x = 0; x < disparity.cols; ++x)
          o[x] = in[x] > 0 ? in[x] / 16.0f : kInvalid;
        break;
      }
      default:
      {
        const uint16_t* in = disparity.ptr<uint16_t>(y);
        for (int x = 0; x < disparity.cols; ++x)
          o[x] = in[x] > 0 ? in[x] / 256.0f : kInvalid;
        break;
      }
    }
  }
  return out;
}

}  // namespace openable
