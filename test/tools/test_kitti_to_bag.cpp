// kitti_to_bag end to end: the real KITTI 07 files (first 160 frames) -> bag, read back with the rosbag
// API; broken folders give clear errors. No master needed.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sys/wait.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <boost/foreach.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "run_tool.h"

namespace fs = std::filesystem;

namespace
{
const std::string kSequence = std::string(OPENABLE_SOURCE_DIR) + "/../shared/data/kitti/07_first160";
const std::string kPoses06 = std::string(OPENABLE_SOURCE_DIR) + "/../shared/data/kitti/poses/06.txt";

struct ToolRun
{
  int status = -1;
  std::string output;  // stdout + stderr
};

ToolRun run(const std::string& arguments)
{
  const openable_test::Result r = openable_test::runTool(KITTI_TO_BAG_BINARY, arguments);
  return ToolRun{r.exit_code, r.output};
}

std::vector<double> readTimes(const std::string& path)
{
  std::ifstream in(path);
  std::vector<double> times;
  double t;
  while (in >> t)
    times.push_back(t);
  return times;
}

ros::Time expectedStamp(double kitti_seconds)
{
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(std::llround((1e9 + kitti_seconds) * 1e9)));
  return t;
}

class KittiToBag : public ::testing::Test
{
protected:
  void SetUp() override
  {
    char pattern[] = "/tmp/openable_kitti_to_bag_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override
  {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  // A KITTI-looking folder built from links to the real files.
  std::string fixture(const std::string& name, bool calib, bool times, bool image_0, bool image_1 = false)
  {
    const fs::path d = fs::path(dir_) / name;
    fs::create_directories(d);
    if (calib)
      fs::create_symlink(kSequence + "/calib.txt", d / "calib.txt");
    if (times)
      fs::create_symlink(kSequence + "/times.txt", d / "times.txt");
    if (image_0)
      fs::create_directory_symlink(kSequence + "/image_0", d / "image_0");
    if (image_1)  // the left images again: enough to test the stereo plumbing
      fs::create_directory_symlink(kSequence + "/image_0", d / "image_1");
    return d.string();
  }
  std::string dir_;
};

TEST_F(KittiToBag, Kitti07First160MonoHas160ImagesWithStampsAndCameraInfo)
{
  const std::string bag_path = dir_ + "/07.bag";
  const ToolRun r = run("--sequence " + kSequence + " --output " + bag_path);
  ASSERT_EQ(r.status, 0) << r.output;
  // times.txt lists all 1101 frames of 07, the folder holds 160 images: converted, with a note.
  EXPECT_NE(r.output.find("times.txt has 1101 stamps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("160/160 frames (100%)"), std::string::npos) << r.output;

  const auto times = readTimes(kSequence + "/times.txt");
  ASSERT_EQ(times.size(), 1101u);
  const cv::Mat first = cv::imread(kSequence + "/image_0/000000.png", cv::IMREAD_GRAYSCALE);
  const cv::Mat last = cv::imread(kSequence + "/image_0/000159.png", cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(first.size(), cv::Size(1226, 370));

  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View everything(bag);
  EXPECT_EQ(everything.size(), 320u);  // 160 images + 160 camera_info, nothing else without --poses
  size_t images = 0;
  rosbag::View image_view(bag, rosbag::TopicQuery("/kitti/left/image_rect"));
  for (const rosbag::MessageInstance& m : image_view)
  {
    const auto image = m.instantiate<sensor_msgs::Image>();
    ASSERT_TRUE(image);
    EXPECT_EQ(image->header.stamp, expectedStamp(times[images])) << images;
    EXPECT_EQ(m.getTime(), image->header.stamp);
    EXPECT_EQ(image->header.seq, images);
    EXPECT_EQ(image->header.frame_id, "camera_left");
    EXPECT_EQ(image->encoding, "mono8");
    EXPECT_EQ(image->width, 1226u);
    EXPECT_EQ(image->height, 370u);
    EXPECT_EQ(image->step, 1226u);
    if (images == 0 || images == 159)
    {
      const cv::Mat& expected = images == 0 ? first : last;
      ASSERT_EQ(image->data.size(), expected.total());
      EXPECT_TRUE(std::equal(image->data.begin(), image->data.end(), expected.data)) << images;
    }
    ++images;
  }
  EXPECT_EQ(images, 160u);
  // Spot values: frame 1 is at 0.1038752 s, frame 159 at 16.51632 s of KITTI time.
  EXPECT_NEAR(times[1], 0.1038752, 1e-9);

  size_t infos = 0;
  rosbag::View info_view(bag, rosbag::TopicQuery("/kitti/left/camera_info"));
  for (const rosbag::MessageInstance& m : info_view)
  {
    const auto info = m.instantiate<sensor_msgs::CameraInfo>();
    ASSERT_TRUE(info);
    EXPECT_EQ(info->header.stamp, expectedStamp(times[infos]));
    EXPECT_EQ(info->header.frame_id, "camera_left");
    EXPECT_EQ(info->width, 1226u);
    EXPECT_EQ(info->height, 370u);
    EXPECT_DOUBLE_EQ(info->K[0], 707.0912);
    EXPECT_DOUBLE_EQ(info->K[2], 601.8873);
    EXPECT_DOUBLE_EQ(info->K[4], 707.0912);
    EXPECT_DOUBLE_EQ(info->K[5], 183.1104);
    EXPECT_DOUBLE_EQ(info->P[0], 707.0912);
    EXPECT_DOUBLE_EQ(info->P[3], 0.0);
    EXPECT_EQ(info->distortion_model, "plumb_bob");
    ++infos;
  }
  EXPECT_EQ(infos, 160u);
  // Quoted in doc/kitti.md; test/docs/check_doc_numbers.py compares the docs with these.
  RecordProperty("images", int(images));
  RecordProperty("camera_infos", int(infos));
  EXPECT_EQ(bag.getSize() > 160u * 1226u * 370u, true);
}

TEST_F(KittiToBag, StereoPosesRangeAndCompression)
{
  // 06's first poses stand in for 07's (not available here): this checks the plumbing, not the data.
  const std::string poses = dir_ + "/poses.txt";
  {
    std::ifstream in(kPoses06);
    std::ofstream out(poses);
    std::string line;
    for (int i = 0; i < 160 && std::getline(in, line); ++i)
      out << line << "\n";
  }
  const std::string sequence = fixture("stereo", true, true, true, true);
  const std::string bag_path = dir_ + "/stereo.bag";
  const ToolRun r = run("--sequence " + sequence + " --output " + bag_path + " --stereo --poses " + poses +
                        " --first 10 --last 19 --compression lz4");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto times = readTimes(kSequence + "/times.txt");

  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  const auto count = [&bag](const std::string& topic) { return rosbag::View(bag, rosbag::TopicQuery(topic)).size(); };
  EXPECT_EQ(count("/kitti/left/image_rect"), 10u);
  EXPECT_EQ(count("/kitti/right/image_rect"), 10u);
  EXPECT_EQ(count("/kitti/right/camera_info"), 10u);
  EXPECT_EQ(count("/tf"), 10u);
  EXPECT_EQ(count("/tf_static"), 1u);
  EXPECT_EQ(count("/kitti/odom"), 10u);

  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/kitti/right/camera_info")))
  {
    const auto info = m.instantiate<sensor_msgs::CameraInfo>();
    ASSERT_TRUE(info);
    EXPECT_EQ(info->header.frame_id, "camera_right");
    EXPECT_NEAR(info->P[3], -379.8145, 1e-9);  // KITTI P1: Tx = -fx * baseline
    break;
  }
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/tf_static")))
  {
    const auto tf = m.instantiate<tf2_msgs::TFMessage>();
    ASSERT_TRUE(tf);
    ASSERT_TRUE(m.getConnectionHeader());
    EXPECT_EQ(m.getConnectionHeader()->at("latching"), "1");  // rosbag play re-latches it
    ASSERT_EQ(tf->transforms.size(), 1u);
    EXPECT_EQ(tf->transforms[0].header.frame_id, "camera_left");
    EXPECT_EQ(tf->transforms[0].child_frame_id, "camera_right");
    EXPECT_NEAR(tf->transforms[0].transform.translation.x, 379.8145 / 707.0912, 1e-12);
  }
  // Frame 10's odometry: the KITTI camera-0 position (x right, y down, z forward) in the ROS odom frame
  // (x forward, y left, z up) is (z, -x, -y); the camera's optical axis (KITTI +z) is odom's R * (0 0 1).
  std::ifstream in(poses);
  std::string line;
  for (int i = 0; i <= 10; ++i)
    std::getline(in, line);
  std::istringstream fields(line);
  double p[12];
  for (double& v : p)
    fields >> v;
  bool first = true;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery("/kitti/odom")))
  {
    const auto odom = m.instantiate<nav_msgs::Odometry>();
    ASSERT_TRUE(odom);
    EXPECT_EQ(odom->header.frame_id, "odom");
    EXPECT_EQ(odom->child_frame_id, "camera_left");
    if (!first)
      continue;
    first = false;
    EXPECT_EQ(odom->header.stamp, expectedStamp(times[10]));
    EXPECT_NEAR(odom->pose.pose.position.x, p[11], 1e-9);
    EXPECT_NEAR(odom->pose.pose.position.y, -p[3], 1e-9);
    EXPECT_NEAR(odom->pose.pose.position.z, -p[7], 1e-9);
    // Optical axis: rotate (0 0 1) by the quaternion and compare with body_from_optical * (r02 r12 r22).
    const auto& q = odom->pose.pose.orientation;
    const double zx = 2 * (q.x * q.z + q.w * q.y), zy = 2 * (q.y * q.z - q.w * q.x),
                 zz = 1 - 2 * (q.x * q.x + q.y * q.y);
    // KITTI's rotations are printed with 7 digits, not exactly orthonormal: 1e-6, not 1e-9.
    EXPECT_NEAR(zx, p[10], 1e-6);
    EXPECT_NEAR(zy, -p[2], 1e-6);
    EXPECT_NEAR(zz, -p[6], 1e-6);
  }
}

TEST_F(KittiToBag, NotAKittiFolderSaysWhatIsMissing)
{
  const ToolRun empty = run("--sequence " + fixture("empty", false, false, false) + " --output " + dir_ + "/x.bag");
  EXPECT_EQ(empty.status, 1);
  EXPECT_NE(empty.output.find("is not a KITTI odometry sequence folder; missing:"), std::string::npos) << empty.output;
  EXPECT_NE(empty.output.find("calib.txt"), std::string::npos);
  EXPECT_NE(empty.output.find("times.txt"), std::string::npos);
  EXPECT_NE(empty.output.find("image_0/"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ + "/x.bag"));

  const ToolRun no_times = run("--sequence " + fixture("no_times", true, false, true) + " --output " + dir_ + "/x.bag");
  EXPECT_EQ(no_times.status, 1);
  EXPECT_NE(no_times.output.find("times.txt"), std::string::npos) << no_times.output;
  EXPECT_EQ(no_times.output.find("calib.txt"), std::string::npos) << no_times.output;

  const ToolRun no_calib = run("--sequence " + fixture("no_calib", false, true, true) + " --output " + dir_ + "/x.bag");
  EXPECT_EQ(no_calib.status, 1);
  EXPECT_NE(no_calib.output.find("calib.txt (projection matrices"), std::string::npos) << no_calib.output;

  const ToolRun no_right =
      run("--sequence " + fixture("mono_only", true, true, true) + " --output " + dir_ + "/x.bag --stereo");
  EXPECT_EQ(no_right.status, 1);
  EXPECT_NE(no_right.output.find("image_1/ (right images, needed by --stereo)"), std::string::npos) << no_right.output;

  const ToolRun colour =
      run("--sequence " + fixture("grey_only", true, true, true) + " --output " + dir_ + "/x.bag --color");
  EXPECT_EQ(colour.status, 1);
  EXPECT_NE(colour.output.find("image_2/"), std::string::npos) << colour.output;
}

TEST_F(KittiToBag, TimeCountMismatchAndMixedSizesAreErrors)
{
  // Fewer stamps than images.
  const fs::path short_times = fs::path(dir_) / "short_times";
  fs::create_directories(short_times);
  fs::create_symlink(kSequence + "/calib.txt", short_times / "calib.txt");
  fs::create_directory_symlink(kSequence + "/image_0", short_times / "image_0");
  {
    std::ifstream in(kSequence + "/times.txt");
    std::ofstream out(short_times / "times.txt");
    std::string line;
    for (int i = 0; i < 100 && std::getline(in, line); ++i)
      out << line << "\n";
  }
  const ToolRun mismatch = run("--sequence " + short_times.string() + " --output " + dir_ + "/x.bag");
  EXPECT_EQ(mismatch.status, 1);
  EXPECT_NE(mismatch.output.find("image/time count mismatch"), std::string::npos) << mismatch.output;
  EXPECT_NE(mismatch.output.find("only 100 stamps"), std::string::npos) << mismatch.output;

  // Three images, the middle one of another size.
  const fs::path mixed = fs::path(dir_) / "mixed";
  fs::create_directories(mixed / "image_0");
  fs::create_symlink(kSequence + "/calib.txt", mixed / "calib.txt");
  fs::create_symlink(kSequence + "/times.txt", mixed / "times.txt");
  const cv::Mat image = cv::imread(kSequence + "/image_0/000000.png", cv::IMREAD_GRAYSCALE);
  cv::Mat small;
  cv::resize(image, small, cv::Size(613, 185));
  cv::imwrite((mixed / "image_0" / "000000.png").string(), image);
  cv::imwrite((mixed / "image_0" / "000001.png").string(), small);
  cv::imwrite((mixed / "image_0" / "000002.png").string(), image);
  const ToolRun sizes = run("--sequence " + mixed.string() + " --output " + dir_ + "/mixed.bag");
  EXPECT_EQ(sizes.status, 1);
  EXPECT_NE(sizes.output.find("images of mixed sizes"), std::string::npos) << sizes.output;
  EXPECT_NE(sizes.output.find("000001.png is 613x185"), std::string::npos) << sizes.output;
  EXPECT_FALSE(fs::exists(dir_ + "/mixed.bag"));  // no half-written bag left behind

  // A gap in the numbering.
  fs::remove(mixed / "image_0" / "000001.png");
  const ToolRun gap = run("--sequence " + mixed.string() + " --output " + dir_ + "/gap.bag");
  EXPECT_EQ(gap.status, 1);
  EXPECT_NE(gap.output.find("with gaps (first missing: 1)"), std::string::npos) << gap.output;
}

TEST_F(KittiToBag, BadArguments)
{
  const ToolRun unknown = run("--sequence " + kSequence + " --output " + dir_ + "/x.bag --frobnicate");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.output.find("unknown argument '--frobnicate'"), std::string::npos) << unknown.output;
  EXPECT_NE(unknown.output.find("usage: kitti_to_bag"), std::string::npos);
  const ToolRun missing = run("--sequence " + kSequence);
  EXPECT_EQ(missing.status, 2);
  const ToolRun range = run("--sequence " + kSequence + " --output " + dir_ + "/x.bag --first 100 --last 200");
  EXPECT_EQ(range.status, 1);
  EXPECT_NE(range.output.find("frame range 100..200 is outside the images 0..159"), std::string::npos) << range.output;
  const ToolRun compression = run("--sequence " + kSequence + " --output " + dir_ + "/x.bag --compression zip");
  EXPECT_EQ(compression.status, 2);
  const ToolRun poses = run("--sequence " + kSequence + " --output " + dir_ + "/x.bag --poses " + dir_ + "/none.txt");
  EXPECT_EQ(poses.status, 1);
  EXPECT_NE(poses.output.find("cannot read poses file"), std::string::npos) << poses.output;
}

// Issue 9 (hardening): a failed run keeps an existing bag; numbers that cannot be a camera or a pose, frame
// names that cannot be frame numbers and stamps that cannot be ROS times are errors naming file and line.
std::string readText(const std::string& path)
{
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeText(const fs::path& path, const std::string& text)
{
  std::ofstream(path) << text;
}

/// KITTI 07's calib.txt with line `line` (1-based) replaced.
std::string calibrationWithLine(int line, const std::string& replacement)
{
  std::istringstream in(readText(kSequence + "/calib.txt"));
  std::string out, text;
  for (int number = 1; std::getline(in, text); ++number)
    out += (number == line ? replacement : text) + "\n";
  return out;
}

TEST_F(KittiToBag, FailedRunLeavesAnExistingBagUntouched)
{
  // Frame 1 is not an image: the run fails after the bag was opened.
  const fs::path d = fs::path(fixture("broken_image", true, true, false));
  fs::create_directories(d / "image_0");
  fs::create_symlink(kSequence + "/image_0/000000.png", d / "image_0" / "000000.png");
  writeText(d / "image_0" / "000001.png", "not a png");
  const std::string bag_path = dir_ + "/existing.bag";
  writeText(bag_path, "the previous bag");
  const ToolRun r = run("--sequence " + d.string() + " --output " + bag_path);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("cannot read image"), std::string::npos) << r.output;
  EXPECT_EQ(readText(bag_path), "the previous bag");
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << "left behind: " << entry.path();

  // A successful run replaces it.
  const ToolRun ok = run("--sequence " + kSequence + " --output " + bag_path + " --last 1");
  ASSERT_EQ(ok.status, 0) << ok.output;
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag).size(), 4u);
}

TEST_F(KittiToBag, CalibrationWithoutFocalLengthIsRefusedNamingFileAndLine)
{
  // P0 all zeros: the camera offset would divide by fx = 0 and put NaN into every camera_info and /tf.
  const fs::path d = fs::path(fixture("zero_calib", false, true, true));
  writeText(d / "calib.txt", calibrationWithLine(1, "P0: 0 0 0 0 0 0 0 0 0 0 0 0"));
  const ToolRun r = run("--sequence " + d.string() + " --output " + dir_ + "/x.bag --last 1");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find((d / "calib.txt").string() + ":1: P0 has focal lengths"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ + "/x.bag"));
}

TEST_F(KittiToBag, PoseThatIsNotARotationIsRefusedNamingFileAndLine)
{
  const std::string poses = dir_ + "/poses.txt";
  writeText(poses, "1 0 0 0 0 1 0 0 0 0 1 0\n0 0 0 1 0 0 0 2 0 0 0 3\n");  // line 2: zero rotation
  const ToolRun r = run("--sequence " + kSequence + " --output " + dir_ + "/x.bag --last 1 --poses " + poses);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(poses + ":2: the pose has a rotation part that is not a rotation"), std::string::npos)
      << r.output;
}

TEST_F(KittiToBag, TwentyDigitImageNameIsAClearError)
{
  const fs::path d = fs::path(fixture("long_name", true, true, false));
  fs::create_directories(d / "image_0");
  fs::create_symlink(kSequence + "/image_0/000000.png", d / "image_0" / "000000.png");
  fs::create_symlink(kSequence + "/image_0/000001.png", d / "image_0" / "12345678901234567890.png");
  const ToolRun r = run("--sequence " + d.string() + " --output " + dir_ + "/x.bag");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("12345678901234567890.png: frame number 12345678901234567890 is too large"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("stol"), std::string::npos) << r.output;
}

TEST_F(KittiToBag, StampPastTwoToThe32SecondsIsRefusedNamingTheFile)
{
  const fs::path d = fs::path(fixture("late", true, false, true));
  std::string times;
  for (int i = 0; i < 160; ++i)
    times += std::to_string(300000000 + i) + ".0\n";
  writeText(d / "times.txt", times);
  // 4e9 + 3e8 s > 2^32 s (4294967296): no ROS time holds it.
  const ToolRun r = run("--sequence " + d.string() + " --output " + dir_ + "/x.bag --time-offset 4e9");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find((d / "times.txt").string() + ":1: time"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("largest ROS time"), std::string::npos) << r.output;
}

TEST_F(KittiToBag, ProgressLineAndQuiet)
{
  // Not a terminal here: plain progress lines, the last one with the rate; --quiet prints nothing.
  const ToolRun loud = run("--sequence " + kSequence + " --output " + dir_ + "/loud.bag --first 0 --last 9");
  ASSERT_EQ(loud.status, 0) << loud.output;
  EXPECT_NE(loud.output.find("kitti_to_bag: 10/10 frames (100%), "), std::string::npos) << loud.output;
  EXPECT_NE(loud.output.find(" frames/s"), std::string::npos) << loud.output;
  EXPECT_EQ(loud.output.find('\r'), std::string::npos) << loud.output;
  const ToolRun quiet = run("--sequence " + kSequence + " --output " + dir_ + "/quiet.bag --first 0 --last 9 --quiet");
  ASSERT_EQ(quiet.status, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("/10 frames"), std::string::npos) << quiet.output;
  EXPECT_EQ(quiet.output.find("wrote"), std::string::npos) << quiet.output;
  EXPECT_TRUE(fs::exists(dir_ + "/quiet.bag"));
}

}  // namespace

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
