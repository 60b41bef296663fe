#pragma once

#include <string>

#include "openable/verification/geometric_verifier.h"

namespace openable
{
/// The verifier's camera from a calibration file, so that the offline tool verifies as a nodelet that
/// receives camera_info does. Two formats, told apart by their content:
/// - a ROS camera_info YAML as camera_calibration / camera_info_manager write it (`image_width`,
///   `image_height`, `camera_matrix`, `projection_matrix`, each matrix `{rows, cols, data: [...]}`). The
///   projection matrix is used when present (the images are rectified, `image_rect`), else the camera
///   matrix. One file is one camera: the result is mono.
/// - a KITTI odometry calib.txt (`P0: 12 numbers` per line, read by readKittiCalibration): P0 is the left
///   camera; with P1 the rig is stereo, baseline -P1(0,3) / fx. KITTI files carry no image size.
/// Throws Error with one line naming the file and the offending key.
PinholeCamera readCameraCalibration(const std::string& path);

/// A ROS camera_info YAML from its text; `name` is used in the error messages.
PinholeCamera parseCameraCalibration(const std::string& text, const std::string& name);

}  // namespace openable
