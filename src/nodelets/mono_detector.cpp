// openable_ros/MonoDetector: ABLE-M, loop closures from one camera.
#include <image_transport/image_transport.h>
#include <sensor_msgs/Image.h>

#include <pluginlib/class_list_macros.hpp>

#include "openable_ros/conversions.h"
#include "openable_ros/detector_base.h"

namespace openable_ros
{
class MonoDetector : public DetectorBase
{
private:
  void onInit() override
  {
    openable::Config defaults;
    defaults.camera_type = "mono";
    if (!setupDetector(defaults))
    {
      return;
    }
    input_transport_ = std::make_unique<image_transport::ImageTransport>(getNodeHandle());
    // Transport hints from the private handle: ~image_transport:=compressed works.
    image_sub_ = input_transport_->subscribe(
        "image", uint32_t(queueSize()), &MonoDetector::imageCallback, this,
        image_transport::TransportHints("raw", ros::TransportHints(), getPrivateNodeHandle()));
    if (verifyEnabled())
    {
      // Geometric verification needs the intrinsics (rectified image: P).
      info_sub_ = getNodeHandle().subscribe<sensor_msgs::CameraInfo>(
          "camera_info", 1, [this](const sensor_msgs::CameraInfoConstPtr& msg) { setCamera(toPinholeCamera(*msg)); });
    }
  }

  void imageCallback(const sensor_msgs::ImageConstPtr& msg)
  {
    cv::Mat image;
    std::string error;
    if (!toCoreImage(msg, image, error))
    {
      rejectFrame("bad image", "'" + image_sub_.getTopic() + "': " + error);
      return;
    }
    openable::FrameInput input;
    input.image = image;
    processFrame(msg->header, image_sub_.getTopic(), std::move(input));
  }

  std::unique_ptr<image_transport::ImageTransport> input_transport_;
  image_transport::Subscriber image_sub_;
  ros::Subscriber info_sub_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::MonoDetector, nodelet::Nodelet)
