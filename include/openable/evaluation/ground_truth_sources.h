#pragma once

#include <string>

#include "openable/evaluation/evaluation.h"

namespace openable
{
/// One stream made of two traversals of the same route joined end to end (loop-closure mode): frame
/// `joined + i` is the place of frame i, so it truly matches frames within `tolerance` of i; frames before
/// `joined` have no loop at all (the first traversal sees each place once). Exact shape
/// num_frames x num_frames. Throws Error unless 0 < joined < num_frames and tolerance >= 0.
GroundTruth joinedGroundTruth(int num_frames, int joined, int tolerance = 0);

/// A ground-truth matrix, rows = query frames, columns = reference frames, any non-zero cell = same place:
/// an image (PNG or anything OpenCV reads; any non-zero channel counts) or a .npy (bool, integer or float).
/// Its shape must equal the distance matrix's (GroundTruth::checkFits says so when it does not). Throws
/// Error for an unreadable or empty file.
GroundTruth loadTruthMatrix(const std::string& path);

/// The same from a mask already in memory (any depth and channels; non-zero = same place); `origin` names
/// it in the description.
GroundTruth truthMatrixGroundTruth(const cv::Mat& mask, const std::string& origin);

}  // namespace openable
