#pragma once

#include <image_transport/image_transport.h>
#include <std_msgs/Header.h>

#include <memory>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/view/distance_matrix_view.h"

namespace openable_ros
{
/// The distance_matrix topic: keeps the bounded core view up to date (one row per stored frame) and
/// renders it only while someone subscribes, at most `rate` Hz (rendering is the expensive part).
class MatrixPublisher
{
public:
  MatrixPublisher(ros::NodeHandle& nh, double rate, int size, const std::string& mode, bool threshold_view);

  /// False while the matrix is off (rate 0): callers then skip computing rows at all.
  bool wanted() const
  {
    return rate_ > 0.0;
  }
  void addRow(uint64_t first_id, const std::vector<float>& row);
  void addLoop(uint64_t match_id, uint64_t rows_ago = 0);
  /// Renders and publishes with the input frame's header when due and watched. Returns an error text
  /// (empty when fine) for the caller to log.
  std::string publish(const std_msgs::Header& header, const openable::Config& config);
  /// New display options (dynamic_reconfigure); returns an error text for a refused size.
  std::string setOptions(double rate, int size, const std::string& mode, bool threshold_view);
  void clear();

  uint64_t published() const
  {
    return published_;
  }

private:
  std::unique_ptr<image_transport::ImageTransport> transport_;
  image_transport::Publisher publisher_;
  openable::DistanceMatrixView view_;
  double rate_;
  bool threshold_view_;
  ros::WallTime last_;
  uint64_t published_ = 0;
};

}  // namespace openable_ros
