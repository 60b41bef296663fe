// Writes the seed corpus of fuzz_place_messages and fuzz_detector_image (formats in fuzz_entries.h) from
// real frames of data/sample (Gardens Point, QUT): real descriptors, small real images. Built with the fuzz
// targets (`make fuzz`); run once by hand when a format changes:
//   build/fuzz/build/write_seeds . test/fuzz/corpus
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "fuzz_entries.h"
#include "openable/description/frame_describer.h"
#include "openable/map/session_map.h"

using openable_fuzz::ByteWriter;

namespace
{
std::string root;

cv::Mat frame(const std::string& traversal, int index, cv::Size size, bool colour)
{
  char name[32];
  std::snprintf(name, sizeof(name), "/Image%03d.jpg", index);
  const cv::Mat full = cv::imread(root + "/data/sample/" + traversal + name, colour ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
  if (full.empty())
    throw std::runtime_error("cannot read " + traversal + name);
  cv::Mat small;
  cv::resize(full, small, size, 0, 0, cv::INTER_AREA);
  return small;
}

void save(const std::string& path, const ByteWriter& w)
{
  std::ofstream(path, std::ios::binary) << w.bytes();
  std::cout << path << ": " << w.bytes().size() << " bytes\n";
}

void pose(ByteWriter& w, double x, double qz = 0.0, double qw = 1.0)
{
  for (double v : {x, 0.0, 0.0, 0.0, 0.0, qz, qw})
    w.f64(v);
}

// kind bits: 1 candidates, 2 right hash, 4 right length, 8 pose, 16 topic robot
void descriptor(ByteWriter& w, const openable::FrameDescriber& describer, const std::string& robot,
                const std::string& traversal, int index, uint64_t frame_id, double stamp, bool with_pose = true)
{
  w.u8(uint8_t(2 | 4 | (with_pose ? 8 : 0) | 16));
  w.str(robot);
  w.str(robot);
  w.str(robot);
  w.u64(frame_id);
  w.f64(stamp);
  for (uint64_t word : describer.describeImage(frame(traversal, index, cv::Size(320, 180), true)))
    w.u64(word);
  if (with_pose)
    pose(w, double(index));
}

void imageFrame(ByteWriter& w, const cv::Mat& image, double stamp, bool has_pose, double x = 0.0,
                uint8_t disparity = 3)
{
  w.u16(uint16_t(image.cols));
  w.u16(uint16_t(image.rows));
  w.u8(image.channels() == 3 ? 1 : 0);
  w.f64(stamp);
  w.u8(has_pose ? 1 : 0);
  if (has_pose)
    pose(w, x);
  w.u8(disparity);
  const size_t n = image.total() * image.elemSize();
  w.u32(uint32_t(n));
  w.raw(image.data, n);
}
}  // namespace

int main(int argc, char** argv)
{
  if (argc != 3)
  {
    std::cerr << "usage: write_seeds REPOSITORY CORPUS_FOLDER\n";
    return 2;
  }
  root = argv[1];
  const std::string out = argv[2];
  const double nan = std::numeric_limits<double>::quiet_NaN();

  const openable::FrameDescriber describer(openable_fuzz::placeMessagesConfig());
  {
    // Two robots, real HOG-B descriptors of the same places (day and night), then another server's answer.
    ByteWriter w;
    w.u8(0);
    for (int i = 0; i < 5; ++i)
      descriptor(w, describer, "r1", "day_right", 10 + i, uint64_t(i), 100.0 + i);
    for (int i = 0; i < 5; ++i)
      descriptor(w, describer, "r2", "night_right", 10 + i, uint64_t(i), 200.0 + i);
    w.u8(1 | 8);  // candidates with a query pose
    w.str("other");
    w.str("r2");
    w.str("r2");
    w.u64(4);
    w.f64(204.0);
    w.u8(1);
    w.u64(4);
    w.u32(3);
    w.u8(0);
    w.u32(5);
    pose(w, 4.0);
    w.u8(2);
    for (int c = 0; c < 2; ++c)
    {
      w.str("r3");
      w.u64(uint64_t(c));
      w.f32(0.2f + 0.1f * float(c));
      w.u8(1);
      w.u16(0);
      w.u16(3);
      w.f64(50.0 + c);
      w.u8(1);
      pose(w, double(c));
    }
    save(out + "/place_messages/seed_two_robots_real_descriptors", w);
  }
  {
    // What the contract refuses, on real descriptors: the same message twice, stamp 0, a NaN pose, a
    // zero quaternion, another robot's name on r1's topic, a wrong hash.
    ByteWriter w;
    w.u8(1);  // owns r1 only
    descriptor(w, describer, "r1", "day_right", 20, 0, 10.0);
    descriptor(w, describer, "r1", "day_right", 20, 0, 10.0);
    descriptor(w, describer, "r1", "day_right", 21, 1, 0.0);
    w.u8(2 | 4 | 8);
    w.str("r1");
    w.str("r1");
    w.u64(2);
    w.f64(12.0);
    for (uint64_t word : describer.describeImage(frame("day_right", 22, cv::Size(320, 180), true)))
      w.u64(word);
    for (double v : {nan, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0})
      w.f64(v);
    descriptor(w, describer, "r1", "day_right", 23, 3, 13.0, false);
    w.u8(4 | 16);  // wrong hash, topic robot r2
    w.str("r1");
    w.str("r1");
    w.str("r2");
    w.u64(4);
    w.f64(14.0);
    w.u64(12345);
    for (uint64_t word : describer.describeImage(frame("day_right", 24, cv::Size(320, 180), true)))
      w.u64(word);
    save(out + "/place_messages/seed_refusals_real_descriptors", w);
  }
  {
    // Mono HOG-B, real 64x36 grey frames, stamped, with poses: the last ones reach matching.
    ByteWriter w;
    w.u8(0);
    w.u8(1);
    for (int i = 0; i < 6; ++i)
      imageFrame(w, frame("day_right", 10 + i, cv::Size(64, 36), false), 1.0 + i, true, double(i));
    save(out + "/detector_image/seed_mono_real_64x36", w);
  }
  {
    // LDB grid with illumination invariance: real colour frames (it needs colour), no poses.
    ByteWriter w;
    w.u8(1);
    w.u8(0);
    for (int i = 0; i < 5; ++i)
      imageFrame(w, frame("night_right", 30 + i, cv::Size(64, 36), true), 1.0 + i, false);
    save(out + "/detector_image/seed_grid_colour_real_64x36", w);
  }
  {
    // Stereo D-LDB: the left image real, the disparity a ramp.
    ByteWriter w;
    w.u8(2);
    w.u8(1);
    for (int i = 0; i < 4; ++i)
      imageFrame(w, frame("day_right", 40 + i, cv::Size(64, 36), false), 1.0 + i, true, double(i), 3);
    save(out + "/detector_image/seed_stereo_real_ramp_disparity", w);
  }
  {
    // What the contract refuses between two good frames: a 1x1 image, a 1000x1 strip, a black frame,
    // stamp 0, a NaN pose.
    ByteWriter w;
    w.u8(0);
    w.u8(1 | 2);
    imageFrame(w, frame("day_right", 50, cv::Size(64, 36), false), 5.0, true, 0.0);
    imageFrame(w, frame("day_right", 51, cv::Size(1, 1), false), 6.0, false);
    imageFrame(w, frame("day_right", 52, cv::Size(1000, 1), false), 7.0, false);
    imageFrame(w, cv::Mat::zeros(36, 64, CV_8UC1), 8.0, false);
    imageFrame(w, frame("day_right", 53, cv::Size(64, 36), false), 0.0, false);
    w.u16(64);
    w.u16(36);
    w.u8(0);
    w.f64(9.0);
    w.u8(1);
    for (double v : {nan, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0})
      w.f64(v);
    w.u8(0);
    const cv::Mat last = frame("day_right", 54, cv::Size(64, 36), false);
    w.u32(uint32_t(last.total()));
    w.raw(last.data, last.total());
    imageFrame(w, frame("day_right", 55, cv::Size(64, 36), false), 10.0, false);  // and a good one again
    save(out + "/detector_image/seed_refusals_real", w);
  }
  return 0;
}
