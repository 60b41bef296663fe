#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

namespace openable
{
/// A bounded picture of the distance matrix of a stream, kept up to date one row per frame.
///
/// The full matrix (query frames down, reference frames across) grows as N x N and cannot be kept; this
/// view keeps at most `size` x `size` cells instead, each cell the minimum of the distances it covers
/// (min-pooling), so that a loop (a low distance) stays visible however far it is downsampled.
///
/// - Mode kWholeHistory: rows cover every query frame since clear(), columns every reference frame; when
///   either axis outgrows `size` cells, pairs of rows (or columns) are pooled into one and the scale
///   (frames per cell) of that axis doubles. Rows and columns have their own scale, so a short query stream
///   against a long reference map (localisation) is not squeezed.
/// - Mode kRollingWindow: one row per query frame for the last `size` query frames (older rows scroll
///   out); columns as in kWholeHistory.
///
/// Cost: addRow() is O(row length) plus, once per doubling of an axis, O(size^2) for the pooling, i.e.
/// O(N) amortised per frame; render() is O(size^2 + loops), independent of the history length.
///
/// Cell values: a distance in [0, 1]; kExcluded where the frames exist but were not compared (exclusion
/// window, the frame itself); NaN where nothing is known (reference frames that did not exist yet).
class DistanceMatrixView
{
public:
  enum class Mode
  {
    kWholeHistory,
    kRollingWindow
  };

  /// Marks cells whose frames exist but were never compared. Larger than every distance, so min-pooling
  /// keeps a real distance over it, and it over unknown (NaN) cells.
  static constexpr float kExcluded = 2.0f;

  struct RenderOptions
  {
    int color_map = 7;       ///< OpenABLE colour map 0..11 (render.h)
    bool stretch = true;     ///< map [min, max] of the shown distances to the full colour map (display only)
    double threshold = -1;   ///< >= 0: paper Eq. 9 view, cells with distance <= threshold white, others black
    bool mark_loops = true;  ///< draw the accepted loops added with addLoop()
  };

  /// size: cells per axis, at least 2 (the rendered image is size x size pixels at most). Throws Error.
  explicit DistanceMatrixView(int size = 512, Mode mode = Mode::kWholeHistory);

  int size() const
  {
    return size_;
  }
  Mode mode() const
  {
    return mode_;
  }
  /// Query frames per row and reference frames per column.
  uint64_t rowScale() const
  {
    return row_scale_;
  }
  uint64_t columnScale() const
  {
    return column_scale_;
  }
  /// Rows and columns currently holding data.
  int rows() const;
  int columns() const
  {
    return columns_used_;
  }
  /// Query rows added since clear().
  uint64_t queries() const
  {
    return queries_;
  }

  /// Changes the cell budget, keeping what is shown (pooled further when it no longer fits). Throws Error.
  void setSize(int size);
  /// Changes the mode; starts a new picture.
  void setMode(Mode mode);
  /// Forgets everything (new history, new map).
  void clear();

  /// One query frame's row: row[i] is the normalised distance to reference frame `first_reference_id + i`
  /// (NaN where no comparison was made). Query frames are counted in the order of the calls. Reference ids
  /// before the first one ever given (frames evicted before the view started) are ignored.
  void addRow(uint64_t first_reference_id, const std::vector<float>& row);
  /// Marks an accepted loop between a row added `rows_ago` rows before the last one (0: the last) and
  /// reference frame `match_id` (a confirmed loop closure arrives a few rows late). Only the last max_loops
  /// loops are kept (10000 by default), so render() stays bounded.
  void addLoop(uint64_t match_id, uint64_t rows_ago = 0);
  void setMaxLoops(size_t max_loops);
  size_t loops() const
  {
    return loops_.size();
  }

  /// Cell values as CV_32F, rows() x columns(), oldest row first.
  cv::Mat cells() const;
  /// The picture as 8-bit BGR, always size() x size() pixels (a steady shape for viewers): the cells scaled
  /// (nearest neighbour) until the longer side fills it, the rest black.
  /// Distances through the colour map, excluded cells dark blue-grey, unknown cells black, loops as
  /// white-and-black rings. Empty before the first row. Throws Error for a bad colour map.
  cv::Mat render(const RenderOptions& options) const;

private:
  /// Row of the cell matrix that holds query row `query_index` (since clear()).
  int storageRow(uint64_t query_index) const;
  void poolRows();
  void poolColumns();
  void combine(float& cell, float value) const;

  int size_;
  Mode mode_;
  cv::Mat cells_;  ///< size_ x size_ CV_32F; used part: rows() x columns_used_
  uint64_t row_scale_ = 1;
  uint64_t column_scale_ = 1;
  int columns_used_ = 0;
  uint64_t queries_ = 0;
  bool has_first_reference_ = false;
  uint64_t first_reference_id_ = 0;                  ///< reference id of column 0
  std::deque<std::pair<uint64_t, uint64_t>> loops_;  ///< (query index, reference id)
  size_t max_loops_ = 10000;
};

}  // namespace openable
