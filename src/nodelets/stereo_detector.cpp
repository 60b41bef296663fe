// openable_ros/StereoDetector: ABLE-S, loop closures from a rectified stereo pair (D-LDB by default).
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>

#include <boost/function.hpp>
#include <memory>
#include <pluginlib/class_list_macros.hpp>

#include "openable/description/stereo.h"
#include "openable_ros/conversions.h"
#include "openable_ros/detector.h"

namespace openable_ros
{
class StereoDetector : public nodelet::Nodelet
{
private:
  using Image = sensor_msgs::Image;
  using Disparity = stereo_msgs::DisparityImage;
  using ExactPair = message_filters::sync_policies::ExactTime<Image, Image>;
  using ApproximatePair = message_filters::sync_policies::ApproximateTime<Image, Image>;
  using ExactDisparity = message_filters::sync_policies::ExactTime<Image, Disparity>;
  using ApproximateDisparity = message_filters::sync_policies::ApproximateTime<Image, Disparity>;

  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::vector<std::string> warnings;
    const RosParameters parameters = readRosParameters(pnh, warnings);
    for (const auto& warning : warnings)
      NODELET_WARN_STREAM("parameter " << warning);
    const bool approximate = parameters.approximate_sync;
    use_disparity_ = parameters.use_disparity;
    const bool use_disparity = use_disparity_;
    openable::Config defaults;
    defaults.camera_type = "stereo";
    defaults.descriptor = "D-LDB";
    detector_ = Detector::create(nh, pnh, getName(), defaults, parameters);
    if (!detector_)
    {
      return;
    }
    const uint32_t queue = uint32_t(parameters.queue_size);
    input_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
    const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
    left_sub_.subscribe(*input_transport_, "left/image_rect", queue, hints);
    left_sub_.registerCallback(boost::function<void(const sensor_msgs::ImageConstPtr&)>(
        [this](const sensor_msgs::ImageConstPtr& msg) { detector_->noteInput(0, msg->header); }));
    // camera_info is optional: when it comes, it is checked against the images (calibrated, same size).
    left_info_sub_ = nh.subscribe<sensor_msgs::CameraInfo>("left/camera_info", 1,
                                                           [this](const sensor_msgs::CameraInfoConstPtr& msg)
                                                           {
                                                             left_info_ = msg;
                                                             updateCamera();
                                                           });

    const std::string advice = approximate ? "Raise ~queue_size if the stamps are far apart."
                                           : "If the stamps are not identical, set ~approximate_sync true.";
    if (use_disparity)
    {
      disparity_sub_.subscribe(nh, "disparity", queue);
      disparity_sub_.registerCallback(boost::function<void(const stereo_msgs::DisparityImageConstPtr&)>(
          [this](const stereo_msgs::DisparityImageConstPtr& msg) { detector_->noteInput(1, msg->header); }));
      if (approximate)
      {
        approximate_disparity_ = std::make_unique<message_filters::Synchronizer<ApproximateDisparity>>(
            ApproximateDisparity(queue), left_sub_, disparity_sub_);
        approximate_disparity_->registerCallback(&StereoDetector::disparityCallback, this);
      }
      else
      {
        exact_disparity_ = std::make_unique<message_filters::Synchronizer<ExactDisparity>>(ExactDisparity(queue),
                                                                                           left_sub_, disparity_sub_);
        exact_disparity_->registerCallback(&StereoDetector::disparityCallback, this);
      }
      detector_->watchSync({left_sub_.getTopic(), disparity_sub_.getTopic()}, advice);
      return;
    }
    right_sub_.subscribe(*input_transport_, "right/image_rect", queue, hints);
    right_sub_.registerCallback(boost::function<void(const sensor_msgs::ImageConstPtr&)>(
        [this](const sensor_msgs::ImageConstPtr& msg) { detector_->noteInput(1, msg->header); }));
    right_info_sub_ = nh.subscribe<sensor_msgs::CameraInfo>("right/camera_info", 1,
                                                            [this](const sensor_msgs::CameraInfoConstPtr& msg)
                                                            {
                                                              right_info_ = msg;
                                                              updateCamera();
                                                            });
    if (approximate)
    {
      approximate_pair_ = std::make_unique<message_filters::Synchronizer<ApproximatePair>>(ApproximatePair(queue),
                                                                                           left_sub_, right_sub_);
      approximate_pair_->registerCallback(&StereoDetector::pairCallback, this);
    }
    else
    {
      exact_pair_ = std::make_unique<message_filters::Synchronizer<ExactPair>>(ExactPair(queue), left_sub_, right_sub_);
      exact_pair_->registerCallback(&StereoDetector::pairCallback, this);
    }
    detector_->watchSync({left_sub_.getTopic(), right_sub_.getTopic()}, advice);
  }

  /// With ~verify: the verifier's camera from the pair's projections (the baseline from the right P), or
  /// from the left one alone in disparity mode.
  void updateCamera()
  {
    if (!detector_->parameters().verify || !left_info_ || (!use_disparity_ && !right_info_))
    {
      return;
    }
    detector_->setCamera(toPinholeCamera(*left_info_, use_disparity_ ? nullptr : right_info_.get()));
  }

  /// False (with the frame rejected) when a received camera_info says the image cannot be used.
  bool checkInfo(const sensor_msgs::CameraInfoConstPtr& info, const sensor_msgs::Image& image, const std::string& topic)
  {
    if (!info)
    {
      return true;
    }
    if (info->K[0] == 0.0)
    {
      detector_->reject("uncalibrated camera", "'" + topic +
                                                   "': camera_info has K[0] = 0 (uncalibrated); expected a "
                                                   "calibrated, rectified camera");
      return false;
    }
    if (info->width != image.width || info->height != image.height)
    {
      detector_->reject("camera_info size mismatch", "'" + topic + "': image is " + std::to_string(image.width) + "x" +
                                                         std::to_string(image.height) + " but its camera_info says " +
                                                         std::to_string(info->width) + "x" +
                                                         std::to_string(info->height));
      return false;
    }
    return true;
  }

  void pairCallback(const sensor_msgs::ImageConstPtr& left_msg, const sensor_msgs::ImageConstPtr& right_msg)
  {
    detector_->noteSet();
    cv::Mat left;
    cv::Mat right;
    openable::InputProblem problem;
    if (!toCoreImage(left_msg, left, problem))
    {
      detector_->reject(problem, left_sub_.getTopic());
      return;
    }
    if (!toCoreImage(right_msg, right, problem))
    {
      detector_->reject(problem, right_sub_.getTopic());
      return;
    }
    if (left.size() != right.size() || left.type() != right.type())
    {
      detector_->reject("left/right mismatch", "'" + left_sub_.getTopic() + "' is " + std::to_string(left.cols) + "x" +
                                                   std::to_string(left.rows) + " " + left_msg->encoding + " but '" +
                                                   right_sub_.getTopic() + "' is " + std::to_string(right.cols) + "x" +
                                                   std::to_string(right.rows) + " " + right_msg->encoding +
                                                   "; expected a rectified pair of one size and encoding");
      return;
    }
    if (!checkInfo(left_info_, *left_msg, left_sub_.getTopic()) ||
        !checkInfo(right_info_, *right_msg, right_sub_.getTopic()))
    {
      return;
    }
    // The core describes (D-LDB computes the disparity with SGBM; a mono descriptor uses the left image) and
    // verifies with the pair.
    openable::FrameInput input;
    input.image = left;
    input.right = right;
    detector_->process(left_msg->header, left_sub_.getTopic(), std::move(input));
  }

  void disparityCallback(const sensor_msgs::ImageConstPtr& left_msg,
                         const stereo_msgs::DisparityImageConstPtr& disparity_msg)
  {
    detector_->noteSet();
    cv::Mat left;
    cv::Mat raw;
    openable::InputProblem problem;
    if (!toCoreImage(left_msg, left, problem))
    {
      detector_->reject(problem, left_sub_.getTopic());
      return;
    }
    if (!toDisparity(disparity_msg->image, raw, problem))
    {
      detector_->reject(problem, disparity_sub_.getTopic());
      return;
    }
    if (raw.size() != left.size())
    {
      detector_->reject("left/disparity mismatch", "'" + left_sub_.getTopic() + "' is " + std::to_string(left.cols) +
                                                       "x" + std::to_string(left.rows) + " but '" +
                                                       disparity_sub_.getTopic() + "' is " + std::to_string(raw.cols) +
                                                       "x" + std::to_string(raw.rows) +
                                                       "; expected the disparity of the left image");
      return;
    }
    if (!checkInfo(left_info_, *left_msg, left_sub_.getTopic()))
    {
      return;
    }
    openable::FrameInput input;
    input.image = left;
    input.disparity = raw;
    detector_->process(left_msg->header, left_sub_.getTopic(), std::move(input));
  }

  std::unique_ptr<Detector> detector_;
  bool use_disparity_ = false;
  std::unique_ptr<image_transport::ImageTransport> input_transport_;
  image_transport::SubscriberFilter left_sub_;
  image_transport::SubscriberFilter right_sub_;
  message_filters::Subscriber<Disparity> disparity_sub_;
  ros::Subscriber left_info_sub_;
  ros::Subscriber right_info_sub_;
  sensor_msgs::CameraInfoConstPtr left_info_;
  sensor_msgs::CameraInfoConstPtr right_info_;
  std::unique_ptr<message_filters::Synchronizer<ExactPair>> exact_pair_;
  std::unique_ptr<message_filters::Synchronizer<ApproximatePair>> approximate_pair_;
  std::unique_ptr<message_filters::Synchronizer<ExactDisparity>> exact_disparity_;
  std::unique_ptr<message_filters::Synchronizer<ApproximateDisparity>> approximate_disparity_;
};

}  // namespace openable_ros

PLUGINLIB_EXPORT_CLASS(openable_ros::StereoDetector, nodelet::Nodelet)
