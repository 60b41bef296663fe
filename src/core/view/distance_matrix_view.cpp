#include "openable/view/distance_matrix_view.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "openable/error.h"
#include "openable/view/render.h"

namespace openable
{
namespace
{
const float kUnknown = std::numeric_limits<float>::quiet_NaN();
// Colours of the picture (BGR). Excluded cells are a muted blue-grey that none of the 12 colour maps
// produces at its ends, unknown cells are black. Loops are a white ring inside a black one: one of the
// two stands out on every colour map (a single colour vanishes in the maps that contain it).
const cv::Vec3b kExcludedColor(90, 60, 50);
const cv::Vec3b kUnknownColor(0, 0, 0);
const cv::Scalar kLoopInnerColor(255, 255, 255);
const cv::Scalar kLoopOuterColor(0, 0, 0);

void checkSize(int size)
{
  if (size < 2)
  {
    throw Error("distance matrix view size: value '" + std::to_string(size) + "' is not allowed; expected >= 2 cells");
  }
}
}  // namespace

DistanceMatrixView::DistanceMatrixView(int size, Mode mode) : size_(size), mode_(mode)
{
  checkSize(size);
  clear();
}

int DistanceMatrixView::rows() const
{
  if (queries_ == 0)
  {
    return 0;
  }
  if (mode_ == Mode::kRollingWindow)
  {
    return int(std::min<uint64_t>(queries_, uint64_t(size_)));
  }
  return int((queries_ - 1) / row_scale_ + 1);
}

void DistanceMatrixView::clear()
{
  cells_.create(size_, size_, CV_32F);
  cells_.setTo(cv::Scalar(kUnknown));
  row_scale_ = 1;
  column_scale_ = 1;
  columns_used_ = 0;
  queries_ = 0;
  has_first_reference_ = false;
  first_reference_id_ = 0;
  loops_.clear();
}

void DistanceMatrixView::setMode(Mode mode)
{
  if (mode != mode_)
  {
    mode_ = mode;
    clear();
  }
}

void DistanceMatrixView::setMaxLoops(size_t max_loops)
{
  max_loops_ = max_loops;
  while (loops_.size() > max_loops_)
  {
    loops_.pop_front();
  }
}

void DistanceMatrixView::setSize(int size)
{
  checkSize(size);
  if (size == size_)
  {
    return;
  }
  if (mode_ == Mode::kRollingWindow)
  {
    // Rows are single frames in a ring: keep the newest that fit, columns pooled until they fit.
    cv::Mat ordered = cells();
    while (columns_used_ > size)
    {
      // Pool the ordered copy the same way poolColumns() pools the ring.
      const int pooled = (columns_used_ + 1) / 2;
      cv::Mat next(ordered.rows, pooled, CV_32F, cv::Scalar(kUnknown));
      for (int r = 0; r < ordered.rows; ++r)
      {
        for (int c = 0; c < columns_used_; ++c)
        {
          combine(next.at<float>(r, c / 2), ordered.at<float>(r, c));
        }
      }
      ordered = next;
      columns_used_ = pooled;
      column_scale_ *= 2;
    }
    const int keep = std::min(ordered.rows, size);
    size_ = size;
    cells_.create(size_, size_, CV_32F);
    cells_.setTo(cv::Scalar(kUnknown));
    // The kept rows go to the ring slots the next addRow() calls expect: query q lives in row q % size.
    for (int i = 0; i < keep; ++i)
    {
      const uint64_t query_index = queries_ - uint64_t(keep) + uint64_t(i);
      ordered.row(ordered.rows - keep + i)
          .colRange(0, columns_used_)
          .copyTo(cells_.row(int(query_index % uint64_t(size_))).colRange(0, columns_used_));
    }
    return;
  }
  // Whole history: pool inside the current storage until the used part fits the new size, then copy.
  while (rows() > size)
  {
    poolRows();
  }
  while (columns_used_ > size)
  {
    poolColumns();
  }
  cv::Mat next(size, size, CV_32F, cv::Scalar(kUnknown));
  const int used_rows = rows();
  if (used_rows > 0 && columns_used_ > 0)
  {
    cells_(cv::Rect(0, 0, columns_used_, used_rows)).copyTo(next(cv::Rect(0, 0, columns_used_, used_rows)));
  }
  cells_ = next;
  size_ = size;
}

void DistanceMatrixView::combine(float& cell, float value) const
{
  // Min-pooling with unknown (NaN) as the identity: a loop anywhere in a cell keeps the cell low.
  if (std::isnan(value))
  {
    return;
  }
  if (std::isnan(cell) || value < cell)
  {
    cell = value;
  }
}

void DistanceMatrixView::poolRows()
{
  const int used = rows();
  const int pooled = (used + 1) / 2;
  for (int r = 0; r < pooled; ++r)
  {
    float* out = cells_.ptr<float>(r);
    const float* a = cells_.ptr<float>(2 * r);
    // Row 2r is copied first: for r = 0 it is the output row itself, for r > 0 it is a row not yet read
    // (2r > r), so reading before writing is safe in place.
    std::vector<float> merged(a, a + size_);
    if (2 * r + 1 < used)
    {
      const float* b = cells_.ptr<float>(2 * r + 1);
      for (int c = 0; c < size_; ++c)
      {
        combine(merged[size_t(c)], b[c]);
      }
    }
    std::copy(merged.begin(), merged.end(), out);
  }
  for (int r = pooled; r < size_; ++r)
  {
    cells_.row(r).setTo(cv::Scalar(kUnknown));
  }
  row_scale_ *= 2;
}

void DistanceMatrixView::poolColumns()
{
  const int pooled = (columns_used_ + 1) / 2;
  for (int r = 0; r < size_; ++r)
  {
    float* row = cells_.ptr<float>(r);
    for (int c = 0; c < pooled; ++c)
    {
      // Column 2c >= c is read before column c is written.
      float value = row[2 * c];
      if (2 * c + 1 < columns_used_)
      {
        combine(value, row[2 * c + 1]);
      }
      row[c] = value;
    }
    std::fill(row + pooled, row + size_, kUnknown);
  }
  columns_used_ = pooled;
  column_scale_ *= 2;
}

int DistanceMatrixView::storageRow(uint64_t query_index) const
{
  if (mode_ == Mode::kRollingWindow)
  {
    return int(query_index % uint64_t(size_));
  }
  return int(query_index / row_scale_);
}

void DistanceMatrixView::addRow(uint64_t first_reference_id, const std::vector<float>& row)
{
  const uint64_t query_index = queries_;
  if (!has_first_reference_)
  {
    has_first_reference_ = true;
    first_reference_id_ = first_reference_id;
  }
  if (mode_ == Mode::kWholeHistory)
  {
    while (query_index / row_scale_ >= uint64_t(size_))
    {
      poolRows();
    }
  }
  else if (query_index >= uint64_t(size_))
  {
    // The ring slot still holds the row of query_index - size: it scrolls out now.
    cells_.row(storageRow(query_index)).setTo(cv::Scalar(kUnknown));
  }
  ++queries_;

  // Reference ids before column 0 (evicted before the view started) cannot be shown.
  size_t skip = 0;
  if (first_reference_id < first_reference_id_)
  {
    skip = size_t(std::min<uint64_t>(first_reference_id_ - first_reference_id, row.size()));
  }
  if (skip == row.size())
  {
    return;
  }
  const uint64_t last_id = first_reference_id + row.size() - 1;
  while ((last_id - first_reference_id_) / column_scale_ >= uint64_t(size_))
  {
    poolColumns();
  }
  columns_used_ = std::max(columns_used_, int((last_id - first_reference_id_) / column_scale_) + 1);

  float* cells = cells_.ptr<float>(storageRow(query_index));
  for (size_t i = skip; i < row.size(); ++i)
  {
    const uint64_t column = (first_reference_id + i - first_reference_id_) / column_scale_;
    // A frame that exists but was not compared is shown as excluded, not as unknown.
    combine(cells[column], std::isnan(row[i]) ? kExcluded : row[i]);
  }
}

void DistanceMatrixView::addLoop(uint64_t match_id, uint64_t rows_ago)
{
  if (queries_ <= rows_ago || max_loops_ == 0)
  {
    return;
  }
  loops_.emplace_back(queries_ - 1 - rows_ago, match_id);
  while (loops_.size() > max_loops_)
  {
    loops_.pop_front();
  }
}

cv::Mat DistanceMatrixView::cells() const
{
  const int used_rows = rows();
  if (used_rows == 0 || columns_used_ == 0)
  {
    return cv::Mat(used_rows, columns_used_, CV_32F);
  }
  if (mode_ == Mode::kWholeHistory || queries_ <= uint64_t(size_))
  {
    return cells_(cv::Rect(0, 0, columns_used_, used_rows)).clone();
  }
  // Rolling window that has wrapped: the oldest row is the slot the next query will overwrite.
  cv::Mat ordered(used_rows, columns_used_, CV_32F);
  const int oldest = int(queries_ % uint64_t(size_));
  for (int i = 0; i < used_rows; ++i)
  {
    cells_.row((oldest + i) % size_).colRange(0, columns_used_).copyTo(ordered.row(i));
  }
  return ordered;
}

cv::Mat DistanceMatrixView::render(const RenderOptions& options) const
{
  const cv::Mat values = cells();
  if (values.empty())
  {
    return cv::Mat();
  }
  cv::Mat shown(values.size(), CV_32F);
  float low = std::numeric_limits<float>::max();
  float high = std::numeric_limits<float>::lowest();
  for (int r = 0; r < values.rows; ++r)
  {
    for (int c = 0; c < values.cols; ++c)
    {
      const float v = values.at<float>(r, c);
      if (!std::isnan(v) && v <= 1.0f)
      {
        low = std::min(low, v);
        high = std::max(high, v);
      }
    }
  }
  const bool stretch = options.stretch && high > low;
  for (int r = 0; r < values.rows; ++r)
  {
    for (int c = 0; c < values.cols; ++c)
    {
      const float v = values.at<float>(r, c);
      if (std::isnan(v) || v > 1.0f)
      {
        shown.at<float>(r, c) = kUnknown;
      }
      else
      {
        shown.at<float>(r, c) = stretch ? (v - low) / (high - low) : v;
      }
    }
  }

  cv::Mat bgr;
  if (options.threshold >= 0)
  {
    // Eq. 9 applies to the distances themselves, not to the stretched display values.
    cv::Mat raw = values.clone();
    raw.setTo(cv::Scalar(kUnknown), values > 1.0f);
    cv::Mat binary = thresholdView(raw, options.threshold);
    cv::cvtColor(binary, bgr, cv::COLOR_GRAY2BGR);
  }
  else
  {
    bgr = colorize(shown, options.color_map, kUnknownColor);
  }
  for (int r = 0; r < values.rows; ++r)
  {
    for (int c = 0; c < values.cols; ++c)
    {
      const float v = values.at<float>(r, c);
      if (std::isnan(v))
      {
        bgr.at<cv::Vec3b>(r, c) = kUnknownColor;
      }
      else if (v > 1.0f)
      {
        bgr.at<cv::Vec3b>(r, c) = kExcludedColor;
      }
    }
  }

  // Always size_ x size_ pixels, so a viewer (rviz) never sees the image change shape as the history grows
  // or is pooled: the cells are scaled (nearest neighbour) until the longer side fills the image, and the
  // rest of the shorter side is unknown (black). A non-integer scale makes some cells a pixel wider than
  // others, which is the price of a steady size.
  const double scale = double(size_) / double(std::max(values.rows, values.cols));
  const cv::Size picture(std::max(1, std::min(size_, int(std::lround(values.cols * scale)))),
                         std::max(1, std::min(size_, int(std::lround(values.rows * scale)))));
  cv::Mat image(size_, size_, CV_8UC3, cv::Scalar(kUnknownColor));
  cv::resize(bgr, image(cv::Rect(cv::Point(0, 0), picture)), picture, 0, 0, cv::INTER_NEAREST);

  if (options.mark_loops && has_first_reference_)
  {
    const uint64_t first_shown_query = queries_ - uint64_t(values.rows) * (mode_ == Mode::kRollingWindow ? 1 : 0);
    const int radius = std::max(3, int(scale));
    for (const auto& loop : loops_)
    {
      int row = 0;
      if (mode_ == Mode::kRollingWindow)
      {
        if (loop.first < first_shown_query)
        {
          continue;
        }
        row = int(loop.first - first_shown_query);
      }
      else
      {
        row = int(loop.first / row_scale_);
      }
      if (loop.second < first_reference_id_)
      {
        continue;
      }
      const uint64_t column = (loop.second - first_reference_id_) / column_scale_;
      if (row >= values.rows || column >= uint64_t(values.cols))
      {
        continue;
      }
      const cv::Point centre(int((double(column) + 0.5) * scale), int((row + 0.5) * scale));
      cv::circle(image, centre, radius + 1, kLoopOuterColor, 1, cv::LINE_8);
      cv::circle(image, centre, radius, kLoopInnerColor, 1, cv::LINE_8);
    }
  }
  return image;
}

}  // namespace openable
