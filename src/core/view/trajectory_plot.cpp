#include "openable/view/trajectory_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"

namespace openable
{
// BGR. The trajectory is a dark blue that neither loop colour is mistaken for.
const cv::Scalar TrajectoryPlot::kTrajectoryColour(140, 70, 20);
const cv::Scalar TrajectoryPlot::kAgreeColour(0, 170, 0);
const cv::Scalar TrajectoryPlot::kDisagreeColour(0, 0, 230);

namespace
{
const int kFont = cv::FONT_HERSHEY_SIMPLEX;
const int kShift = 4;  // sub-pixel bits for cv::line / cv::circle: positions are not rounded to whole pixels
const cv::Scalar kText(0, 0, 0);
const cv::Scalar kGrid(232, 232, 232);
const cv::Scalar kAxis(60, 60, 60);

cv::Point fixedPoint(const cv::Point2d& p)
{
  return cv::Point(static_cast<int>(std::lround(p.x * (1 << kShift))),
                   static_cast<int>(std::lround(p.y * (1 << kShift))));
}

/// Tick label without trailing zeros: 100, 2.5, -50.
std::string tickText(double value)
{
  char text[32];
  std::snprintf(text, sizeof(text), "%g", std::abs(value) < 1e-9 ? 0.0 : value);
  return text;
}

void putText(cv::Mat& image, const std::string& text, cv::Point origin, double scale, int thickness)
{
  cv::putText(image, text, origin, kFont, scale, kText, thickness, cv::LINE_AA);
}

/// Text turned a quarter to the left (reads bottom to top), centred on `centre`: the vertical axis label.
void putVerticalText(cv::Mat& image, const std::string& text, cv::Point centre, double scale, int thickness)
{
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::Mat label(size.height + baseline + 4, size.width + 4, CV_8UC3, cv::Scalar::all(255));
  cv::putText(label, text, cv::Point(2, size.height + 2), kFont, scale, kText, thickness, cv::LINE_AA);
  cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect target = cv::Rect(centre.x - label.cols / 2, centre.y - label.rows / 2, label.cols, label.rows) &
                          cv::Rect(0, 0, image.cols, image.rows);
  cv::Mat roi = image(target);
  // Dark text over whatever is there: the darker of both.
  cv::min(roi,
          label(cv::Rect(target.x - (centre.x - label.cols / 2), target.y - (centre.y - label.rows / 2), target.width,
                         target.height)),
          roi);
}
}  // namespace

double niceTickStep(double range, int wanted)
{
  if (!(range > 0.0) || wanted < 1)
    return 1.0;
  const double raw = range / wanted;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double factor : {1.0, 2.0, 5.0})
    if (factor * power >= raw)
      return factor * power;
  return 10.0 * power;
}

TrajectoryPlot::TrajectoryPlot(std::vector<cv::Vec3d> positions, cv::Size size)
  : positions_(std::move(positions)), size_(size)
{
  if (positions_.empty())
    throw Error("trajectory plot: no positions");
  if (size.width < 320 || size.height < 240)
    throw Error("trajectory plot: size " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                " is too small (at least 320x240)");
  double x_lo = positions_[0][0], x_hi = x_lo, z_lo = positions_[0][2], z_hi = z_lo;
  for (size_t i = 0; i < positions_.size(); ++i)
  {
    const cv::Vec3d& p = positions_[i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw Error("trajectory plot: position of frame " + std::to_string(i) + " is not finite");
    x_lo = std::min(x_lo, p[0]);
    x_hi = std::max(x_hi, p[0]);
    z_lo = std::min(z_lo, p[2]);
    z_hi = std::max(z_hi, p[2]);
  }
  // Text and margins grow with the image so the labels stay readable from 320x240 to poster size.
  const double scale = std::min(size.width / 1000.0, size.height / 800.0);
  text_scale_ = std::max(0.35, 0.55 * scale);
  const int left = static_cast<int>(std::lround(90 * std::max(scale, 0.6)));
  const int bottom = static_cast<int>(std::lround(75 * std::max(scale, 0.6)));
  const int top = static_cast<int>(std::lround(50 * std::max(scale, 0.6)));
  const int right = static_cast<int>(std::lround(25 * std::max(scale, 0.6)));
  area_ = cv::Rect(left, top, size.width - left - right, size.height - top - bottom);

  // One scale for both axes (a map, not a chart), a little room around the path, the path centred.
  const double span = std::max({x_hi - x_lo, z_hi - z_lo, 1.0});
  const double padding = 0.04 * span;
  pixels_per_metre_ = std::min(area_.width / (x_hi - x_lo + 2 * padding), area_.height / (z_hi - z_lo + 2 * padding));
  const double x_centre = 0.5 * (x_lo + x_hi), z_centre = 0.5 * (z_lo + z_hi);
  x_min_ = x_centre - 0.5 * area_.width / pixels_per_metre_;
  x_max_ = x_centre + 0.5 * area_.width / pixels_per_metre_;
  z_min_ = z_centre - 0.5 * area_.height / pixels_per_metre_;
  z_max_ = z_centre + 0.5 * area_.height / pixels_per_metre_;
  tick_ = niceTickStep(std::max(x_max_ - x_min_, z_max_ - z_min_), 8);
}

cv::Point2d TrajectoryPlot::toPixel(const cv::Vec3d& position) const
{
  return cv::Point2d(area_.x + (position[0] - x_min_) * pixels_per_metre_,
                     area_.y + area_.height - (position[2] - z_min_) * pixels_per_metre_);
}

cv::Point2d TrajectoryPlot::framePixel(int frame) const
{
  if (frame < 0 || static_cast<size_t>(frame) >= positions_.size())
    throw Error("trajectory plot: frame " + std::to_string(frame) + " has no position (poses of frames 0.." +
                std::to_string(positions_.size() - 1) + ")");
  return toPixel(positions_[static_cast<size_t>(frame)]);
}

void TrajectoryPlot::drawAxes(cv::Mat& image) const
{
  const int thickness = std::max(1, static_cast<int>(std::lround(text_scale_ / 0.55)));
  const int tick_length = std::max(4, area_.height / 100);
  int baseline = 0;
  // Grid and ticks at the multiples of the step inside the shown range.
  for (double x = std::ceil(x_min_ / tick_) * tick_; x <= x_max_ + 1e-9; x += tick_)
  {
    const int px = static_cast<int>(std::lround(toPixel({x, 0, z_min_}).x));
    cv::line(image, {px, area_.y}, {px, area_.y + area_.height}, kGrid, 1);
    cv::line(image, {px, area_.y + area_.height}, {px, area_.y + area_.height + tick_length}, kAxis, 1);
    const std::string text = tickText(x);
    const cv::Size s = cv::getTextSize(text, kFont, text_scale_, 1, &baseline);
    putText(image, text, {px - s.width / 2, area_.y + area_.height + tick_length + s.height + 4}, text_scale_, 1);
  }
  for (double z = std::ceil(z_min_ / tick_) * tick_; z <= z_max_ + 1e-9; z += tick_)
  {
    const int py = static_cast<int>(std::lround(toPixel({x_min_, 0, z}).y));
    cv::line(image, {area_.x, py}, {area_.x + area_.width, py}, kGrid, 1);
    cv::line(image, {area_.x - tick_length, py}, {area_.x, py}, kAxis, 1);
    const std::string text = tickText(z);
    const cv::Size s = cv::getTextSize(text, kFont, text_scale_, 1, &baseline);
    putText(image, text, {area_.x - tick_length - 4 - s.width, py + s.height / 2}, text_scale_, 1);
  }
  cv::rectangle(image, area_, kAxis, 1);
  const std::string x_label = "x (m, right)";
  const cv::Size xs = cv::getTextSize(x_label, kFont, text_scale_ * 1.1, thickness, &baseline);
  putText(image, x_label, {area_.x + area_.width / 2 - xs.width / 2, size_.height - 10}, text_scale_ * 1.1, thickness);
  putVerticalText(image, "z (m, forward)", {static_cast<int>(16 * text_scale_ / 0.55), area_.y + area_.height / 2},
                  text_scale_ * 1.1, thickness);
}

void TrajectoryPlot::drawLegend(cv::Mat& image, const cv::Mat& ink, int agreeing, int disagreeing) const
{
  struct Entry
  {
    std::string text;
    cv::Scalar colour;
    bool marker;  // a start marker instead of a line
  };
  const std::vector<Entry> entries = {
      {"trajectory (" + std::to_string(positions_.size()) + " frames)", kTrajectoryColour, false},
      {"start", kTrajectoryColour, true},
      {"loop, ground truth agrees (" + std::to_string(agreeing) + ")", kAgreeColour, false},
      {"loop, ground truth disagrees (" + std::to_string(disagreeing) + ")", kDisagreeColour, false},
  };
  int baseline = 0;
  int text_width = 0;
  const cv::Size row = cv::getTextSize("Mg", kFont, text_scale_, 1, &baseline);
  for (const Entry& e : entries)
    text_width = std::max(text_width, cv::getTextSize(e.text, kFont, text_scale_, 1, &baseline).width);
  const int line_length = static_cast<int>(40 * text_scale_ / 0.55);
  const int gap = row.height;
  const cv::Size box(line_length + text_width + 3 * gap, static_cast<int>(entries.size()) * 2 * gap + gap);
  // The corner of the plot area that hides the least of the drawing.
  const int margin = gap;
  const std::vector<cv::Point> corners = {
      {area_.x + area_.width - box.width - margin, area_.y + margin},
      {area_.x + margin, area_.y + margin},
      {area_.x + area_.width - box.width - margin, area_.y + area_.height - box.height - margin},
      {area_.x + margin, area_.y + area_.height - box.height - margin}};
  cv::Rect best;
  int best_hidden = -1;
  for (const cv::Point& corner : corners)
  {
    const cv::Rect r = cv::Rect(corner, box) & cv::Rect(0, 0, image.cols, image.rows);
    const int hidden = cv::countNonZero(ink(r));
    if (best_hidden < 0 || hidden < best_hidden)
    {
      best_hidden = hidden;
      best = r;
    }
  }
  cv::rectangle(image, best, cv::Scalar::all(255), cv::FILLED);
  cv::rectangle(image, best, kAxis, 1);
  const int thickness = std::max(2, static_cast<int>(std::lround(3 * text_scale_ / 0.55)));
  for (size_t i = 0; i < entries.size(); ++i)
  {
    const int y = best.y + gap + static_cast<int>(i) * 2 * gap + gap / 2;
    const cv::Point a(best.x + gap, y), b(best.x + gap + line_length, y);
    if (entries[i].marker)
    {
      cv::circle(image, (a + b) / 2, thickness + 3, cv::Scalar::all(255), cv::FILLED, cv::LINE_AA);
      cv::circle(image, (a + b) / 2, thickness + 3, entries[i].colour, 2, cv::LINE_AA);
    }
    else
    {
      cv::line(image, a, b, entries[i].colour, thickness, cv::LINE_AA);
    }
    putText(image, entries[i].text, {b.x + gap, y + row.height / 2}, text_scale_, 1);
  }
}

cv::Mat TrajectoryPlot::draw(const std::vector<LoopPair>& loops, const std::string& title) const
{
  for (const LoopPair& loop : loops)
  {
    framePixel(loop.query);  // throws for a frame without position, naming it
    framePixel(loop.match);
  }
  cv::Mat image(size_, CV_8UC3, cv::Scalar::all(255));
  drawAxes(image);
  // What the legend must not hide: the path and the loops.
  cv::Mat ink(size_, CV_8U, cv::Scalar(0));
  const int path_thickness = std::max(2, static_cast<int>(std::lround(2 * text_scale_ / 0.55)));
  const int loop_thickness = path_thickness + 1;
  std::vector<cv::Point> path;
  path.reserve(positions_.size());
  for (const cv::Vec3d& p : positions_)
    path.push_back(fixedPoint(toPixel(p)));
  const std::vector<std::vector<cv::Point>> paths = {path};
  cv::polylines(image, paths, false, kTrajectoryColour, path_thickness, cv::LINE_AA, kShift);
  cv::polylines(ink, paths, false, cv::Scalar(255), path_thickness + 4, cv::LINE_8, kShift);

  // Start marker: a ring on the first position, larger than the loop dots that may cover its centre.
  const cv::Point start = fixedPoint(framePixel(0));
  cv::circle(image, start, (loop_thickness + 5) << kShift, cv::Scalar::all(255), cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(image, start, (loop_thickness + 5) << kShift, kTrajectoryColour, 2, cv::LINE_AA, kShift);

  // Loops: a line between the two positions and a dot at each end (a loop between two passes of the same
  // road is a few metres long: the dots keep it visible at any scale). The ground truth's verdict is the
  // colour; wrong loops are drawn last, on top.
  int agreeing = 0;
  for (bool agrees : {true, false})
  {
    const cv::Scalar colour = agrees ? kAgreeColour : kDisagreeColour;
    for (const LoopPair& loop : loops)
    {
      if (loop.agrees != agrees)
        continue;
      agreeing += agrees ? 1 : 0;
      const cv::Point a = fixedPoint(framePixel(loop.query)), b = fixedPoint(framePixel(loop.match));
      cv::line(image, a, b, colour, loop_thickness, cv::LINE_AA, kShift);
      cv::circle(image, a, (loop_thickness + 1) << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
      cv::circle(image, b, (loop_thickness + 1) << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
      cv::line(ink, a, b, cv::Scalar(255), loop_thickness + 4, cv::LINE_8, kShift);
    }
  }

  drawLegend(image, ink, agreeing, static_cast<int>(loops.size()) - agreeing);
  if (!title.empty())
  {
    int baseline = 0;
    const int thickness = std::max(1, static_cast<int>(std::lround(text_scale_ / 0.55)));
    double scale = text_scale_ * 1.3;
    while (scale > 0.3 && cv::getTextSize(title, kFont, scale, thickness, &baseline).width > size_.width - 20)
      scale *= 0.95;
    const cv::Size s = cv::getTextSize(title, kFont, scale, thickness, &baseline);
    putText(image, title, {size_.width / 2 - s.width / 2, area_.y / 2 + s.height / 2}, scale, thickness);
  }
  return image;
}

}  // namespace openable
