// openable_ros/PanoramicDetector: ABLE-P, loop closures from a panoramic camera, in both directions.
#include <image_transport/image_transport.h>
#include <sensor_msgs/Image.h>

#include <pluginlib/class_list_macros.hpp>

#include "openable_ros/conversions.h"
#include "openable_ros/detector_base.h"
#include "openable_ros/params.h"
#include "openable_ros/ring_synchronizer.h"

namespace openable_ros
{
class PanoramicDetector : public DetectorBase
{
private:
  void onInit() override
  {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::vector<std::string> warnings;
    cameras_ = readStringList(pnh, "cameras", warnings);
    const bool approximate = readBool(pnh, "approximate_sync", false, warnings);
    const double max_skew = readDouble(pnh, "max_skew", 0.02, 0.0, 10.0, "s", warnings);
    for (const auto& warning : warnings)
    {
      NODELET_WARN_STREAM("parameter " << warning);
    }
    openable::Config defaults;
    defaults.camera_type = "panoramic";
    if (!cameras_.empty())
    {
      // One sub-panorama per camera: ~panoramas follows the ring.
      int panoramas = 0;
      if (pnh.getParam("panoramas", panoramas) && panoramas != int(cameras_.size()))
      {
        NODELET_WARN_STREAM("parameter ~panoramas: value '" << panoramas << "' does not match the " << cameras_.size()
                                                            << " ~cameras; using " << cameras_.size());
      }
      pnh.setParam("panoramas", int(cameras_.size()));
    }
    if (!setupDetector(defaults))
    {
      return;
    }
    input_transport_ = std::make_unique<image_transport::ImageTransport>(getNodeHandle());
    const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
    if (cameras_.empty())
    {
      subscribers_.push_back(input_transport_->subscribe("image", uint32_t(queueSize()),
                                                         &PanoramicDetector::panoramaCallback, this, hints));
      return;
    }
    synchronizer_ =
        std::make_unique<RingSynchronizer>(cameras_.size(), size_t(queueSize()), approximate ? max_skew : 0.0);
    std::vector<std::string> topics;
    for (size_t i = 0; i < cameras_.size(); ++i)
    {
      subscribers_.push_back(input_transport_->subscribe(
          cameras_[i], uint32_t(queueSize()),
          boost::function<void(const sensor_msgs::ImageConstPtr&)>([this, i](const sensor_msgs::ImageConstPtr& msg)
                                                                   { cameraCallback(i, msg); }),
          ros::VoidPtr(), hints));
      topics.push_back(subscribers_.back().getTopic());
    }
    startSyncWatchdog(topics, approximate ? "Raise ~max_skew if the cameras are not triggered together."
                                          : "If the cameras are not hardware-triggered, set ~approximate_sync "
                                            "true (with ~max_skew).");
  }

  void panoramaCallback(const sensor_msgs::ImageConstPtr& msg)
  {
    cv::Mat image;
    std::string error;
    if (!toCoreImage(msg, image, error))
    {
      rejectFrame("bad image", "'" + subscribers_[0].getTopic() + "': " + error);
      return;
    }
    openable::FrameInput input;
    input.image = image;
    processFrame(msg->header, subscribers_[0].getTopic(), std::move(input));
  }

  void cameraCallback(size_t index, const sensor_msgs::ImageConstPtr& msg)
  {
    noteInput(index);
    RingSynchronizer::Set set;
    if (!synchronizer_->add(index, msg, set))
    {
      return;
    }
    noteSynchronised();
    std::vector<cv::Mat> images(set.size());
    for (size_t i = 0; i < set.size(); ++i)
    {
      std::string error;
      if (!toCoreImage(set[i], images[i], error))
      {
        rejectFrame("bad image", "'" + subscribers_[i].getTopic() + "': " + error);
        return;
      }
    }
    // The ring is stamped by its first camera.
    openable::FrameInput input;
    input.cameras = std::move(images);
    processFrame(set[0]->header, subscribers_[0].getTopic(), std::move(input));
  }

  std::vector<std::string> cameras_;
  std::unique_ptr<image_transport::ImageTransport> input_transport_;
  std::vector<image_transport::Subscriber> subscribers_;
  std::unique_ptr<RingSynchronizer> synchronizer_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::PanoramicDetector, nodelet::Nodelet)
