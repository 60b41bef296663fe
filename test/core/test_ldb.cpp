#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "openable/error.h"
#include "openable/description/frame_describer.h"
#include "openable/hamming/hamming.h"
#include "openable/descriptors/ldb.h"
#include "test_util.h"

using namespace openable;

namespace
{
/// LDB computed the obvious way, pixel by pixel, without integral images: the reference for the fast one.
std::vector<uint64_t> naiveLdb(const cv::Mat& patch)
{
  std::vector<uint64_t> words(wordsForBits(kLdbBits), 0);
  auto mean = [&patch](int x0, int y0, int x1, int y1)
  {
    double s = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        s += patch.at<float>(y, x);
    return s / ((x1 - x0) * (y1 - y0));
  };
  int bit = 0;
  for (int n = 2; n <= 5; ++n)
  {
    std::vector<std::array<double, 3>> f;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
      {
        const int x0 = int(std::lround(double(c) * patch.cols / n)),
                  x1 = int(std::lround(double(c + 1) * patch.cols / n));
        const int y0 = int(std::lround(double(r) * patch.rows / n)),
                  y1 = int(std::lround(double(r + 1) * patch.rows / n));
        const int xm = (x0 + x1) / 2, ym = (y0 + y1) / 2;
        f.push_back({mean(x0, y0, x1, y1), mean(xm, y0, x1, y1) - mean(x0, y0, xm, y1),
                     mean(x0, ym, x1, y1) - mean(x0, y0, x1, ym)});
      }
    for (size_t a = 0; a < f.size(); ++a)
      for (size_t b = a + 1; b < f.size(); ++b)
        for (int k = 0; k < 3; ++k, ++bit)
          if (f[a][k] < f[b][k])
            words[bit / 64] |= uint64_t(1) << (bit % 64);
  }
  EXPECT_EQ(bit, kLdbBits);
  return words;
}

std::vector<uint64_t> ldb(const cv::Mat& patch, const cv::Mat& mask = cv::Mat())
{
  std::vector<uint64_t> words(wordsForBits(kLdbBits));
  computeLdb(patch, mask, words.data());
  return words;
}

bool bitSet(const std::vector<uint64_t>& w, int bit)
{
  return (w[bit / 64] >> (bit % 64)) & 1;
}
}  // namespace

TEST(Ldb, Has1386BitsIn22WordsWithZeroPadding)
{
  EXPECT_EQ(kLdbBits, 3 * (6 + 36 + 120 + 300));
  EXPECT_EQ(wordsForBits(kLdbBits), 22);
  cv::Mat patch(64, 64, CV_32F);
  cv::randu(patch, 0, 255);
  const auto w = ldb(patch);
  EXPECT_EQ(w[21] >> (kLdbBits - 21 * 64), 0u);
}

TEST(Ldb, KnownAnswerBrightBottomRightQuadrant)
{
  // 2x2 grid, cells 0 1 / 2 3; only cell 3 is bright. Mean tests (a < b) are 1 for pairs (0,3), (1,3), (2,3):
  // pairs are ordered (0,1) (0,2) (0,3) (1,2) (1,3) (2,3) and each has 3 bits, mean first: bits 6, 12, 15.
  // Uniform cells have zero gradients, so every gradient test of the 2x2 grid is 0.
  cv::Mat patch(64, 64, CV_32F, cv::Scalar(10));
  patch(cv::Rect(32, 32, 32, 32)).setTo(200);
  const auto w = ldb(patch);
  for (int bit = 0; bit < 18; ++bit)
    EXPECT_EQ(bitSet(w, bit), bit == 6 || bit == 12 || bit == 15) << "bit " << bit;
}

TEST(Ldb, FlatPatchHasNoBitSet)
{
  const auto w = ldb(cv::Mat(64, 64, CV_32F, cv::Scalar(77)));
  for (uint64_t word : w)
    EXPECT_EQ(word, 0u);
}

TEST(Ldb, EqualsNaivePixelByPixelReferenceOnRandomPatches)
{
  cv::RNG rng(42);
  for (int size : {10, 16, 33, 64, 97})
    for (int trial = 0; trial < 5; ++trial)
    {
      cv::Mat patch(size, size, CV_32F);
      rng.fill(patch, cv::RNG::UNIFORM, 0, 255);
      if (trial == 4)
        cv::GaussianBlur(patch, patch, cv::Size(0, 0), 3);  // smooth patches: small differences
      EXPECT_EQ(ldb(patch), naiveLdb(patch)) << "size " << size;
    }
}

TEST(Ldb, IsDeterministicAndPinnedOnARealImage)
{
  Config config = Config::paper();
  const FrameDescriber describer(config);
  const cv::Mat image = openable_test::gardensPoint("day_left", 0);
  ASSERT_FALSE(image.empty());
  const auto a = describer.describeImage(image);
  const auto b = describer.describeImage(image.clone());
  EXPECT_EQ(a, b);
  // Pinned bits (Debian 12's libjpeg and OpenCV 4.6 decode this file): a change here changes every stored
  // map. Update only on purpose. (Last updated for the two-step area downsampling of the preprocessor: one
  // bit of 1386 changed on this image.)
  uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a over the descriptor bytes
  uint32_t ones = 0;
  for (uint64_t w : a)
  {
    ones += __builtin_popcountll(w);
    for (int i = 0; i < 8; ++i)
    {
      hash ^= (w >> (8 * i)) & 0xff;
      hash *= 0x100000001b3ULL;
    }
  }
  EXPECT_EQ(ones, 824u);
  EXPECT_EQ(a[0], 0x5fae87fdb66ac9f3ULL);
  EXPECT_EQ(hash, 0x42ae52cdf95228e5ULL);
}

TEST(Ldb, MaskedMeansIgnoreInvalidPixels)
{
  cv::Mat values(20, 20, CV_32F, cv::Scalar(5));
  cv::Mat mask(20, 20, CV_8U, cv::Scalar(255));
  cv::Mat with_garbage = values.clone();
  with_garbage(cv::Rect(0, 0, 3, 3)).setTo(1e9);  // invalid pixels holding huge values
  mask(cv::Rect(0, 0, 3, 3)).setTo(0);
  EXPECT_EQ(ldb(with_garbage, mask), ldb(values, mask));
}

TEST(Ldb, SmallPatchOrWrongTypeIsAClearError)
{
  EXPECT_THROW(ldb(cv::Mat(9, 9, CV_32F, cv::Scalar(0))), Error);
  EXPECT_THROW(ldb(cv::Mat(16, 16, CV_16U, cv::Scalar(0))), Error);
  Config c = Config::paper();
  c.patch_size = 8;  // allowed by the config, too small for LDB
  EXPECT_THROW(FrameDescriber{c}, Error);
}

TEST(Ldb, SameRealPlaceIsCloserThanOtherPlaces)
{
  const FrameDescriber describer{Config::paper()};
  const auto left = describer.describeImage(openable_test::gardensPoint("day_left", 100));
  const auto right = describer.describeImage(openable_test::gardensPoint("day_right", 100));
  const auto other = describer.describeImage(openable_test::gardensPoint("day_right", 10));
  EXPECT_LT(hamming(left.data(), right.data(), left.size()), hamming(left.data(), other.data(), left.size()));
}
