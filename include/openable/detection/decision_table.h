#pragma once

#include <string>
#include <vector>

namespace openable
{
/// What the loop-closure detector decided for one frame: a row of openable_offline's decisions.csv (one per
/// frame) or loop_closures.csv (one per published loop closure).
struct DecisionRow
{
  /// 0-based frame index of the stream (the query row of distance_matrix.npy).
  int query = -1;
  /// 0-based frame index of the best match; -1 when the frame had no candidate.
  int match = -1;
  /// NaN when the frame had no candidate.
  double distance = 0.0;
  /// Higher = surer; NaN when the frame had no candidate.
  double score = 0.0;
  /// The word of a FrameStatus (loop_decision.h), e.g. "published", "not_unique".
  std::string status;
  /// The `accepted` column of decisions.csv (false in loop_closures.csv, which has none).
  bool accepted = false;
  /// 1-based line of the file, for messages.
  int line = 0;

  bool published() const
  {
    return status == "published";
  }
};

/// The rows of one file, and whether it is a per-frame decisions file (it has an `accepted` column).
/// Read by loadDecisionTable (loop_csv.h, where both files' format lives).
struct DecisionTable
{
  std::string path;
  std::vector<DecisionRow> rows;
  bool per_frame = false;
};

}  // namespace openable
