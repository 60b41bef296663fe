#pragma once

#include <geometry_msgs/Pose.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

#include <array>
#include <opencv2/core.hpp>
#include <string>

#include "openable/description/input_contract.h"
#include "openable/verification/geometric_verifier.h"
#include "openable/detection/online_detector.h"
#include "openable/map/place_database.h"
#include "openable_ros/LoopClosure.h"

namespace openable_ros
{
/// Encodings the detectors describe: 8-bit grey and colour, and mono16 (scaled to 8 bits). Depth and
/// float images (16UC1, 32FC1, ...) are not camera intensity and are refused.
bool isSupportedEncoding(const std::string& encoding);
const char* supportedEncodings();

/// A camera image as the core wants it: 8-bit grey (mono8) or 8-bit BGR, shared with the message when
/// possible (the result must not be modified). Returns false with `problem` set: its reason ("empty image",
/// "unsupported encoding", "image data too short", "cannot convert image": each counted and throttled on its
/// own) and what was wrong and expected. Never throws.
bool toCoreImage(const sensor_msgs::ImageConstPtr& msg, cv::Mat& image, openable::InputProblem& problem);

/// A stereo_msgs/DisparityImage's image (32FC1) as CV_32F, shared with the message. Returns false with
/// `problem` set ("unsupported disparity encoding", "malformed disparity"). Never throws.
bool toDisparity(const sensor_msgs::Image& msg, cv::Mat& disparity, openable::InputProblem& problem);

/// A rectified camera from CameraInfo.P (and, for a stereo pair, the right camera's P: baseline).
openable::PinholeCamera toPinholeCamera(const sensor_msgs::CameraInfo& left,
                                        const sensor_msgs::CameraInfo* right = nullptr);

geometry_msgs::Pose toPoseMsg(const std::array<double, 7>& pose);

/// One frame's outcome as a message: header of the query image, status and score, ids, stamps, sessions,
/// distance, uniqueness, direction, shift, the poses of both frames when both are known, and the verified
/// relative pose when verification accepted the loop.
LoopClosurePtr makeLoopClosure(const std_msgs::Header& header, const openable::FrameOutcome& outcome);

}  // namespace openable_ros
