// Ground truths that evaluation.cpp does not make: a stream of two joined traversals, a truth matrix.
#include "openable/evaluation/ground_truth_sources.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "openable/error.h"
#include "openable/io/npy.h"

namespace openable
{
GroundTruth joinedGroundTruth(int num_frames, int joined, int tolerance)
{
  // joined = 0 would make every frame its own loop, joined >= num_frames a stream without a second traversal.
  if (joined <= 0 || joined >= num_frames)
  {
    throw Error("joined ground truth: the second traversal must start at a frame in [1, " +
                std::to_string(num_frames - 1) + "] of the " + std::to_string(num_frames) + "-frame stream, got " +
                std::to_string(joined));
  }
  if (tolerance < 0)
  {
    throw Error("joined ground truth: tolerance must be >= 0 frames, got " + std::to_string(tolerance));
  }
  std::vector<std::vector<int>> anchors(num_frames);
  for (int q = joined; q < num_frames; ++q)
  {
    anchors[q].push_back(q - joined);
  }
  return GroundTruth(std::move(anchors), tolerance, num_frames, num_frames, true,
                     "joined stream, frame " + std::to_string(joined) +
                         " + i is frame i, |match - i| <= " + std::to_string(tolerance));
}

GroundTruth truthMatrixGroundTruth(const cv::Mat& mask, const std::string& origin)
{
  if (mask.empty() || mask.dims != 2)
  {
    throw Error("truth matrix (" + origin + "): empty or not 2-D");
  }
  // One channel that is non-zero wherever any channel is, so a coloured mark counts as well as a grey one.
  cv::Mat any = cv::Mat::zeros(mask.rows, mask.cols, CV_8U);
  std::vector<cv::Mat> channels;
  cv::split(mask, channels);
  for (const cv::Mat& channel : channels)
  {
    any |= (channel != 0);
  }
  std::vector<std::vector<int>> anchors(mask.rows);
  for (int q = 0; q < mask.rows; ++q)
  {
    const unsigned char* row = any.ptr<unsigned char>(q);
    for (int r = 0; r < mask.cols; ++r)
    {
      if (row[r] != 0)
      {
        anchors[q].push_back(r);
      }
    }
  }
  return GroundTruth(std::move(anchors), 0, mask.rows, mask.cols, true, "truth matrix " + origin);
}

GroundTruth loadTruthMatrix(const std::string& path)
{
  if (std::filesystem::path(path).extension() == ".npy")
  {
    return truthMatrixGroundTruth(readNpyNonZero(path), path);
  }
  if (!std::filesystem::is_regular_file(path))
  {
    throw Error("truth matrix: cannot open '" + path + "' (missing or not a file)");
  }
  // Unchanged: 16-bit values stay, so nothing non-zero is rounded away to 0.
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty())
  {
    throw Error("truth matrix: cannot read '" + path + "' as an image (PNG) or .npy");
  }
  if (image.channels() == 2 || image.channels() == 4)
  {
    // Alpha says how opaque a pixel is, not whether it is marked: an opaque black pixel is "not the same place".
    std::vector<cv::Mat> channels;
    cv::split(image, channels);
    channels.pop_back();
    cv::merge(channels, image);
  }
  return truthMatrixGroundTruth(image, path);
}

}  // namespace openable
