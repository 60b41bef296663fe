#include <gtest/gtest.h>

#include <cmath>

#include "openable/error.h"
#include "openable/view/render.h"

using namespace openable;

TEST(Render, NormalizeByMaxIsEquation5AndKeepsNaN)
{
  cv::Mat m = (cv::Mat_<float>(2, 2) << 1.0f, 2.0f, std::nanf(""), 4.0f);
  const cv::Mat n = normalizeByMax(m);
  EXPECT_FLOAT_EQ(n.at<float>(0, 0), 0.25f);
  EXPECT_FLOAT_EQ(n.at<float>(1, 1), 1.0f);
  EXPECT_TRUE(std::isnan(n.at<float>(1, 0)));
  EXPECT_FLOAT_EQ(normalizeByMax(cv::Mat::zeros(2, 2, CV_32F)).at<float>(0, 0), 0.0f);
}

TEST(Render, MinMaxStretchesFiniteCellsToZeroOne)
{
  cv::Mat m = (cv::Mat_<float>(1, 4) << 0.2f, 0.3f, std::nanf(""), 0.25f);
  const cv::Mat n = normalizeMinMax(m);
  EXPECT_FLOAT_EQ(n.at<float>(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(n.at<float>(0, 1), 1.0f);
  EXPECT_TRUE(std::isnan(n.at<float>(0, 2)));
  EXPECT_NEAR(n.at<float>(0, 3), 0.5f, 1e-6);
  EXPECT_FLOAT_EQ(normalizeMinMax(cv::Mat(2, 2, CV_32F, cv::Scalar(0.4f))).at<float>(1, 1), 0.0f);
}

TEST(Render, ThresholdViewIsEquation9)
{
  cv::Mat m = (cv::Mat_<float>(1, 4) << 0.1f, 0.2f, 0.3f, std::nanf(""));
  const cv::Mat t = thresholdView(m, 0.2);
  EXPECT_EQ(t.at<uint8_t>(0, 0), 0);    // below theta: loop
  EXPECT_EQ(t.at<uint8_t>(0, 1), 255);  // theta itself is not below
  EXPECT_EQ(t.at<uint8_t>(0, 2), 255);
  EXPECT_EQ(t.at<uint8_t>(0, 3), 255);
}

TEST(Render, EveryColorMapGivesADifferentBgrImage)
{
  cv::Mat ramp(1, 256, CV_32F);
  for (int i = 0; i < 256; ++i)
    ramp.at<float>(0, i) = i / 255.0f;
  std::vector<cv::Mat> images;
  for (int map = 0; map < kColorMapCount; ++map)
  {
    const cv::Mat bgr = colorize(ramp, map);
    ASSERT_EQ(bgr.type(), CV_8UC3);
    for (const auto& other : images)
      EXPECT_GT(cv::norm(bgr, other, cv::NORM_L1), 0.0) << "colour map " << map;
    images.push_back(bgr);
  }
  cv::Mat with_nan = (cv::Mat_<float>(1, 1) << std::nanf(""));
  EXPECT_EQ(colorize(with_nan, 2, cv::Vec3b(1, 2, 3)).at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
  EXPECT_THROW(colorize(ramp, 12), Error);
  EXPECT_THROW(colorize(ramp, -1), Error);
}
