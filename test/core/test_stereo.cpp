// Stereo disparity: SGBM on a real EuRoC pair, conversions of given disparity images, bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"
#include "openable/description/stereo.h"
#include "test_util.h"

using namespace openable;
using openable_test::sharedData;

namespace openable_test
{
namespace
{
struct EurocCamera
{
  cv::Mat K, D, T_BS;
};

EurocCamera readCamera(const std::string& path)
{
  cv::FileStorage fs(path, cv::FileStorage::READ);
  std::vector<double> k, d, t;
  fs["intrinsics"] >> k;  // fu fv cu cv
  fs["distortion_coefficients"] >> d;
  fs["T_BS"]["data"] >> t;
  EXPECT_EQ(k.size(), 4u) << path;
  EXPECT_EQ(t.size(), 16u) << path;
  EurocCamera c;
  c.K = (cv::Mat_<double>(3, 3) << k.at(0), 0, k.at(2), 0, k.at(1), k.at(3), 0, 0, 1);
  c.D = cv::Mat(d, true).reshape(1, 1);
  c.T_BS = cv::Mat(t, true).reshape(1, 4);
  return c;
}
}  // namespace

/// EuRoC pair `pair` of euroc_v101_revisits, undistorted and rectified with its calibration. The files are raw
/// camera images (radial-tangential distortion, cameras not row-aligned); SGBM and every stereo input of the
/// library expect a rectified pair, as a robot's stereo_image_proc would deliver. Also used by
/// test_descriptors.cpp (same test binary).
void eurocRectifiedPair(int pair, cv::Mat* left, cv::Mat* right)
{
  const std::string dir = sharedData("stereo/euroc_v101_revisits/");
  const EurocCamera c0 = readCamera(dir + "sensorLeft.yaml"), c1 = readCamera(dir + "sensorRight.yaml");
  const cv::Mat T10 = c1.T_BS.inv() * c0.T_BS;  // left camera frame -> right camera frame
  const cv::Mat R = T10(cv::Rect(0, 0, 3, 3)).clone(), t = T10(cv::Rect(3, 0, 1, 3)).clone();
  const cv::Size size(752, 480);
  cv::Mat R0, R1, P0, P1, Q, map0x, map0y, map1x, map1y;
  cv::stereoRectify(c0.K, c0.D, c1.K, c1.D, size, R, t, R0, R1, P0, P1, Q, cv::CALIB_ZERO_DISPARITY, 0);
  cv::initUndistortRectifyMap(c0.K, c0.D, R0, P0, size, CV_32FC1, map0x, map0y);
  cv::initUndistortRectifyMap(c1.K, c1.D, R1, P1, size, CV_32FC1, map1x, map1y);
  const cv::Mat raw_left = cv::imread(dir + "left_img_" + std::to_string(pair) + ".png", cv::IMREAD_GRAYSCALE);
  const cv::Mat raw_right = cv::imread(dir + "right_img_" + std::to_string(pair) + ".png", cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(raw_left.size(), size);
  ASSERT_EQ(raw_right.size(), size);
  cv::remap(raw_left, *left, map0x, map0y, cv::INTER_LINEAR);
  cv::remap(raw_right, *right, map1x, map1y, cv::INTER_LINEAR);
}
}  // namespace openable_test

namespace
{
cv::Mat eurocImage(const std::string& side, int pair)
{
  cv::Mat left, right;
  openable_test::eurocRectifiedPair(pair, &left, &right);
  return side == "left" ? left : right;
}

std::string messageOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Stereo, RangeIsScaledToTheWidthInStepsOf16)
{
  Config config;  // 64 disparities at 640 px
  EXPECT_EQ(scaledNumDisparities(config, 640), 64);
  EXPECT_EQ(scaledNumDisparities(config, 752), 80);  // 75.2 -> 80
  EXPECT_EQ(scaledNumDisparities(config, 1280), 128);
  EXPECT_EQ(scaledNumDisparities(config, 320), 32);
  EXPECT_EQ(scaledNumDisparities(config, 64), 16);  // never below SGBM's minimum
  config.stereo_num_disparities = 100;
  EXPECT_EQ(scaledNumDisparities(config, 640), 96);
}

// SGBM works at 4 pixels per described patch pixel, at least 320 px, never above the input width.
TEST(Stereo, WorkWidthFollowsTheDescribedResolution)
{
  Config config;  // global, patch_size 64
  EXPECT_EQ(stereoWorkWidth(config, 752), 320);
  EXPECT_EQ(stereoWorkWidth(config, 200), 200);
  config.patch_size = 100;
  EXPECT_EQ(stereoWorkWidth(config, 752), 400);
  config.description_type = "grid";
  config.grid_x = 4;
  config.grid_y = 2;
  EXPECT_EQ(stereoWorkWidth(config, 752), 752);
  EXPECT_EQ(stereoWorkWidth(config, 4000), 1600);
}

// The disparity comes back at the input's size and in the input's pixels whatever the working width.
TEST(Stereo, DisparityIsInInputPixelsAtAnyWorkWidth)
{
  const cv::Mat left = eurocImage("left", 1), right = eurocImage("right", 1);
  Config fine;
  fine.patch_size = 200;  // works at the full 752 px
  ASSERT_EQ(stereoWorkWidth(fine, left.cols), left.cols);
  const cv::Mat a = disparityFromPair(left, right, Config()), b = disparityFromPair(left, right, fine);
  ASSERT_EQ(a.size(), left.size());
  ASSERT_EQ(b.size(), left.size());
  const cv::Mat both = (a == a) & (b == b);  // valid in both
  ASSERT_GT(cv::countNonZero(both), int(0.5 * left.total()));
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::patchNaNs(diff, 0);
  const double mean_difference = cv::mean(diff, both)[0];
  std::printf("[ measured ] mean |disparity at 320 px - at 752 px| = %.3f px\n", mean_difference);
  EXPECT_LE(mean_difference, 0.52);  // measured 0.514 (unscaled disparities would be off by ~6 px)
}

// EuRoC V1_01 (752x480, baseline 0.11 m, rectified focal length 436 px): the room is about 1.5..8 m away,
// i.e. disparities of about 6..32 px. Measured on pair 1 with the default config.
TEST(Stereo, EurocPairGivesPlausibleDisparities)
{
  const cv::Mat left = eurocImage("left", 1), right = eurocImage("right", 1);
  ASSERT_FALSE(left.empty());
  ASSERT_FALSE(right.empty());
  const cv::Mat disparity = disparityFromPair(left, right, Config());
  ASSERT_EQ(disparity.type(), CV_32FC1);
  ASSERT_EQ(disparity.size(), left.size());

  int valid = 0, plausible = 0, bad = 0;
  std::vector<float> values;
  for (int y = 0; y < disparity.rows; ++y)
    for (int x = 0; x < disparity.cols; ++x)
    {
      const float d = disparity.at<float>(y, x);
      if (std::isnan(d))
        continue;
      bad += !(d > 0.0f) || d > 80.0f;  // valid values are positive and inside the search range
      ++valid;
      plausible += d >= 6.0f && d <= 32.0f;  // 8 m .. 1.5 m
      values.push_back(d);
    }
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double valid_fraction = double(valid) / disparity.total();
  const double plausible_fraction = double(plausible) / valid;
  std::printf("[ measured ] valid %.4f, plausible among valid %.4f, median %.2f px\n", valid_fraction,
              plausible_fraction, values[values.size() / 2]);
  EXPECT_EQ(bad, 0);
  EXPECT_GE(valid_fraction, 0.871);      // measured 0.8715 (0.8592 with SGBM at the full 752 px)
  EXPECT_GE(plausible_fraction, 0.954);  // measured 0.9543 (0.9579 at 752 px)
  // The left band that the right camera cannot see (the search range) has no match.
  EXPECT_TRUE(std::isnan(disparity.at<float>(240, 10)));
}

TEST(Stereo, ColourAndGreyInputGiveTheSameDisparity)
{
  const cv::Mat left = eurocImage("left", 2), right = eurocImage("right", 2);
  cv::Mat left_bgr, right_bgr;
  cv::cvtColor(left, left_bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(right, right_bgr, cv::COLOR_GRAY2BGR);
  const cv::Mat a = disparityFromPair(left, right, Config());
  const cv::Mat b = disparityFromPair(left_bgr, right_bgr, Config());
  // NaN != NaN, so compare with NaN patched to -1.
  cv::Mat a2 = a.clone(), b2 = b.clone();
  cv::patchNaNs(a2, -1);
  cv::patchNaNs(b2, -1);
  EXPECT_EQ(cv::norm(a2, b2, cv::NORM_INF), 0.0);
}

TEST(Stereo, BadPairsAreRejectedNamingBothSizes)
{
  const cv::Mat left = eurocImage("left", 0), right = eurocImage("right", 0);
  cv::Mat smaller;
  cv::resize(right, smaller, cv::Size(376, 240));
  const std::string message = messageOf([&] { disparityFromPair(left, smaller, Config()); });
  EXPECT_NE(message.find("752x480"), std::string::npos) << message;
  EXPECT_NE(message.find("376x240"), std::string::npos) << message;

  cv::Mat colour;
  cv::cvtColor(right, colour, cv::COLOR_GRAY2BGR);
  EXPECT_THROW(checkStereoPair(left, colour), Error);  // same size, different type
  EXPECT_THROW(checkStereoPair(cv::Mat(), right), Error);
  cv::Mat wide;
  left.convertTo(wide, CV_16U);
  EXPECT_THROW(checkStereoPair(wide, wide), Error);
  EXPECT_NO_THROW(checkStereoPair(left, right));

  const cv::Mat tiny(16, 16, CV_8U, cv::Scalar(0));  // not wider than the smallest disparity range (16)
  EXPECT_THROW(disparityFromPair(tiny, tiny, Config()), Error);
}

TEST(Stereo, GivenDisparityImagesAreConvertedWithInvalidAsNaN)
{
  cv::Mat fixed = (cv::Mat_<int16_t>(1, 4) << -16, 0, 16, 168);  // OpenCV x16; -16 is SGBM's "no match"
  cv::Mat out = disparityFromImage(fixed);
  ASSERT_EQ(out.type(), CV_32FC1);
  EXPECT_TRUE(std::isnan(out.at<float>(0)));
  EXPECT_TRUE(std::isnan(out.at<float>(1)));
  EXPECT_FLOAT_EQ(out.at<float>(2), 1.0f);
  EXPECT_FLOAT_EQ(out.at<float>(3), 10.5f);

  cv::Mat kitti = (cv::Mat_<uint16_t>(1, 3) << 0, 256, 2560 + 128);  // KITTI PNG x256, 0 = invalid
  out = disparityFromImage(kitti);
  EXPECT_TRUE(std::isnan(out.at<float>(0)));
  EXPECT_FLOAT_EQ(out.at<float>(1), 1.0f);
  EXPECT_FLOAT_EQ(out.at<float>(2), 10.5f);

  cv::Mat pixels = (cv::Mat_<float>(1, 5) << std::nanf(""), -1.0f, 0.0f, 3.25f, INFINITY);
  out = disparityFromImage(pixels);
  EXPECT_TRUE(std::isnan(out.at<float>(0)));
  EXPECT_TRUE(std::isnan(out.at<float>(1)));
  EXPECT_TRUE(std::isnan(out.at<float>(2)));
  EXPECT_FLOAT_EQ(out.at<float>(3), 3.25f);
  EXPECT_TRUE(std::isnan(out.at<float>(4)));
}

TEST(Stereo, DisparityImagesOfOtherTypesAreRejected)
{
  const std::string message = messageOf([] { disparityFromImage(cv::Mat(4, 4, CV_8U, cv::Scalar(3))); });
  EXPECT_NE(message.find("8UC1"), std::string::npos) << message;
  EXPECT_NE(message.find("CV_16S"), std::string::npos) << message;  // lists what is accepted
  EXPECT_THROW(disparityFromImage(cv::Mat(4, 4, CV_32FC3, cv::Scalar(3))), Error);
  EXPECT_THROW(disparityFromImage(cv::Mat(4, 4, CV_64F, cv::Scalar(3))), Error);
  EXPECT_THROW(disparityFromImage(cv::Mat()), Error);
}
