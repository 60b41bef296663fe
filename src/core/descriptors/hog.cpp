#include <cstring>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "openable/descriptor_implementations.h"
#include "openable/error.h"
#include "patch_input.h"

namespace openable
{
HogExtractor::HogExtractor(int patch_size) : patch_size_(patch_size), window_(patch_size / kCells * kCells)
{
  if (patch_size < minPatchSize())
    throw Error("HOG needs patch_size >= " + std::to_string(minPatchSize()) + " (4x4 cells of 2 pixels), got " +
                std::to_string(patch_size));
}

void HogExtractor::describeFloat(const Patch& patch, float* values) const
{
  descriptors::checkIntensityPatch(name(), patch.intensity, patch_size_);
  cv::Mat image = descriptors::toEightBit(patch.intensity);
  if (window_ != patch_size_)
    cv::resize(image, image, cv::Size(window_, window_), 0, 0, cv::INTER_AREA);
  // The patch is the detection window: 4x4 cells, Dalal and Triggs' 2x2-cell blocks with a one-cell stride,
  // 9 unsigned bins, L2-Hys block normalisation (OpenCV's defaults for the rest).
  const int cell = window_ / kCells;
  cv::HOGDescriptor hog(cv::Size(window_, window_), cv::Size(2 * cell, 2 * cell), cv::Size(cell, cell),
                        cv::Size(cell, cell), kBins);
  std::vector<float> out;
  hog.compute(image, out);
  if (static_cast<int>(out.size()) != length())
    throw Error("HOG returned " + std::to_string(out.size()) + " values for a " + std::to_string(window_) +
                " px window; expected " + std::to_string(length()));
  std::memcpy(values, out.data(), sizeof(float) * out.size());
}

}  // namespace openable
