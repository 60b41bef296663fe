#include "openable_ros/conversions.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>

#include <boost/make_shared.hpp>
#include <opencv2/imgproc.hpp>

namespace openable_ros
{
namespace enc = sensor_msgs::image_encodings;

bool isSupportedEncoding(const std::string& encoding)
{
  return encoding == enc::MONO8 || encoding == enc::TYPE_8UC1 || encoding == enc::BGR8 || encoding == enc::RGB8 ||
         encoding == enc::BGRA8 || encoding == enc::RGBA8 || encoding == enc::TYPE_8UC3 || encoding == enc::TYPE_8UC4 ||
         encoding == enc::MONO16;
}

const char* supportedEncodings()
{
  return "mono8, 8UC1, bgr8, rgb8, bgra8, rgba8, 8UC3, 8UC4 or mono16";
}

bool toCoreImage(const sensor_msgs::ImageConstPtr& msg, cv::Mat& image, openable::InputProblem& problem)
{
  problem = openable::InputProblem();
  if (msg->width == 0 || msg->height == 0)
  {
    problem = {"empty image", "empty image (" + std::to_string(msg->width) + "x" + std::to_string(msg->height) + ")"};
    return false;
  }
  if (!isSupportedEncoding(msg->encoding))
  {
    problem = {"unsupported encoding",
               "encoding '" + msg->encoding + "' is not supported; expected " + supportedEncodings()};
    return false;
  }
  if (size_t(msg->step) * msg->height > msg->data.size())
  {
    problem = {"image data too short", "image data holds " + std::to_string(msg->data.size()) +
                                           " bytes, but step x height = " +
                                           std::to_string(size_t(msg->step) * msg->height)};
    return false;
  }
  try
  {
    const std::string& e = msg->encoding;
    if (e == enc::MONO8 || e == enc::TYPE_8UC1 || e == enc::BGR8 || e == enc::TYPE_8UC3)
    {
      // No copy: the core only reads its input.
      image = cv_bridge::toCvShare(msg)->image;
    }
    else if (e == enc::MONO16)
    {
      // Either byte order (is_bigendian), the top 8 bits kept.
      cv::Mat raw(int(msg->height), int(msg->width), CV_16UC1, const_cast<uint8_t*>(msg->data.data()), msg->step);
      cv::Mat native = raw.clone();
      const bool host_big_endian = cv::Mat(1, 1, CV_16UC1, cv::Scalar(1)).data[0] == 0;
      if (bool(msg->is_bigendian) != host_big_endian)
        for (int r = 0; r < native.rows; ++r)
        {
          uint16_t* row = native.ptr<uint16_t>(r);
          for (int c = 0; c < native.cols; ++c)
            row[c] = uint16_t((row[c] >> 8) | (row[c] << 8));
        }
      native.convertTo(image, CV_8U, 1.0 / 256.0);
    }
    else if (e == enc::TYPE_8UC4)
    {
      cv::cvtColor(cv_bridge::toCvShare(msg)->image, image, cv::COLOR_BGRA2BGR);
    }
    else
    {
      image = cv_bridge::toCvCopy(msg, enc::BGR8)->image;
    }
  }
  catch (const cv_bridge::Exception& e)
  {
    problem = {"cannot convert image", std::string("cv_bridge could not convert it: ") + e.what()};
    return false;
  }
  catch (const cv::Exception& e)
  {
    problem = {"cannot convert image", std::string("OpenCV could not convert it: ") + e.what()};
    return false;
  }
  return true;
}

bool toDisparity(const sensor_msgs::Image& msg, cv::Mat& disparity, openable::InputProblem& problem)
{
  problem = openable::InputProblem();
  if (msg.encoding != enc::TYPE_32FC1)
  {
    problem = {"unsupported disparity encoding", "disparity encoding '" + msg.encoding +
                                                     "' is not supported; expected 32FC1 (stereo_msgs/DisparityImage)"};
    return false;
  }
  if (msg.width == 0 || msg.height == 0 || size_t(msg.step) * msg.height > msg.data.size() ||
      msg.step < msg.width * sizeof(float))
  {
    problem = {"malformed disparity", "disparity image of " + std::to_string(msg.width) + "x" +
                                          std::to_string(msg.height) + " with step " + std::to_string(msg.step) +
                                          " and " + std::to_string(msg.data.size()) + " bytes is malformed"};
    return false;
  }
  // The message outlives this call (the caller holds it), so a header over its data is enough.
  disparity = cv::Mat(int(msg.height), int(msg.width), CV_32F, const_cast<uint8_t*>(msg.data.data()), msg.step);
  return true;
}

openable::PinholeCamera toPinholeCamera(const sensor_msgs::CameraInfo& left, const sensor_msgs::CameraInfo* right)
{
  cv::Matx34d p_left;
  cv::Matx34d p_right = cv::Matx34d::zeros();
  for (int i = 0; i < 12; ++i)
  {
    p_left(i / 4, i % 4) = left.P[size_t(i)];
    if (right)
    {
      p_right(i / 4, i % 4) = right->P[size_t(i)];
    }
  }
  openable::PinholeCamera camera = openable::PinholeCamera::fromProjection(p_left, p_right);
  camera.image_size = cv::Size(int(left.width), int(left.height));  // images of another size are scaled to it
  return camera;
}

geometry_msgs::Pose toPoseMsg(const std::array<double, 7>& pose)
{
  geometry_msgs::Pose out;
  out.position.x = pose[0];
  out.position.y = pose[1];
  out.position.z = pose[2];
  out.orientation.x = pose[3];
  out.orientation.y = pose[4];
  out.orientation.z = pose[5];
  out.orientation.w = pose[6];
  return out;
}

LoopClosurePtr makeLoopClosure(const std_msgs::Header& header, const openable::FrameOutcome& outcome)
{
  const openable::Detection& detection = outcome.detection;
  const openable::FrameInfo* match = outcome.has_match_info ? &outcome.match : nullptr;
  auto msg = boost::make_shared<LoopClosure>();
  msg->header = header;
  msg->status = openable::toString(outcome.status);
  msg->score = outcome.score;
  msg->query_id = uint32_t(outcome.query.id);
  msg->match_id = uint32_t(detection.best.id);
  if (match)
  {
    msg->match_stamp = ros::Time(std::max(0.0, match->stamp));
    msg->match_session = match->session;
  }
  msg->query_session = outcome.query.session;
  msg->distance = detection.best.distance;
  msg->uniqueness = detection.uniqueness;
  msg->relief = detection.relief;
  msg->sequence_length = detection.best.sequence_length;
  msg->direction = detection.best.direction;
  msg->shift = detection.best.shift;
  msg->has_poses = match && outcome.query.has_pose && match->has_pose;
  msg->query_pose.orientation.w = 1.0;
  msg->match_pose.orientation.w = 1.0;
  if (msg->has_poses)
  {
    msg->query_pose = toPoseMsg(outcome.query.pose);
    msg->match_pose = toPoseMsg(match->pose);
  }
  msg->has_relative_pose = outcome.verified;
  msg->relative_pose.pose.orientation.w = 1.0;
  if (outcome.verified)
  {
    const openable::Verification& v = outcome.verification;
    msg->relative_pose.pose.position.x = v.translation[0];
    msg->relative_pose.pose.position.y = v.translation[1];
    msg->relative_pose.pose.position.z = v.translation[2];
    const cv::Matx33d& r = v.rotation;
    tf2::Quaternion q;
    tf2::Matrix3x3(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)).getRotation(q);
    msg->relative_pose.pose.orientation.x = q.x();
    msg->relative_pose.pose.orientation.y = q.y();
    msg->relative_pose.pose.orientation.z = q.z();
    msg->relative_pose.pose.orientation.w = q.w();
    for (int row = 0; row < 6; ++row)
    {
      for (int col = 0; col < 6; ++col)
      {
        msg->relative_pose.covariance[size_t(row * 6 + col)] = v.covariance(row, col);
      }
    }
  }
  return msg;
}

}  // namespace openable_ros
