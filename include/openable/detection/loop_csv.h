#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "openable/detection/decision_table.h"
#include "openable/detection/loop_decision.h"

namespace openable
{
/// The one home of openable_offline's two decision files, written and read here only:
/// - loop_closures.csv: one row per published loop closure,
///   `query,match,distance,score,status[,direction,shift],query_session,match_session`
///   (direction and shift with a panoramic camera, or a mono one with lateral_shift: Candidate::shift);
/// - decisions.csv: one row per frame, `query,match,distance,score,status,accepted,pace,inliers`
///   (distance, score and pace `nan` when the frame had no candidate, match -1; inliers -1 when geometric
///   verification did not run on the frame).
/// Numbers are written with 6 significant digits.

/// What the files say of one frame.
struct LoopCsvFrame
{
  long query = 0;               ///< the stream's frame number
  long match = -1;              ///< frame number of the best match; -1 when the frame had no candidate
  bool has_candidates = false;  ///< false: distance, score and pace are written as nan
  float distance = 0.0f;        ///< normalised distance of the best match
  float score = 0.0f;           ///< the decision score (LoopDecision::score)
  float pace = 1.0f;            ///< pace of the best match's sequence
  FrameStatus status = FrameStatus::TooEarly;
  int direction = 1;           ///< of the best match (files with the shift column only)
  int shift = 0;               ///< of the best match (Candidate::shift; files with the shift column only)
  uint32_t query_session = 0;  ///< session index of the query
  uint32_t match_session = 0;  ///< session index of the best match
  int inliers = -1;            ///< geometric verification's inliers for the best match; -1 when it did not run
};

/// Collects the rows of both files, frame after frame; the caller writes the texts where it wants them. A row's
/// status may change after it was added: a pending loop closure (confirm_frames) is published or dropped later.
class LoopCsvWriter
{
public:
  /// with_shift (a panoramic camera, or lateral_shift): loop_closures.csv gets the direction and shift columns.
  explicit LoopCsvWriter(bool with_shift);

  /// One frame: a row of decisions.csv, and of loop_closures.csv while it is published. Returns its row.
  size_t add(const LoopCsvFrame& frame);
  /// A later word on row `row` (Published once confirmed). Throws Error for a row that was never added.
  void setStatus(size_t row, FrameStatus status);
  /// Row `row`'s match: a loop closure confirmed later may have moved (placeInHindsight). Throws Error when there is no
  /// such row.
  void setMatch(size_t row, long match);
  /// The stream ended: every row still pending becomes unconfirmed (no frame after it could confirm it).
  void settlePending();
  const std::vector<LoopCsvFrame>& frames() const
  {
    return frames_;
  }

  /// The text of loop_closures.csv so far, header included.
  std::string loopClosures() const;
  /// The text of decisions.csv so far, header included.
  std::string decisions() const;

private:
  bool with_shift_;
  std::vector<LoopCsvFrame> frames_;
};

/// Reads loop_closures.csv (`query,match,distance,score,status`, maybe more columns such as `direction,shift`)
/// or decisions.csv (the same plus `accepted`). Columns are found by name in the header, so their order and
/// extra columns do not matter. Throws Error naming the file, and the line where one is at fault: missing
/// file, a missing column, a row with the wrong number of fields, a bad number, a status that is no
/// FrameStatus word, accepted not 0/1, a published row without a match, or a loop_closures.csv row
/// that is not published.
DecisionTable loadDecisionTable(const std::string& path);

/// True for the header line of a loop_closures.csv (it starts with `query,match`).
bool isLoopCsvHeader(const std::string& line);

/// The query and match of one loop_closures.csv row (further columns ignored): false unless its first two
/// fields are frame indices >= 0.
bool readLoopCsvPair(const std::string& line, int& query, int& match);

}  // namespace openable
