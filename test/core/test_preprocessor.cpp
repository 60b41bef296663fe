#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "openable/description/area_downsample.h"
#include "openable/error.h"
#include "openable/description/preprocessor.h"
#include "test_util.h"

using namespace openable;

TEST(IlluminationInvariant, HandComputedPixels)
{
  // One BGR pixel (B=20, G=100, R=50) and a black one; alpha 0.47.
  cv::Mat bgr(1, 2, CV_8UC3);
  bgr.at<cv::Vec3b>(0, 0) = cv::Vec3b(20, 100, 50);
  bgr.at<cv::Vec3b>(0, 1) = cv::Vec3b(0, 0, 0);
  const cv::Mat out = illuminationInvariant(bgr, 0.47);
  ASSERT_EQ(out.type(), CV_32FC1);
  const double expected = std::log(100.0) - 0.47 * std::log(20.0) - 0.53 * std::log(50.0);
  EXPECT_NEAR(out.at<float>(0, 0), expected, 1e-5);
  EXPECT_FLOAT_EQ(out.at<float>(0, 1), 0.0f);  // zeros are treated as 1: log 1 = 0

  // A zero channel next to non-zero ones: only that channel is replaced by 1.
  cv::Mat partly_black(1, 1, CV_8UC3, cv::Scalar(0, 200, 10));
  EXPECT_NEAR(illuminationInvariant(partly_black, 0.47).at<float>(0, 0), std::log(200.0) - 0.53 * std::log(10.0), 1e-5);
}

TEST(IlluminationInvariant, ScalingAllChannelsByOneFactorDoesNotChangeTheResult)
{
  // Eq. 6 with the coefficients 1 - alpha - (1 - alpha) = 0 cancels a global intensity factor.
  cv::Mat a(1, 1, CV_8UC3, cv::Scalar(20, 60, 40));
  cv::Mat b(1, 1, CV_8UC3, cv::Scalar(60, 180, 120));
  EXPECT_NEAR(illuminationInvariant(a, 0.3).at<float>(0, 0), illuminationInvariant(b, 0.3).at<float>(0, 0), 1e-5);
}

TEST(IlluminationInvariant, GreyInputIsAClearError)
{
  Config c;
  c.illumination_invariance = true;
  const Preprocessor p(c);
  try
  {
    p.patches(cv::Mat(10, 10, CV_8UC1, cv::Scalar(5)));
    FAIL();
  }
  catch (const Error& e)
  {
    EXPECT_NE(std::string(e.what()).find("illumination_invariance"), std::string::npos);
  }
  EXPECT_THROW(illuminationInvariant(cv::Mat(3, 3, CV_8UC1), 0.47), Error);
}

TEST(Preprocessor, BadImagesAreClearErrors)
{
  const Preprocessor p{Config()};
  const std::vector<cv::Mat> bad = {cv::Mat(), cv::Mat(10, 10, CV_16UC1), cv::Mat(10, 10, CV_8UC2),
                                    cv::Mat(10, 10, CV_32FC1), cv::Mat(10, 10, CV_8UC(5))};
  for (const auto& image : bad)
  {
    try
    {
      p.patches(image);
      FAIL() << "accepted a bad image";
    }
    catch (const Error& e)
    {
      EXPECT_NE(std::string(e.what()).find("expected"), std::string::npos) << e.what();
    }
  }
}

TEST(Preprocessor, GlobalPatchIsTheAreaAverageOfTheImage)
{
  Config c;
  c.patch_size = 8;
  const Preprocessor p(c);
  cv::Mat image(32, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  image(cv::Rect(0, 0, 32, 32)).setTo(cv::Scalar(200, 200, 200));
  const auto patches = p.patches(image);
  ASSERT_EQ(patches.size(), 1u);
  ASSERT_EQ(patches[0].intensity.size(), cv::Size(8, 8));
  ASSERT_EQ(patches[0].intensity.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(patches[0].intensity.at<float>(0, 0), 200.0f);
  // Grey of (B, G, R) = (10, 20, 30) with OpenCV's BT.601 weights, rounded to 8 bits.
  EXPECT_NEAR(patches[0].intensity.at<float>(7, 7), 0.114 * 10 + 0.587 * 20 + 0.299 * 30, 0.5);
}

// lateral_shift: a place is the centre crop of 1 - 2 x lateral_shift of the width, a query's shifted views the crops of
// the same width at the left and right edges; each view is exactly the whole-image preprocessing of its crop.
TEST(Preprocessor, ShiftedViewsAreCropsOfOneWidthAtTheCentreAndBothEdges)
{
  Config c;
  c.patch_size = 16;
  c.lateral_shift = 0.1;
  cv::Mat image(40, 100, CV_8UC1);
  for (int x = 0; x < image.cols; ++x)
    image.col(x).setTo(2 * x + 20);  // every column its own grey
  const Preprocessor shifted(c);
  c.lateral_shift = 0.0;
  const Preprocessor whole(c);
  ASSERT_TRUE(shifted.hasShiftedViews(image.size()));
  EXPECT_FALSE(whole.hasShiftedViews(image.size()));
  const std::vector<std::pair<Preprocessor::View, int>> views{
      {Preprocessor::View::Centre, 10}, {Preprocessor::View::Left, 0}, {Preprocessor::View::Right, 20}};
  for (const auto& [view, left] : views)
  {
    const auto got = shifted.patches(image, view);
    const auto expected = whole.patches(image(cv::Rect(left, 0, 80, 40)));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(cv::norm(got[0].intensity, expected[0].intensity, cv::NORM_INF), 0.0) << "crop from column " << left;
    // The view's first patch column averages its crop's first 5 columns (80 / 16): 2 x (left + 2) + 20.
    EXPECT_FLOAT_EQ(got[0].intensity.at<float>(0, 0), float(2 * (left + 2) + 20));
  }
  // Without a shift every view is the whole image; a panorama has none (it is matched at every rotation).
  EXPECT_EQ(cv::norm(whole.patches(image, Preprocessor::View::Left)[0].intensity, whole.patches(image)[0].intensity,
                     cv::NORM_INF),
            0.0);
  Config ring;
  ring.camera_type = "panoramic";
  ring.panoramas = 4;
  ring.lateral_shift = 0.1;
  EXPECT_FALSE(Preprocessor(ring).hasShiftedViews(image.size()));
  // A crop narrower than the patch would be enlarged: a small image keeps its whole frame (80 px cropped to 64 at
  // lateral_shift 0.1 against a 72-pixel patch).
  Config small;
  small.patch_size = 72;
  small.lateral_shift = 0.1;
  const cv::Mat frame(40, 80, CV_8UC1, cv::Scalar(90));
  EXPECT_FALSE(Preprocessor(small).hasShiftedViews(frame.size()));
  EXPECT_EQ(Preprocessor(small).viewOf(frame.size(), Preprocessor::View::Centre), cv::Rect(0, 0, 80, 40));
}

TEST(Preprocessor, GridAndPanoramaCellLayout)
{
  Config c;
  c.patch_size = 16;
  c.description_type = "grid";
  c.grid_x = 2;
  c.grid_y = 3;
  cv::Mat image(60, 80, CV_8UC1);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x)
      image.at<uint8_t>(y, x) = static_cast<uint8_t>((x / 40) * 100 + (y / 20) * 10);  // cell id in the value
  const auto cells = Preprocessor(c).patches(image);
  ASSERT_EQ(cells.size(), 6u);
  for (int gy = 0; gy < 3; ++gy)
    for (int gx = 0; gx < 2; ++gx)
    {
      EXPECT_FLOAT_EQ(cells[gy * 2 + gx].intensity.at<float>(8, 8), gx * 100 + gy * 10);
      EXPECT_EQ(cells[gy * 2 + gx].intensity.size(), cv::Size(16, 16));
    }

  c.camera_type = "panoramic";
  c.panoramas = 4;
  c.description_type = "global";
  c.grid_x = c.grid_y = 1;
  cv::Mat panorama(20, 80, CV_8UC1);
  for (int x = 0; x < 80; ++x)
    panorama.col(x).setTo(x / 20 * 50);
  const auto subs = Preprocessor(c).patches(panorama);
  ASSERT_EQ(subs.size(), 4u);
  for (int i = 0; i < 4; ++i)
    EXPECT_FLOAT_EQ(subs[i].intensity.at<float>(5, 5), i * 50);
  // A panorama narrower than the number of sub-panoramas cannot be split.
  EXPECT_THROW(Preprocessor(c).patches(cv::Mat(20, 3, CV_8UC1)), Error);
}

TEST(Preprocessor, ACellSmallerThanThePatchAlongBothAxesIsDescribedAtItsOwnSize)
{
  Config c;
  c.descriptor = "HOG-B";
  c.patch_size = 128;
  const auto side = [](const Config& config, int cols, int rows)
  { return Preprocessor(config).patches(cv::Mat(rows, cols, CV_8UC1, cv::Scalar(90)))[0].intensity.size(); };
  // Nordland's 64x32 frames, and any cell smaller than the patch both ways: the cell's longer side.
  EXPECT_EQ(side(c, 64, 32), cv::Size(64, 64));
  EXPECT_EQ(side(c, 100, 20), cv::Size(100, 100));
  // As large as the patch along one axis: the patch (the other axis enlarged, as always).
  EXPECT_EQ(side(c, 128, 20), cv::Size(128, 128));
  EXPECT_EQ(side(c, 960, 540), cv::Size(128, 128));
  // Never below the descriptor's smallest patch (HOG-B 8, LDB 10).
  EXPECT_EQ(side(c, 6, 4), cv::Size(8, 8));
  c.descriptor = "LDB";
  EXPECT_EQ(side(c, 6, 4), cv::Size(10, 10));
  // Every configuration's patch of 64 on Nordland's frames: enlarged along one axis only, as before.
  c.descriptor = "HOG-B";
  c.patch_size = 64;
  EXPECT_EQ(side(c, 64, 32), cv::Size(64, 64));
  // Grid cells and sub-panoramas are cells: each one's own size.
  c.description_type = "grid";
  c.grid_x = c.grid_y = 2;
  const auto cells = Preprocessor(c).patches(cv::Mat(60, 100, CV_8UC1, cv::Scalar(90)));
  ASSERT_EQ(cells.size(), 4u);
  for (const Patch& cell : cells)
    EXPECT_EQ(cell.intensity.size(), cv::Size(50, 50));
  c.description_type = "global";
  c.grid_x = c.grid_y = 1;
  c.camera_type = "panoramic";
  c.panoramas = 6;
  const auto subs = Preprocessor(c).patches(cv::Mat(50, 300, CV_8UC1, cv::Scalar(90)));
  ASSERT_EQ(subs.size(), 6u);
  for (const Patch& sub : subs)
    EXPECT_EQ(sub.intensity.size(), cv::Size(50, 50));
}

TEST(Preprocessor, ARealSmallFrameGivesThePatchOfItsOwnSizeAtALargerPatch)
{
  // A Nordland frame (64x32) at gardens_point.yaml's patch of 128: the same floats as at 64, the size its pixels
  // fill, not a patch of 128 whose 2x4 blocks each repeat one pixel.
  const cv::Mat frame = cv::imread(openable_test::sharedData("nordland/summer/images-00500.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(frame.size(), cv::Size(64, 32));
  Config c;
  c.descriptor = "HOG-B";
  c.patch_size = 128;
  const auto large = Preprocessor(c).patches(frame);
  c.patch_size = 64;
  const auto own = Preprocessor(c).patches(frame);
  ASSERT_EQ(large.size(), 1u);
  ASSERT_EQ(large[0].intensity.size(), own[0].intensity.size());
  EXPECT_EQ(cv::norm(large[0].intensity, own[0].intensity, cv::NORM_INF), 0.0);
}

TEST(Preprocessor, MultiCameraRingGivesOneSubPanoramaPerCamera)
{
  Config c;
  c.camera_type = "panoramic";
  c.panoramas = 3;
  c.patch_size = 16;
  std::vector<cv::Mat> ring;
  for (int i = 0; i < 3; ++i)
    ring.emplace_back(30, 40, CV_8UC1, cv::Scalar(i * 60));
  const auto cells = Preprocessor(c).patchesFromCameras(ring);
  ASSERT_EQ(cells.size(), 3u);
  for (int i = 0; i < 3; ++i)
    EXPECT_FLOAT_EQ(cells[i].intensity.at<float>(3, 3), i * 60);
  ring.pop_back();
  EXPECT_THROW(Preprocessor(c).patchesFromCameras(ring), Error);
}

TEST(Preprocessor, DisparityIsAveragedOverValidPixelsAndScaledToThePatch)
{
  Config c;
  c.camera_type = "stereo";
  c.patch_size = 8;
  const Preprocessor p(c);
  cv::Mat left(32, 32, CV_8UC1, cv::Scalar(100));
  cv::Mat disparity(32, 32, CV_32F, cv::Scalar(20.0f));
  disparity(cv::Rect(0, 0, 16, 32)).setTo(std::nanf(""));  // left half invalid
  disparity.at<float>(20, 20) = -1.0f;                     // one negative (invalid) value
  const auto patches = p.patchesWithDisparity(left, disparity);
  ASSERT_EQ(patches.size(), 1u);
  const cv::Mat& d = patches[0].disparity;
  const cv::Mat& valid = patches[0].valid;
  EXPECT_EQ(valid.at<uint8_t>(0, 0), 0);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 0.0f);  // never a huge value
  EXPECT_EQ(valid.at<uint8_t>(0, 7), 255);
  EXPECT_FLOAT_EQ(d.at<float>(0, 7), 20.0f * 8 / 32);  // in patch pixels
  EXPECT_FLOAT_EQ(d.at<float>(5, 5), 20.0f * 8 / 32);  // the -1 pixel was left out of the average
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      EXPECT_TRUE(std::isfinite(d.at<float>(y, x)));
  EXPECT_THROW(p.patchesWithDisparity(left, cv::Mat(32, 32, CV_16SC1)), Error);
  EXPECT_THROW(p.patchesWithDisparity(left, cv::Mat(16, 32, CV_32FC1)), Error);
}

TEST(Preprocessor, PatchNormalizationGivesZeroMeanUnitStdBlocksAndKeepsFlatBlocksFlat)
{
  cv::Mat image(16, 16, CV_32F, cv::Scalar(50));
  cv::Mat left = image(cv::Rect(0, 0, 8, 16));
  cv::randu(left, 0, 255);  // textured left half, flat right half
  const cv::Mat out = normalizeBlocks(image, 8);
  for (int by = 0; by < 2; ++by)
  {
    cv::Scalar mean, stddev;
    cv::meanStdDev(out(cv::Rect(0, by * 8, 8, 8)), mean, stddev);
    EXPECT_NEAR(mean[0], 0.0, 1e-4);
    EXPECT_NEAR(stddev[0], 1.0, 1e-4);
    EXPECT_EQ(cv::countNonZero(out(cv::Rect(8, by * 8, 8, 8))), 0);
  }
  // Brightness and contrast changes of a block do not change its normalised values.
  cv::Mat brighter = image * 0.5 + 30;
  EXPECT_LT(cv::norm(normalizeBlocks(brighter, 8), out, cv::NORM_INF), 1e-3);
  EXPECT_EQ(cv::norm(normalizeBlocks(image, 0), image, cv::NORM_INF), 0.0);
}

// ---------------------------------------------------------------------------------------------------------
// The two-step area downsampling (area_downsample.h).
namespace
{
/// Naive reference of decimate(): every block summed pixel by pixel, its mean rounded half up.
cv::Mat naiveDecimate(const cv::Mat& image, int kx, int ky)
{
  const int channels = image.channels();
  cv::Mat out(image.rows / ky, image.cols / kx, image.type());
  const int x0 = (image.cols - out.cols * kx) / 2;
  const int y0 = (image.rows - out.rows * ky) / 2;
  for (int oy = 0; oy < out.rows; ++oy)
    for (int ox = 0; ox < out.cols; ++ox)
      for (int c = 0; c < channels; ++c)
      {
        long sum = 0;
        for (int y = y0 + oy * ky; y < y0 + (oy + 1) * ky; ++y)
          for (int x = x0 + ox * kx; x < x0 + (ox + 1) * kx; ++x)
            sum += image.ptr<uint8_t>(y)[x * channels + c];
        const long n = long(kx) * ky;
        out.ptr<uint8_t>(oy)[ox * channels + c] = static_cast<uint8_t>((sum + n / 2) / n);
      }
  return out;
}
}  // namespace

TEST(AreaDownsample, DecimateIsTheRoundedBlockMeanForEveryChannelCountAndBlockShape)
{
  cv::RNG rng(7);
  for (int channels = 1; channels <= 4; ++channels)
    for (const auto& [kx, ky] : std::vector<std::pair<int, int>>{{1, 1}, {2, 1}, {5, 3}, {7, 4}, {10, 7}, {3, 300}})
    {
      cv::Mat image(601, 643, CV_8UC(channels));  // not multiples of the blocks: borders are left out
      rng.fill(image, cv::RNG::UNIFORM, 0, 256);
      const cv::Mat fast = decimate(image, kx, ky);
      const cv::Mat naive = naiveDecimate(image, kx, ky);
      ASSERT_EQ(fast.size(), naive.size());
      ASSERT_EQ(fast.type(), naive.type());
      EXPECT_EQ(cv::norm(fast, naive, cv::NORM_INF), 0.0) << channels << " channels, " << kx << "x" << ky;
    }
  // Saturated blocks stay 255 (the sums of ky = 300 rows need 32 bits).
  EXPECT_EQ(cv::norm(decimate(cv::Mat(600, 10, CV_8UC1, cv::Scalar(255)), 1, 300), cv::NORM_INF), 255.0);
}

// The preprocessor converts to grey inside the decimation: it must give the pixels of the two steps it
// replaced, cvtColor(decimate()), for BGR and BGRA and every block shape (the descriptors stay bit-identical).
TEST(AreaDownsample, DecimateGreyIsCvtColorOfDecimate)
{
  cv::RNG rng(11);
  for (int channels : {1, 3, 4})
    for (const auto& [kx, ky] : std::vector<std::pair<int, int>>{{1, 1}, {2, 1}, {5, 3}, {10, 7}, {3, 300}})
    {
      cv::Mat image(601, 643, CV_8UC(channels));
      rng.fill(image, cv::RNG::UNIFORM, 0, 256);
      cv::Mat expected = decimate(image, kx, ky);
      if (channels > 1)
        cv::cvtColor(expected, expected, channels == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
      const cv::Mat grey = decimateGrey(image, kx, ky);
      ASSERT_EQ(grey.type(), CV_8UC1);
      EXPECT_EQ(cv::norm(grey, expected, cv::NORM_INF), 0.0) << channels << " channels, " << kx << "x" << ky;
    }
  // Every colour once: the fixed-point weights are OpenCV's.
  cv::Mat colours(4096, 4096, CV_8UC3);
  for (int i = 0; i < (1 << 24); ++i)
  {
    uint8_t* p = colours.ptr<uint8_t>(0) + 3 * i;
    p[0] = uint8_t(i), p[1] = uint8_t(i >> 8), p[2] = uint8_t(i >> 16);
  }
  cv::Mat expected;
  cv::cvtColor(colours, expected, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(decimateGrey(colours, 1, 1), expected, cv::NORM_INF), 0.0);
  EXPECT_THROW(decimateGrey(cv::Mat(10, 10, CV_8UC2), 2, 2), Error);
}

TEST(AreaDownsample, ExactIntegerFactorsGiveOpenCvsAreaResize)
{
  // 640x480 -> 128x160 is 5x3 blocks: OpenCV's area interpolation is the same block mean.
  const cv::Mat image = openable_test::gardensPoint("day_right", 100);
  ASSERT_FALSE(image.empty());
  cv::Mat vga, expected;
  cv::resize(image, vga, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  cv::resize(vga, expected, cv::Size(128, 160), 0, 0, cv::INTER_AREA);
  EXPECT_LE(cv::norm(decimate(vga, 5, 3), expected, cv::NORM_INF), 1.0);  // rounding of .5 only
  const cv::Mat two_step = areaDownsample(vga, cv::Size(128, 128));
  ASSERT_EQ(two_step.size(), cv::Size(128, 128));
  // Against the one-step area resize: the same picture, up to the blocks the small area step mixes.
  cv::Mat one_step;
  cv::resize(vga, one_step, cv::Size(128, 128), 0, 0, cv::INTER_AREA);
  cv::Mat difference;
  cv::absdiff(two_step, one_step, difference);
  EXPECT_LT(cv::mean(difference)[0], 2.0);
}

namespace
{
/// Every float of a and b the same, bit for bit (-0 and +0 differ, as do NaNs with other payloads).
bool sameBits(const cv::Mat& a, const cv::Mat& b)
{
  if (a.size() != b.size() || a.type() != b.type())
    return false;
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0)
      return false;
  return true;
}

cv::Mat openCvAreaResize(const cv::Mat& image, cv::Size target)
{
  cv::Mat out;
  cv::resize(image, out, target, 0, 0, cv::INTER_AREA);
  return out;
}
}  // namespace

// The preprocessor's small area step is areaResize instead of cv::resize: the descriptors stay bit-identical only
// if every float is OpenCV's. Real frames as the preprocessor sees them (decimated, grey or Eq. 6), for every
// patch size whose ratio is not a whole number, and the 640x480 frame of the benchmarks.
TEST(AreaDownsample, AreaResizeIsOpenCvsBitForBit)
{
  const std::string nordland = openable_test::sharedData("nordland/");
  std::vector<cv::Mat> frames = {
      openable_test::gardensPoint("day_right", 100), openable_test::gardensPoint("night_right", 100),
      openable_test::gardensPoint("day_left", 7), cv::imread(nordland + "summer/images-00010.png", cv::IMREAD_COLOR),
      cv::imread(nordland + "winter/images-01000.png", cv::IMREAD_COLOR)};
  for (const cv::Mat& frame : frames)
    ASSERT_FALSE(frame.empty());
  cv::Mat vga;
  cv::resize(frames[0], vga, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  frames.push_back(vga);
  const size_t colour_frames = frames.size();
  for (size_t i = 0; i < colour_frames; ++i)
  {
    cv::Mat grey;
    cv::cvtColor(frames[i], grey, cv::COLOR_BGR2GRAY);
    frames.push_back(grey);
  }
  int non_integer = 0;
  for (const cv::Mat& frame : frames)
    for (int p : {128, 100, 64, 48, 32, 24, 20, 16})
    {
      const cv::Size target(p, p);
      cv::Mat grey;
      decimateGreyTowards(frame, target).convertTo(grey, CV_32F);
      std::vector<cv::Mat> inputs = {grey};
      if (frame.channels() == 3)  // Eq. 6: negative values too
        inputs.push_back(illuminationInvariant(decimateTowards(frame, target), 0.47));
      for (const cv::Mat& small : inputs)
      {
        if (small.cols < p || small.rows < p)
          continue;  // enlargements are cv::resize's own
        non_integer += small.cols % p != 0 || small.rows % p != 0;
        EXPECT_TRUE(sameBits(areaResize(small, target), openCvAreaResize(small, target)))
            << frame.cols << "x" << frame.rows << "x" << frame.channels() << " -> " << small.cols << "x" << small.rows
            << " -> " << p;
      }
    }
  EXPECT_GT(non_integer, 40);  // the tables were exercised, not only cv::resize's own paths
  // Noise of both signs with -0 among it, odd sizes and ratios, and sizes areaResize hands to cv::resize.
  cv::RNG rng(5);
  for (const auto& [from, to] : std::vector<std::pair<cv::Size, cv::Size>>{{{137, 135}, {128, 128}},
                                                                           {{128, 160}, {128, 128}},
                                                                           {{31, 97}, {7, 13}},
                                                                           {{100, 100}, {99, 1}},
                                                                           {{64, 32}, {32, 32}},
                                                                           {{40, 40}, {20, 20}},
                                                                           {{20, 20}, {40, 30}}})
  {
    cv::Mat noise(from, CV_32FC1);
    rng.fill(noise, cv::RNG::UNIFORM, -1000.0, 1000.0);
    noise.at<float>(0, 0) = -0.f;
    noise.at<float>(from.height - 1, from.width - 1) = -0.f;
    EXPECT_TRUE(sameBits(areaResize(noise, to), openCvAreaResize(noise, to))) << from << " -> " << to;
  }
  // The check itself sees one float off by one unit in the last place.
  cv::Mat small;
  decimateGreyTowards(vga, cv::Size(128, 128)).convertTo(small, CV_32F);
  cv::Mat changed = areaResize(small, cv::Size(128, 128));
  changed.at<int32_t>(64, 64) ^= 1;
  EXPECT_FALSE(sameBits(changed, openCvAreaResize(small, cv::Size(128, 128))));
}

TEST(AreaDownsample, BadInputIsAClearError)
{
  EXPECT_THROW(decimate(cv::Mat(), 2, 2), Error);
  EXPECT_THROW(decimate(cv::Mat(10, 10, CV_32FC1), 2, 2), Error);
  EXPECT_THROW(decimate(cv::Mat(10, 10, CV_8UC1), 0, 2), Error);
  EXPECT_THROW(decimate(cv::Mat(10, 10, CV_8UC1), 11, 1), Error);
  EXPECT_THROW(areaDownsample(cv::Mat(10, 10, CV_8UC1), cv::Size(0, 4)), Error);
  // A target larger than the image is OpenCV's area resize (an upsampling).
  EXPECT_EQ(areaDownsample(cv::Mat(4, 4, CV_8UC1, cv::Scalar(9)), cv::Size(8, 8)).size(), cv::Size(8, 8));
}
