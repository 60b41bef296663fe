// The precision-recall plot (PNG): axes, curves, legend.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "evaluation/evaluation_text.h"
#include "openable/error.h"
#include "openable/evaluation/evaluation.h"

namespace openable
{
using namespace detail;

// ---------------------------------------------------------------------------------------------------
// Plot

namespace
{
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
const int kFont = cv::FONT_HERSHEY_SIMPLEX;

/// Distinguishable colours (BGR) for overlaid curves; repeats after the last.
cv::Scalar seriesColour(size_t index)
{
  static const cv::Scalar kColours[] = {{180, 119, 31},  {14, 127, 255}, {44, 160, 44},   {40, 39, 214},
                                        {189, 103, 148}, {75, 86, 140},  {194, 119, 227}, {34, 189, 188}};
  return kColours[index % (sizeof(kColours) / sizeof(kColours[0]))];
}

void putCentred(cv::Mat& image, const std::string& text, cv::Point centre, double scale, int thickness)
{
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::putText(image, text, cv::Point(centre.x - size.width / 2, centre.y + size.height / 2), kFont, scale, kBlack,
              thickness, cv::LINE_AA);
}

/// Text turned 90 degrees counter-clockwise (the y-axis label), centred on `centre`.
void putVertical(cv::Mat& image, const std::string& text, cv::Point centre, double scale, int thickness)
{
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::Mat strip(size.height + baseline + 4, size.width + 4, image.type(), cv::Scalar::all(255));
  cv::putText(strip, text, cv::Point(2, size.height + 2), kFont, scale, kBlack, thickness, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect target(centre.x - turned.cols / 2, centre.y - turned.rows / 2, turned.cols, turned.rows);
  const cv::Rect inside = target & cv::Rect(0, 0, image.cols, image.rows);
  turned(cv::Rect(inside.x - target.x, inside.y - target.y, inside.width, inside.height)).copyTo(image(inside));
}

/// Grid, ticks every 0.1 with labels, axis labels; returns nothing, draws into `image` around `area`.
void drawAxes(cv::Mat& image, const cv::Rect& area, double scale)
{
  for (int k = 0; k <= 10; ++k)
  {
    const int x = area.x + area.width * k / 10;
    const int y = area.y + area.height - area.height * k / 10;
    cv::line(image, cv::Point(x, area.y), cv::Point(x, area.y + area.height), kGrid, 1);
    cv::line(image, cv::Point(area.x, y), cv::Point(area.x + area.width, y), kGrid, 1);
    cv::line(image, cv::Point(x, area.y + area.height), cv::Point(x, area.y + area.height + 6), kBlack, 1);
    cv::line(image, cv::Point(area.x - 6, y), cv::Point(area.x, y), kBlack, 1);
    std::ostringstream label;
    label << std::fixed << std::setprecision(1) << k / 10.0;
    putCentred(image, label.str(), cv::Point(x, area.y + area.height + 20), 0.45 * scale, 1);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label.str(), kFont, 0.45 * scale, 1, &baseline);
    cv::putText(image, label.str(), cv::Point(area.x - 10 - size.width, y + size.height / 2), kFont, 0.45 * scale,
                kBlack, 1, cv::LINE_AA);
  }
  cv::rectangle(image, area, kBlack, 1);
  putCentred(image, "recall", cv::Point(area.x + area.width / 2, area.y + area.height + 45), 0.6 * scale, 1);
  putVertical(image, "precision", cv::Point(area.x - 55, area.y + area.height / 2), 0.6 * scale, 1);
}

cv::Point plotPoint(const cv::Rect& area, double recall, double precision)
{
  return cv::Point(area.x + static_cast<int>(std::lround(recall * area.width)),
                   area.y + area.height - static_cast<int>(std::lround(precision * area.height)));
}

void drawCurve(cv::Mat& image, const cv::Rect& area, const std::vector<PrPoint>& curve, const cv::Scalar& colour)
{
  std::vector<cv::Point> points;
  for (const PrPoint& p : curve)
  {
    points.push_back(plotPoint(area, p.recall, p.precision));
  }
  if (points.size() == 1)
  {
    cv::circle(image, points.front(), 3, colour, cv::FILLED, cv::LINE_AA);
  }
  cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
}

/// The corner of the plot area where a box of `size` covers the fewest curve pixels (`ink`, non-zero where
/// a curve is drawn), so the legend hides as little as possible; lower right first, where PR curves
/// rarely go (high recall at low precision).
cv::Rect quietestCorner(const cv::Mat& ink, const cv::Rect& area, cv::Size size)
{
  const int margin = 10;
  const int left = area.x + margin, right = area.x + area.width - margin - size.width;
  const int top = area.y + margin, bottom = area.y + area.height - margin - size.height;
  const cv::Point corners[] = {{right, bottom}, {left, bottom}, {right, top}, {left, top}};
  cv::Rect best;
  int best_ink = -1;
  for (const cv::Point& corner : corners)
  {
    const cv::Rect box = cv::Rect(corner, size) & cv::Rect(0, 0, ink.cols, ink.rows);
    const int covered = cv::countNonZero(ink(box));
    if (best_ink < 0 || covered < best_ink)
    {
      best = box;
      best_ink = covered;
    }
  }
  return best;
}

void drawLegend(cv::Mat& image, const cv::Mat& ink, const cv::Rect& area, const std::vector<PrPlotSeries>& series,
                double scale)
{
  const int line_height = static_cast<int>(22 * scale);
  int width = 0;
  std::vector<std::string> labels;
  for (const PrPlotSeries& s : series)
  {
    labels.push_back(s.name + " (AUC " + numberText(std::round(s.result.auc * 1000.0) / 1000.0) + ")");
    int baseline = 0;
    width = std::max(width, cv::getTextSize(labels.back(), kFont, 0.45 * scale, 1, &baseline).width);
  }
  const cv::Rect box =
      quietestCorner(ink, area, cv::Size(width + 50, line_height * static_cast<int>(series.size()) + 8));
  cv::rectangle(image, box, cv::Scalar::all(255), cv::FILLED);
  cv::rectangle(image, box, kBlack, 1);
  for (size_t i = 0; i < series.size(); ++i)
  {
    const int y = box.y + 4 + line_height * static_cast<int>(i) + line_height / 2;
    cv::line(image, cv::Point(box.x + 8, y), cv::Point(box.x + 36, y), seriesColour(i), 2, cv::LINE_AA);
    cv::putText(image, labels[i], cv::Point(box.x + 44, y + 5), kFont, 0.45 * scale, kBlack, 1, cv::LINE_AA);
  }
}

}  // namespace

cv::Mat drawPrCurves(const std::vector<PrPlotSeries>& series, const std::string& title, cv::Size size)
{
  if (series.empty())
  {
    throw Error("PR plot: no curve to draw");
  }
  if (size.width < 320 || size.height < 240)
  {
    throw Error("PR plot: size " + shapeText(size.width, size.height) + " is too small (at least 320x240)");
  }
  // Text scales with the image so labels stay readable from 320x240 to poster size.
  const double scale = std::min(size.width / 800.0, size.height / 600.0) * 1.25;
  cv::Mat image(size, CV_8UC3, cv::Scalar::all(255));
  const int left = static_cast<int>(95 * scale), bottom = static_cast<int>(70 * scale);
  const int top = static_cast<int>(55 * scale), right = static_cast<int>(30 * scale);
  const cv::Rect area(left, top, size.width - left - right, size.height - top - bottom);
  drawAxes(image, area, scale);
  cv::Mat ink(size, CV_8U, cv::Scalar(0));
  for (size_t i = 0; i < series.size(); ++i)
  {
    drawCurve(image, area, series[i].result.curve, seriesColour(i));
    drawCurve(ink, area, series[i].result.curve, cv::Scalar(255));
  }
  drawLegend(image, ink, area, series, scale);
  std::string heading = title;
  if (series.size() == 1)
  {
    heading += (heading.empty() ? "" : " - ") + std::string("AUC ") +
               numberText(std::round(series.front().result.auc * 1000.0) / 1000.0);
  }
  // A long title is set smaller rather than cut off at the image edges.
  const int thickness = std::max(1, static_cast<int>(std::lround(scale)));
  double title_scale = 0.7 * scale;
  int baseline = 0;
  while (title_scale > 0.3 &&
         cv::getTextSize(heading, kFont, title_scale, thickness, &baseline).width > size.width - 20)
  {
    title_scale *= 0.95;
  }
  putCentred(image, heading, cv::Point(size.width / 2, top / 2), title_scale, thickness);
  return image;
}

}  // namespace openable
