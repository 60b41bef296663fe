// readPoseFile: KITTI and TUM trajectories for openable_offline --poses, with known answers and bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "openable/error.h"
#include "openable/io/pose_file.h"
#include "test_util.h"

namespace fs = std::filesystem;
using openable::PoseFile;

namespace
{
/// This test program's folder, removed when it ends.
struct Folder
{
  fs::path path = fs::temp_directory_path() / ("openable_test_pose_file_" + std::to_string(::getpid()));
  Folder()
  {
    fs::create_directories(path);
  }
  ~Folder()
  {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

/// A file holding `text`.
std::string writeFile(const std::string& name, const std::string& text)
{
  static const Folder folder;
  const std::string path = (folder.path / name).string();
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

/// readPoseFile(path) throws an Error whose message holds every one of `needles`.
void expectError(const std::string& path, const std::vector<std::string>& needles)
{
  try
  {
    openable::readPoseFile(path);
    ADD_FAILURE() << path << ": no error";
  }
  catch (const openable::Error& e)
  {
    for (const std::string& needle : needles)
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "'" << needle << "' not in: " << e.what();
  }
}

/// The rotation matrix of a unit quaternion (x y z w at 3..6), row-major.
std::array<double, 9> rotationOf(const std::array<double, 7>& p)
{
  const double x = p[3], y = p[4], z = p[5], w = p[6];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
          2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
          2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
}
}  // namespace

TEST(PoseFile, KittiSequence00)
{
  const std::string path = openable_test::sharedData("kitti/poses/00.txt");
  const PoseFile file = openable::readPoseFile(path);
  EXPECT_EQ(file.format, PoseFile::Format::Kitti);
  EXPECT_TRUE(file.stamps.empty());  // KITTI poses carry no time
  ASSERT_EQ(file.poses.size(), 4541u);
  // Frame 0 is the identity (the first camera frame is the world).
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(file.poses[0][size_t(i)], 0.0, 1e-9) << i;
  EXPECT_NEAR(file.poses[0][6], 1.0, 1e-9);
  // Frame 1 (second line): t = (-4.690294e-02, -2.839928e-02, 8.586941e-01), the car drove 0.86 m forward,
  // and the quaternion gives back the file's R to its 7 printed digits.
  const auto& p = file.poses[1];
  EXPECT_DOUBLE_EQ(p[0], -4.690294e-02);
  EXPECT_DOUBLE_EQ(p[1], -2.839928e-02);
  EXPECT_DOUBLE_EQ(p[2], 8.586941e-01);
  EXPECT_NEAR(p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6], 1.0, 1e-12);
  const std::array<double, 9> r = {9.999978e-01,  5.272628e-04, -2.066935e-03, -5.296506e-04, 9.999992e-01,
                                   -1.154865e-03, 2.066324e-03, 1.155958e-03,  9.999971e-01};
  const std::array<double, 9> back = rotationOf(p);
  for (size_t i = 0; i < 9; ++i)
    EXPECT_NEAR(back[i], r[i], 2e-6) << i;
}

TEST(PoseFile, KittiHalfTurnsTakeEveryBranch)
{
  // trace <= 0: the quaternion comes from the largest diagonal entry. 180 degrees about x, y and z.
  const openable::KittiMatrix about_x = {1, 0, 0, 1, 0, -1, 0, 2, 0, 0, -1, 3};
  const openable::KittiMatrix about_y = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0};
  const openable::KittiMatrix about_z = {-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0};
  const std::array<double, 7> x = openable::poseFromKitti(about_x);
  EXPECT_EQ(x, (std::array<double, 7>{1, 2, 3, 1, 0, 0, 0}));
  EXPECT_EQ(openable::poseFromKitti(about_y), (std::array<double, 7>{0, 0, 0, 0, 1, 0, 0}));
  EXPECT_EQ(openable::poseFromKitti(about_z), (std::array<double, 7>{0, 0, 0, 0, 0, 1, 0}));
  // 90 degrees about z (trace > 0): w = cos(45 deg), z = sin(45 deg).
  const std::array<double, 7> quarter = openable::poseFromKitti({0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0});
  EXPECT_NEAR(quarter[5], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(quarter[6], std::sqrt(0.5), 1e-12);
}

TEST(PoseFile, TumWithCommentsStampsAndUnnormalisedQuaternions)
{
  const std::string path = writeFile("tum.txt",
                                     "# timestamp tx ty tz qx qy qz qw\n"
                                     "1305031102.175304 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n"
                                     "\n"
                                     "  # a comment after a blank line\n"
                                     "1305031102.211214 1.3303 0.6256 1.6464 0 0 0 1.004\n"
                                     "1305031102.211214 -1 -2 -3 0 0 -1 0\n");
  const PoseFile file = openable::readPoseFile(path);
  EXPECT_EQ(file.format, PoseFile::Format::Tum);
  ASSERT_EQ(file.poses.size(), 3u);
  ASSERT_EQ(file.stamps.size(), 3u);
  EXPECT_DOUBLE_EQ(file.stamps[0], 1305031102.175304);
  EXPECT_DOUBLE_EQ(file.stamps[1], 1305031102.211214);
  EXPECT_DOUBLE_EQ(file.stamps[2], 1305031102.211214);  // equal stamps are allowed, only backwards is not
  EXPECT_DOUBLE_EQ(file.poses[0][0], 1.3405);
  EXPECT_DOUBLE_EQ(file.poses[0][2], 1.6575);
  // The first quaternion's norm is not exactly 1 (4 printed digits): normalised.
  const auto& q = file.poses[0];
  EXPECT_NEAR(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6], 1.0, 1e-12);
  EXPECT_NEAR(q[3], 0.6574, 1e-4);
  EXPECT_EQ(file.poses[1], (std::array<double, 7>{1.3303, 0.6256, 1.6464, 0, 0, 0, 1}));
  EXPECT_EQ(file.poses[2], (std::array<double, 7>{-1, -2, -3, 0, 0, -1, 0}));
}

TEST(PoseFile, BadInputNamesFileLineAndExpectation)
{
  const std::string kitti_line = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::string tum_line = "0.1 0 0 0 0 0 0 1\n";
  // Non-finite numbers, in either format.
  const std::string tum_nan = writeFile("tum_nan.txt", tum_line + "0.2 nan 0 0 0 0 0 1\n");
  expectError(tum_nan, {tum_nan + ":2:", "NaN or infinite"});
  const std::string kitti_inf = writeFile("kitti_inf.txt", kitti_line + "1 0 0 inf 0 1 0 0 0 0 1 0\n");
  expectError(kitti_inf, {kitti_inf + ":2:", "NaN or infinite"});
  // 11 numbers: neither format.
  const std::string eleven = writeFile("eleven.txt", "# KITTI, one number short\n1 0 0 0 0 1 0 0 0 0 1\n");
  expectError(eleven, {eleven + ":2:", "11 numbers", "KITTI pose (12 numbers", "TUM pose (8 numbers"});
  // A KITTI file with a short line later on, and a TUM file with a KITTI line: mixed formats.
  const std::string short_kitti = writeFile("short_kitti.txt", kitti_line + kitti_line + "1 0 0 0 0 1 0 0 0 0 1\n");
  expectError(short_kitti, {short_kitti + ":3:", "12 numbers"});
  const std::string mixed = writeFile("mixed.txt", tum_line + kitti_line);
  expectError(mixed, {mixed + ":2:", "not a TUM pose", "8 numbers"});
  // A zero quaternion is no rotation.
  const std::string zero_q = writeFile("zero_q.txt", tum_line + "0.2 1 2 3 0 0 0 0\n");
  expectError(zero_q, {zero_q + ":2:", "quaternion", "zero"});
  // Not a number, stamps going backwards, a rotation that is none.
  const std::string word = writeFile("word.txt", "0.1 0 0 0 0 0 0 one\n");
  expectError(word, {word + ":1:", "not a number"});
  const std::string backwards = writeFile("backwards.txt", tum_line + "0.05 0 0 0 0 0 0 1\n");
  expectError(backwards, {backwards + ":2:", "goes backwards"});
  const std::string scaled = writeFile("scaled.txt", "2 0 0 0 0 2 0 0 0 0 2 0\n");
  expectError(scaled, {scaled + ":1:", "not a rotation"});
  // Empty, only comments, missing.
  const std::string empty = writeFile("empty.txt", "");
  expectError(empty, {empty, "holds no pose"});
  const std::string comments = writeFile("comments.txt", "# stamp tx ty tz qx qy qz qw\n\n");
  expectError(comments, {comments, "holds no pose"});
  expectError("/nonexistent/poses.txt", {"/nonexistent/poses.txt", "cannot read pose file"});
}
