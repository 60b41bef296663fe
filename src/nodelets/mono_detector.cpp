// openable_ros/MonoDetector: ABLE-M, loop closures from one camera.
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <pluginlib/class_list_macros.hpp>

#include "openable_ros/conversions.h"
#include "openable_ros/detector.h"

namespace openable_ros
{
class MonoDetector : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    std::vector<std::string> warnings;
    const RosParameters parameters = readRosParameters(getPrivateNodeHandle(), warnings);
    for (const auto& warning : warnings)
      NODELET_WARN_STREAM("parameter " << warning);
    openable::Config defaults;
    defaults.camera_type = "mono";
    detector_ = Detector::create(getNodeHandle(), getPrivateNodeHandle(), getName(), defaults, parameters);
    if (!detector_)
      return;
    transport_ = std::make_unique<image_transport::ImageTransport>(getNodeHandle());
    // Transport hints from the private handle: ~image_transport:=compressed works.
    image_sub_ =
        transport_->subscribe("image", uint32_t(parameters.queue_size), &MonoDetector::imageCallback, this,
                              image_transport::TransportHints("raw", ros::TransportHints(), getPrivateNodeHandle()));
    if (parameters.verify)
    {
      // Geometric verification needs the intrinsics of the rectified image (P), beside the image.
      info_sub_ = getNodeHandle().subscribe<sensor_msgs::CameraInfo>("camera_info", 1,
                                                                     [this](const sensor_msgs::CameraInfoConstPtr& msg)
                                                                     { detector_->setCamera(toPinholeCamera(*msg)); });
    }
  }

  void imageCallback(const sensor_msgs::ImageConstPtr& msg)
  {
    detector_->noteInput(0, msg->header);
    openable::FrameInput input;
    openable::InputProblem problem;
    if (!toCoreImage(msg, input.image, problem))
    {
      detector_->reject(problem, image_sub_.getTopic());
      return;
    }
    detector_->process(msg->header, image_sub_.getTopic(), std::move(input));
  }

  std::unique_ptr<Detector> detector_;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  image_transport::Subscriber image_sub_;
  ros::Subscriber info_sub_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::MonoDetector, nodelet::Nodelet)
