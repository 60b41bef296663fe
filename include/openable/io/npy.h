#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace openable
{
/// Writes a 2-D CV_32F matrix as a NumPy .npy file (version 1.0, '<f4', C order), atomically
/// (temporary file + rename). Throws Error.
void writeNpy(const std::string& path, const cv::Mat& matrix);

/// Reads a 2-D .npy file of little-endian float32 or float64 (C order) into a CV_32F matrix.
/// Throws Error naming what is wrong (missing, not .npy, unsupported dtype / order / rank, truncated).
cv::Mat readNpy(const std::string& path);

/// Reads a 2-D .npy of bool, integer (any width, little-endian) or float32/float64 (C order) as a CV_8U
/// mask: 255 where the cell is non-zero (NaN counts as non-zero, -0.0 as zero), 0 elsewhere. For masks such
/// as ground-truth matrices, which numpy saves as bool or int64. Throws Error like readNpy.
cv::Mat readNpyNonZero(const std::string& path);

}  // namespace openable
