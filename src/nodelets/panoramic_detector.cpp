// openable_ros/PanoramicDetector: ABLE-P, loop closures from a panoramic camera, in both directions.
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/Image.h>

#include <pluginlib/class_list_macros.hpp>

#include "openable/node_support/ring_sync.h"
#include "openable_ros/conversions.h"
#include "openable_ros/detector.h"

namespace openable_ros
{
class PanoramicDetector : public nodelet::Nodelet
{
private:
  using Ring = openable::RingSync<sensor_msgs::ImageConstPtr>;

  void onInit() override
  {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::vector<std::string> warnings;
    const RosParameters parameters = readRosParameters(pnh, warnings);
    for (const auto& warning : warnings)
      NODELET_WARN_STREAM("parameter " << warning);
    openable::Config defaults;
    defaults.camera_type = "panoramic";
    const size_t cameras = parameters.cameras.size();
    if (cameras > 0)
    {
      // One sub-panorama per camera: ~panoramas follows the ring.
      int panoramas = 0;
      if (pnh.getParam("panoramas", panoramas) && panoramas != int(cameras))
        NODELET_WARN_STREAM("parameter ~panoramas: value '" << panoramas << "' does not match the " << cameras
                                                            << " ~cameras; using " << cameras);
      pnh.setParam("panoramas", int(cameras));
    }
    detector_ = Detector::create(getNodeHandle(), pnh, getName(), defaults, parameters);
    if (!detector_)
      return;
    transport_ = std::make_unique<image_transport::ImageTransport>(getNodeHandle());
    const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
    const uint32_t queue = uint32_t(parameters.queue_size);
    if (cameras == 0)
    {
      subscribers_.push_back(transport_->subscribe("image", queue, &PanoramicDetector::panoramaCallback, this, hints));
      return;
    }
    ring_ = std::make_unique<Ring>(cameras, size_t(queue), parameters.approximate_sync ? parameters.max_skew : 0.0,
                                   [](const sensor_msgs::ImageConstPtr& m) { return m->header.stamp.toSec(); });
    std::vector<std::string> topics;
    for (size_t i = 0; i < cameras; ++i)
    {
      subscribers_.push_back(transport_->subscribe(
          parameters.cameras[i], queue,
          boost::function<void(const sensor_msgs::ImageConstPtr&)>([this, i](const sensor_msgs::ImageConstPtr& msg)
                                                                   { cameraCallback(i, msg); }),
          ros::VoidPtr(), hints));
      topics.push_back(subscribers_.back().getTopic());
    }
    detector_->watchSync(topics, parameters.approximate_sync
                                     ? "Raise ~max_skew if the cameras are not triggered together."
                                     : "If the cameras are not hardware-triggered, set ~approximate_sync true (with "
                                       "~max_skew).");
  }

  void panoramaCallback(const sensor_msgs::ImageConstPtr& msg)
  {
    detector_->noteInput(0, msg->header);
    openable::FrameInput input;
    openable::InputProblem problem;
    if (!toCoreImage(msg, input.image, problem))
    {
      detector_->reject(problem, subscribers_[0].getTopic());
      return;
    }
    detector_->process(msg->header, subscribers_[0].getTopic(), std::move(input));
  }

  void cameraCallback(size_t index, const sensor_msgs::ImageConstPtr& msg)
  {
    detector_->noteInput(index, msg->header);
    Ring::Set set;
    const bool complete = ring_->add(index, msg, set);
    detector_->noteDropped(ring_->dropped());
    if (!complete)
      return;
    detector_->noteSet();
    openable::FrameInput input;
    input.cameras.resize(set.size());
    for (size_t i = 0; i < set.size(); ++i)
    {
      openable::InputProblem problem;
      if (!toCoreImage(set[i], input.cameras[i], problem))
      {
        detector_->reject(problem, subscribers_[i].getTopic());
        return;
      }
    }
    // The ring is stamped by its first camera.
    detector_->process(set[0]->header, subscribers_[0].getTopic(), std::move(input));
  }

  std::unique_ptr<Detector> detector_;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  std::vector<image_transport::Subscriber> subscribers_;
  std::unique_ptr<Ring> ring_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::PanoramicDetector, nodelet::Nodelet)
