#pragma once

#include <string>
#include <vector>

#include "openable/evaluation/evaluation.h"

namespace openable
{
/// One detected loop closure: frame `query` was recognised as the place of frame `match`.
struct LoopPair
{
  int query = 0;
  int match = 0;
  /// Set by judgeLoops(): the ground truth has this loop.
  bool agrees = false;
};

/// Loop closures from a file, in file order. Two formats, told apart by the first line that is not blank
/// or a `#` comment:
/// - a CSV whose header starts with `query,match` (openable_offline's loop_closures.csv: further columns
///   such as the distance are ignored; its rows are read by readLoopCsvPair, loop_csv.h);
/// - `i j` lines (0-based frames; the published KITTI loop ground truth), `#` comments allowed.
/// Throws Error for a missing file, a malformed line (with its number) or a negative frame.
std::vector<LoopPair> loadLoopPairs(const std::string& path);

/// Sets `agrees` of every loop: the ground truth holds it in either direction (a pairs file lists a loop
/// once, from its later frame; a detector may report it from either end).
void judgeLoops(std::vector<LoopPair>& loops, const GroundTruth& truth);

}  // namespace openable
