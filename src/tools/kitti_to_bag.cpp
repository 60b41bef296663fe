// kitti_to_bag: a KITTI odometry sequence folder -> a rosbag ready for `rosbag play` beside the detector.
//
//   kitti_to_bag --sequence DIR --output FILE.bag [--poses FILE] [--stereo] [--color]
//                [--first N] [--last M] [--compression none|bz2|lz4] [--time-offset SEC] [--quiet]
//
// What it writes (doc/kitti.md has the full description):
//   /kitti/left/image_rect, /kitti/left/camera_info      sensor_msgs, frame camera_left
//   /kitti/right/image_rect, /kitti/right/camera_info    with --stereo, frame camera_right
//   /tf_static   camera_left -> camera_right             with --stereo (the rectified baseline)
//   /tf          odom -> camera_left                      with --poses
//   /kitti/odom  nav_msgs/Odometry odom -> camera_left   with --poses
// Stamps: time_offset + times.txt[frame] (default offset 1e9 s, so no stamp is the invalid zero time and
// stamp - 1e9 is the KITTI time). Frame k's stamp is line k of times.txt: a folder holding only the first
// images of a sequence (times.txt lists all frames) is fine; an image without a stamp is an error.
// ROS-free apart from the message types and rosbag; no master needed.

#include <cv_bridge/cv_bridge.h>
#include <dirent.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <boost/make_shared.hpp>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "openable/io/atomic_file.h"
#include "openable/io/kitti.h"
#include "progress.h"

namespace
{
const char* const kUsage =
    "usage: kitti_to_bag --sequence DIR --output FILE.bag [--poses FILE] [--stereo] [--color]\n"
    "                    [--first N] [--last M] [--compression none|bz2|lz4] [--time-offset SEC] [--quiet]\n"
    "  --sequence DIR     KITTI odometry sequence folder: calib.txt, times.txt, image_0/ (and image_1/ with\n"
    "                     --stereo), or image_2/ (and image_3/) with --color\n"
    "  --output FILE.bag  bag to write (replaced only when the conversion succeeds)\n"
    "  --poses FILE       KITTI poses (e.g. poses/07.txt): adds /tf odom->camera_left and /kitti/odom\n"
    "  --stereo           also the right camera\n"
    "  --color            colour cameras 2 and 3 (bgr8) instead of grey cameras 0 and 1 (mono8)\n"
    "  --first N --last M frame range, inclusive (default: every frame with an image)\n"
    "  --compression C    bag chunk compression: none (default), bz2, lz4\n"
    "  --time-offset SEC  added to times.txt (default 1000000000: valid, non-zero ROS times)\n"
    "  --quiet            no progress (frames done, frames/s, time left) and no summary on stderr\n";

class UsageError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

struct Options
{
  std::string sequence;
  std::string output;
  std::string poses;
  bool stereo = false;
  bool color = false;
  long first = -1;
  long last = -1;
  std::string compression = "none";
  double time_offset = 1e9;
  bool quiet = false;
};

long parseLong(const std::string& flag, const std::string& text)
{
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (errno != 0 || end == text.c_str() || *end != '\0' || value < 0)
    throw UsageError(flag + ": '" + text + "' is not a frame index (expected an integer >= 0)");
  return value;
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string
    {
      if (i + 1 >= argc)
        throw UsageError(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--sequence")
      o.sequence = value();
    else if (arg == "--output")
      o.output = value();
    else if (arg == "--poses")
      o.poses = value();
    else if (arg == "--stereo")
      o.stereo = true;
    else if (arg == "--color" || arg == "--colour")
      o.color = true;
    else if (arg == "--first")
      o.first = parseLong(arg, value());
    else if (arg == "--last")
      o.last = parseLong(arg, value());
    else if (arg == "--compression")
      o.compression = value();
    else if (arg == "--time-offset")
    {
      const std::string text = value();
      char* end = nullptr;
      o.time_offset = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(o.time_offset >= 0.0) || o.time_offset > 4e9)
        throw UsageError("--time-offset: '" + text + "', expected seconds in [0, 4e9]");
    }
    else if (arg == "--quiet")
      o.quiet = true;
    else if (arg == "-h" || arg == "--help")
      throw UsageError("");
    else
      throw UsageError("unknown argument '" + arg + "'");
  }
  if (o.sequence.empty() || o.output.empty())
    throw UsageError("--sequence and --output are required");
  if (o.compression != "none" && o.compression != "bz2" && o.compression != "lz4")
    throw UsageError("--compression: '" + o.compression + "', expected none, bz2 or lz4");
  if (o.first >= 0 && o.last >= 0 && o.last < o.first)
    throw UsageError("--last " + std::to_string(o.last) + " is before --first " + std::to_string(o.first));
  return o;
}

bool isDirectory(const std::string& path)
{
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool isFile(const std::string& path)
{
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Frame index -> file name of every NNNNNN.png in a KITTI image folder.
using Projection = openable::KittiMatrix;

/// A KITTI pose or offset as an Eigen transform.
Eigen::Isometry3d toIsometry(const Projection& pose)
{
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
      t.linear()(r, c) = pose[size_t(4 * r + c)];
    t.translation()(r) = pose[size_t(4 * r + 3)];
  }
  return t;
}

sensor_msgs::CameraInfo cameraInfo(const Projection& p, double tx_metres, const cv::Size& size,
                                   const std::string& frame)
{
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame;
  info.width = static_cast<uint32_t>(size.width);
  info.height = static_cast<uint32_t>(size.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);  // rectified images: no distortion left
  info.K = {p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  // P = K [I | (Tx, 0, 0)] with Tx = -fx * baseline for the right camera, 0 for the left (REP: the
  // projection of a point in the left camera's frame).
  info.P = {p[0], p[1], p[2], p[0] * tx_metres, p[4], p[5], p[6], 0.0, p[8], p[9], p[10], 0.0};
  return info;
}

sensor_msgs::ImagePtr toImage(const cv::Mat& image, const std::string& frame)
{
  std_msgs::Header header;
  header.frame_id = frame;
  return cv_bridge::CvImage(header, image.channels() == 1 ? "mono8" : "bgr8", image).toImageMsg();
}

ros::Time stampOf(double seconds)
{
  // Exact to the nanosecond from the decimal text (times.txt has microseconds): round, do not truncate.
  const int64_t ns = static_cast<int64_t>(std::llround(seconds * 1e9));
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(ns));
  return t;
}

// The bag is written beside --output under this name and renamed over it only when complete (fsynced), so a
// failed or killed run leaves an existing bag as it was; temporaries of killed runs go at the next run.
std::string temporaryBagPath(const std::string& output)
{
  static const std::string path = openable::temporaryPath(output);
  return path;
}

int run(const Options& o, bool& bag_opened)
{
  // ---- Check the folder before writing anything: say everything that is missing at once.
  const std::string dir = o.sequence.back() == '/' ? o.sequence : o.sequence + "/";
  if (!isDirectory(dir))
    throw std::runtime_error("--sequence " + o.sequence + " is not a directory");
  const std::string left_dir = o.color ? "image_2" : "image_0";
  const std::string right_dir = o.color ? "image_3" : "image_1";
  std::vector<std::string> missing;
  if (!isFile(dir + "calib.txt"))
    missing.push_back("calib.txt (projection matrices P0..P3)");
  if (!isFile(dir + "times.txt"))
    missing.push_back("times.txt (one timestamp per frame)");
  if (!isDirectory(dir + left_dir))
    missing.push_back(left_dir + "/ (" + std::string(o.color ? "left colour" : "left grey") + " images" +
                      (o.color ? ")" : "; use --color for image_2/image_3)"));
  if (o.stereo && !isDirectory(dir + right_dir))
    missing.push_back(right_dir + "/ (right images, needed by --stereo)");
  if (!missing.empty())
  {
    std::string text = o.sequence + " is not a KITTI odometry sequence folder; missing:";
    for (const auto& m : missing)
      text += "\n  " + m;
    throw std::runtime_error(text);
  }

  const auto calibration = openable::readKittiCalibration(dir + "calib.txt");
  const std::string left_key = o.color ? "P2" : "P0";
  const std::string right_key = o.color ? "P3" : "P1";
  for (const auto& key : {left_key, right_key})
    if (!calibration.count(key) && (key == left_key || o.stereo))
      throw std::runtime_error(dir + "calib.txt has no " + key +
                               " (expected lines 'P0: ...' to 'P3: ...' with 12 numbers)");

  const auto times = openable::readKittiTimes(dir + "times.txt", o.time_offset);
  const auto left_images = openable::listKittiImages(dir + left_dir);
  if (left_images.empty())
    throw std::runtime_error(dir + left_dir + "/ has no NNNNNN.png images");
  // Frame indices must be contiguous from the first one found.
  const long first_index = left_images.begin()->first;
  const long last_index = left_images.rbegin()->first;
  if (static_cast<long>(left_images.size()) != last_index - first_index + 1)
  {
    long gap = first_index;
    while (left_images.count(gap))
      ++gap;
    throw std::runtime_error(dir + left_dir + "/ has " + std::to_string(left_images.size()) + " images numbered " +
                             std::to_string(first_index) + ".." + std::to_string(last_index) +
                             " with gaps (first missing: " + std::to_string(gap) + ")");
  }
  if (static_cast<long>(times.size()) <= last_index)
    throw std::runtime_error("image/time count mismatch: " + left_dir + "/ has images up to frame " +
                             std::to_string(last_index) + " but times.txt has only " + std::to_string(times.size()) +
                             " stamps (frames 0.." + std::to_string(static_cast<long>(times.size()) - 1) + ")");
  if (static_cast<long>(times.size()) != last_index + 1)
    std::cerr << "kitti_to_bag: note: times.txt has " << times.size() << " stamps, " << left_dir << "/ has "
              << left_images.size() << " images (frames " << first_index << ".." << last_index
              << "): converting the frames that have images, with their own stamps\n";
  std::map<long, std::string> right_images;
  if (o.stereo)
  {
    right_images = openable::listKittiImages(dir + right_dir);
    for (const auto& entry : left_images)
      if (!right_images.count(entry.first))
        throw std::runtime_error("stereo: " + dir + right_dir + "/" + entry.second + " is missing (" + left_dir +
                                 "/ and " + right_dir + "/ must hold the same frames)");
  }

  const long first = o.first >= 0 ? o.first : first_index;
  const long last = o.last >= 0 ? o.last : last_index;
  if (first < first_index || last > last_index)
    throw std::runtime_error("frame range " + std::to_string(first) + ".." + std::to_string(last) +
                             " is outside the images " + std::to_string(first_index) + ".." +
                             std::to_string(last_index));
  if (last < first)
    throw std::runtime_error("empty frame range " + std::to_string(first) + ".." + std::to_string(last));

  std::vector<Projection> poses;
  std::vector<int> pose_lines;
  if (!o.poses.empty())
  {
    openable::KittiPoses read = openable::readKittiPoses(o.poses);
    poses = std::move(read.poses);
    pose_lines = std::move(read.lines);
    if (static_cast<long>(poses.size()) <= last)
      throw std::runtime_error("pose/frame count mismatch: " + o.poses + " has " + std::to_string(poses.size()) +
                               " poses, frame " + std::to_string(last) + " needs at least " + std::to_string(last + 1));
  }

  // ---- Geometry. KITTI poses are camera-0 poses in the first camera-0 frame (optical: x right, y down,
  // z forward). `odom` is a ROS body frame (x forward, y left, z up) at the first camera-0 pose, so the
  // trajectory lies in rviz's ground plane; `camera_left` is the optical frame of the left camera used
  // (camera 0, or camera 2 with --color, offset from camera 0 by its P).
  Eigen::Isometry3d odom_T_cam0start = Eigen::Isometry3d::Identity();
  odom_T_cam0start.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Projection& p_left = calibration.at(left_key);
  const auto offset_left = openable::kittiProjectionOffset(p_left);  // p_camL = p_cam0 + offset
  Eigen::Isometry3d cam0_T_left = Eigen::Isometry3d::Identity();
  cam0_T_left.translation() = -Eigen::Vector3d(offset_left[0], offset_left[1], offset_left[2]);
  double baseline = 0.0;
  if (o.stereo)
  {
    const auto offset_right = openable::kittiProjectionOffset(calibration.at(right_key));
    baseline = offset_left[0] - offset_right[0];
    if (!(baseline > 0.0))
      throw std::runtime_error("calib.txt: " + right_key + " is not to the right of " + left_key + " (baseline " +
                               std::to_string(baseline) + " m, expected > 0)");
  }

  // ---- Write.
  rosbag::Bag bag;
  try
  {
    bag_opened = true;  // from here on a partial temporary file may exist
    bag.open(temporaryBagPath(o.output), rosbag::bagmode::Write);
  }
  catch (const rosbag::BagException& e)
  {
    throw std::runtime_error("cannot write " + o.output + ": " + e.what());
  }
  bag.setCompression(o.compression == "bz2"   ? rosbag::compression::BZ2
                     : o.compression == "lz4" ? rosbag::compression::LZ4
                                              : rosbag::compression::Uncompressed);
  const std::string left_frame = "camera_left", right_frame = "camera_right";
  cv::Size size;
  std::string size_source;
  const long count = last - first + 1;
  long written = 0;
  // A whole sequence takes minutes: one updating line on a terminal, a line every few seconds in a log.
  openable::Progress progress("kitti_to_bag", static_cast<size_t>(count), o.quiet);
  for (long k = first; k <= last; ++k)
  {
    const ros::Time stamp = stampOf(o.time_offset + times[k]);
    const std::string left_path = dir + left_dir + "/" + left_images.at(k);
    const cv::Mat left = cv::imread(left_path, o.color ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
    if (left.empty())
      throw std::runtime_error("cannot read image " + left_path);
    if (size_source.empty())
    {
      size = left.size();
      size_source = left_path;
    }
    if (left.size() != size)
      throw std::runtime_error("images of mixed sizes: " + left_path + " is " + std::to_string(left.cols) + "x" +
                               std::to_string(left.rows) + ", " + size_source + " is " + std::to_string(size.width) +
                               "x" + std::to_string(size.height) + " (one sequence has one camera size)");
    auto left_msg = toImage(left, left_frame);
    left_msg->header.stamp = stamp;
    left_msg->header.seq = static_cast<uint32_t>(k);
    auto left_info = cameraInfo(p_left, 0.0, size, left_frame);
    left_info.header = left_msg->header;
    bag.write("/kitti/left/image_rect", stamp, *left_msg);
    bag.write("/kitti/left/camera_info", stamp, left_info);

    if (o.stereo)
    {
      const std::string right_path = dir + right_dir + "/" + right_images.at(k);
      const cv::Mat right = cv::imread(right_path, o.color ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
      if (right.empty())
        throw std::runtime_error("cannot read image " + right_path);
      if (right.size() != size)
        throw std::runtime_error("images of mixed sizes: " + right_path + " is " + std::to_string(right.cols) + "x" +
                                 std::to_string(right.rows) + ", " + size_source + " is " + std::to_string(size.width) +
                                 "x" + std::to_string(size.height));
      auto right_msg = toImage(right, right_frame);
      right_msg->header.stamp = stamp;
      right_msg->header.seq = static_cast<uint32_t>(k);
      auto right_info = cameraInfo(calibration.at(right_key), -baseline, size, right_frame);
      right_info.header = right_msg->header;
      bag.write("/kitti/right/image_rect", stamp, *right_msg);
      bag.write("/kitti/right/camera_info", stamp, right_info);
      if (k == first)
      {
        tf2_msgs::TFMessage tf_static;
        geometry_msgs::TransformStamped t;
        t.header.stamp = stamp;
        t.header.frame_id = left_frame;
        t.child_frame_id = right_frame;
        t.transform.translation.x = baseline;
        t.transform.rotation.w = 1.0;
        tf_static.transforms.push_back(t);
        // Recorded as latched, as a live /tf_static is: `rosbag play` then latches it too, so nodes that
        // start after the first frame still get camera_left -> camera_right.
        auto header = boost::make_shared<ros::M_string>();
        (*header)["type"] = ros::message_traits::datatype(tf_static);
        (*header)["md5sum"] = ros::message_traits::md5sum(tf_static);
        (*header)["message_definition"] = ros::message_traits::definition(tf_static);
        (*header)["callerid"] = "/kitti_to_bag";
        (*header)["latching"] = "1";
        bag.write("/tf_static", stamp, tf_static, header);
      }
    }

    if (!poses.empty())
    {
      const Eigen::Isometry3d odom_T_left = odom_T_cam0start * toIsometry(poses[k]) * cam0_T_left;
      const Eigen::Quaterniond rotation(odom_T_left.rotation());
      geometry_msgs::TransformStamped t;
      t.header.stamp = stamp;
      t.header.frame_id = "odom";
      t.child_frame_id = left_frame;
      t.transform.translation.x = odom_T_left.translation().x();
      t.transform.translation.y = odom_T_left.translation().y();
      t.transform.translation.z = odom_T_left.translation().z();
      t.transform.rotation.x = rotation.x();
      t.transform.rotation.y = rotation.y();
      t.transform.rotation.z = rotation.z();
      t.transform.rotation.w = rotation.w();
      // Checked poses give finite transforms unless their numbers are near the double range.
      const auto& q = t.transform.rotation;
      if (!std::isfinite(odom_T_left.translation().sum() + q.x + q.y + q.z + q.w))
        throw std::runtime_error(o.poses + ":" + std::to_string(pose_lines[k]) + ": the pose of frame " +
                                 std::to_string(k) + " gives a non-finite transform (numbers too large?)");
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(t);
      bag.write("/tf", stamp, tf);
      nav_msgs::Odometry odom;
      odom.header = t.header;
      odom.header.seq = static_cast<uint32_t>(k);
      odom.child_frame_id = left_frame;
      odom.pose.pose.position.x = t.transform.translation.x;
      odom.pose.pose.position.y = t.transform.translation.y;
      odom.pose.pose.position.z = t.transform.translation.z;
      odom.pose.pose.orientation = t.transform.rotation;
      bag.write("/kitti/odom", stamp, odom);
    }

    ++written;
    progress.update(static_cast<size_t>(written));
  }
  progress.finish();
  bag.close();
  openable::publishFile(temporaryBagPath(o.output), o.output);
  if (!o.quiet)
    std::cerr << "kitti_to_bag: wrote " << o.output << ": " << written << (o.stereo ? " stereo" : " mono") << " frames "
              << first << ".." << last << ", " << size.width << "x" << size.height << (o.color ? " bgr8" : " mono8")
              << (poses.empty() ? "" : ", /tf and /kitti/odom from " + o.poses) << "\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    options = parseArguments(argc, argv);
  }
  catch (const UsageError& e)
  {
    if (*e.what())
      std::cerr << "kitti_to_bag: " << e.what() << "\n";
    std::cerr << kUsage;
    return std::string(e.what()).empty() ? 0 : 2;
  }
  bool bag_opened = false;
  try
  {
    ros::Time::init();
    return run(options, bag_opened);
  }
  catch (const std::exception& e)
  {
    std::cerr << "kitti_to_bag: error: " << e.what() << "\n";
    if (bag_opened)
      std::remove(temporaryBagPath(options.output).c_str());  // no half-written bag; --output untouched
    return 1;
  }
}
