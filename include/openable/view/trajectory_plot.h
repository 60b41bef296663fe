#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/evaluation/loop_list.h"

namespace openable
{
/// A map of a trajectory seen from above with its loop closures: the picture of the paper's Fig. 6.
///
/// Positions are in the KITTI camera frame (x right, y down, z forward), so the ground plane is x-z and
/// seen from above x points right and z up. Both axes have the same scale (metres per pixel), with ticks,
/// grid and labels in metres. Each loop is a line between its two positions, green when the ground truth
/// agrees, red when not (red drawn last: a wrong loop is never hidden under right ones).
class TrajectoryPlot
{
public:
  /// Lays out `positions` in an image of `size` (at least 320x240). Throws Error for no positions, a
  /// non-finite position or a too small size.
  TrajectoryPlot(std::vector<cv::Vec3d> positions, cv::Size size = cv::Size(1000, 800));

  /// Pixel (sub-pixel precision) where a position is drawn.
  cv::Point2d toPixel(const cv::Vec3d& position) const;
  /// Pixel of frame `frame`'s position. Throws Error for a frame without position.
  cv::Point2d framePixel(int frame) const;
  /// Metres between two neighbouring ticks.
  double tickStep() const
  {
    return tick_;
  }

  /// The picture (BGR). Throws Error for a loop naming a frame without position.
  cv::Mat draw(const std::vector<LoopPair>& loops, const std::string& title) const;

  static const cv::Scalar kTrajectoryColour;
  static const cv::Scalar kAgreeColour;
  static const cv::Scalar kDisagreeColour;

private:
  void drawAxes(cv::Mat& image) const;
  void drawLegend(cv::Mat& image, const cv::Mat& ink, int agreeing, int disagreeing) const;

  std::vector<cv::Vec3d> positions_;
  cv::Size size_;
  cv::Rect area_;                         ///< the plot area inside the margins
  double text_scale_;                     ///< font scale that grows with the image
  double x_min_, z_min_, x_max_, z_max_;  ///< metres shown
  double pixels_per_metre_;
  double tick_;
};

/// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `wanted` ticks over `range`.
double niceTickStep(double range, int wanted);

}  // namespace openable
