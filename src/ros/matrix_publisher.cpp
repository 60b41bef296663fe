#include "openable_ros/matrix_publisher.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>

#include <algorithm>

#include "openable/error.h"

namespace openable_ros
{
namespace
{
openable::DistanceMatrixView::Mode viewMode(const std::string& mode)
{
  return mode == "rolling_window" ? openable::DistanceMatrixView::Mode::kRollingWindow
                                  : openable::DistanceMatrixView::Mode::kWholeHistory;
}
}  // namespace

MatrixPublisher::MatrixPublisher(ros::NodeHandle& nh, double rate, int size, const std::string& mode,
                                 bool threshold_view)
  : transport_(std::make_unique<image_transport::ImageTransport>(nh)),
    view_(size, viewMode(mode)),
    rate_(rate),
    threshold_view_(threshold_view)
{
  publisher_ = transport_->advertise("distance_matrix", 1);
}

void MatrixPublisher::addRow(uint64_t first_id, const std::vector<float>& row)
{
  if (wanted())
    view_.addRow(first_id, row);
}

void MatrixPublisher::addLoop(uint64_t match_id, uint64_t rows_ago)
{
  if (wanted())
    view_.addLoop(match_id, rows_ago);
}

std::string MatrixPublisher::publish(const std_msgs::Header& header, const openable::Config& config)
{
  if (!wanted() || publisher_.getNumSubscribers() == 0)
    return "";
  const ros::WallTime now = ros::WallTime::now();
  if (!last_.isZero() && (now - last_).toSec() < 1.0 / rate_)
    return "";
  openable::DistanceMatrixView::RenderOptions options;
  options.color_map = config.color_map;
  // display_normalization: minmax stretches the shown distances over the colour map, max is paper Eq. 5.
  options.stretch = config.display_normalization != "max";
  if (threshold_view_)
    options.threshold = std::max(0.0, config.threshold);
  cv::Mat picture;
  try
  {
    picture = view_.render(options);
  }
  catch (const openable::Error& e)
  {
    return std::string("distance_matrix: ") + e.what();
  }
  if (picture.empty())
    return "";
  last_ = now;
  publisher_.publish(cv_bridge::CvImage(header, sensor_msgs::image_encodings::BGR8, picture).toImageMsg());
  ++published_;
  return "";
}

std::string MatrixPublisher::setOptions(double rate, int size, const std::string& mode, bool threshold_view)
{
  if (rate_ <= 0.0 && rate > 0.0)
    view_.clear();  // the view was not kept while off: start a fresh picture rather than a misleading one
  rate_ = rate;
  threshold_view_ = threshold_view;
  view_.setMode(viewMode(mode));
  try
  {
    view_.setSize(size);
  }
  catch (const openable::Error& e)
  {
    return std::string("matrix_size: ") + e.what();
  }
  return "";
}

void MatrixPublisher::clear()
{
  view_.clear();
}

}  // namespace openable_ros
