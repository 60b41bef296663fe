// Ground truth from every source (pairs files, KITTI poses and published files, hand-made positions), query
// masks, and ground truths built to cost too much.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "memory_limit.h"
#include "openable/error.h"
#include "evaluation_test_helpers.h"
#include "openable/evaluation/evaluation.h"

namespace fs = std::filesystem;
using openable::EvaluationResult;
using openable::GroundTruth;
using namespace evaluation_test;

TEST(GroundTruth, AlignedMatchesWithinTolerance)
{
  const GroundTruth t = openable::alignedGroundTruth(10, 10, 2);
  EXPECT_TRUE(t.isMatch(5, 3));
  EXPECT_TRUE(t.isMatch(5, 7));
  EXPECT_FALSE(t.isMatch(5, 8));
  EXPECT_FALSE(t.isMatch(5, 2));
  EXPECT_TRUE(t.isMatch(0, 0));
  EXPECT_EQ(t.numPairs(), 10u);
  EXPECT_EQ(t.description(), "aligned traversals, |i - j| <= 2");
  expectError([] { openable::alignedGroundTruth(10, 12, 2); }, "as many queries as references");
  expectError([] { openable::alignedGroundTruth(10, 10, -1); }, "tolerance");
  expectError([] { openable::alignedGroundTruth(0, 0, 1); }, "no rows");
}

TEST(GroundTruth, PairsFileWithCommentsToleranceAndNoDeclaredShape)
{
  TempDir dir;
  const std::string file = dir.file(
      "pairs.txt", "# loops of a tiny sequence\n\n9 2\n9 0  # trailing comment\n  # indented comment\n7 3\n9 2\n");
  const GroundTruth t = openable::loadPairsGroundTruth(file, 1);
  EXPECT_EQ(t.numPairs(), 3u);  // the repeated pair counts once
  EXPECT_EQ(t.anchors(9), (std::vector<int>{0, 2}));
  EXPECT_TRUE(t.isMatch(9, 1));  // one frame from both anchors
  EXPECT_TRUE(t.isMatch(9, 3));
  EXPECT_FALSE(t.isMatch(9, 4));
  EXPECT_FALSE(t.isMatch(8, 3));
  EXPECT_FALSE(t.hasMatch(8));
  EXPECT_FALSE(t.hasMatch(100));
  EXPECT_FALSE(t.exactShape());
  EXPECT_EQ(t.numQueries(), 10);
  EXPECT_EQ(t.numReferences(), 4);
  EXPECT_NO_THROW(t.checkFits(10, 4));
  EXPECT_NO_THROW(t.checkFits(20, 20));
  expectError([&] { t.checkFits(9, 10); }, "needs at least 10x4");
  expectError([&] { t.checkFits(10, 3); }, "needs at least 10x4");
}

TEST(GroundTruth, PairsFileDeclaredShapeAndBadLines)
{
  TempDir dir;
  const GroundTruth t = openable::loadPairsGroundTruth(dir.file("ok.txt", "# shape=12x12; pairs\n11 0\n"));
  EXPECT_TRUE(t.exactShape());
  expectError([&] { t.checkFits(12, 13); }, "is for a 12x12 matrix");
  expectError([&] { openable::loadPairsGroundTruth(dir.file("range.txt", "# shape=12x12\n12 0\n")); },
              "line 2 pair (12, 0) is out of range for its declared shape 12x12");
  expectError([&] { openable::loadPairsGroundTruth(dir.file("bad.txt", "1 0\n3 x\n")); }, "line 2 is not two");
  expectError([&] { openable::loadPairsGroundTruth(dir.file("three.txt", "1 0 5\n")); }, "line 1 is not two");
  expectError([&] { openable::loadPairsGroundTruth(dir.file("neg.txt", "1 -1\n")); }, "line 1 is not two");
  expectError([&] { openable::loadPairsGroundTruth(dir.path("missing.txt")); }, "cannot open");
  expectError([&] { openable::loadPairsGroundTruth(dir.file("ok2.txt", "1 0\n"), -1); }, "tolerance");
  // A pairs file for a bigger matrix than the one evaluated.
  const GroundTruth pairs = openable::loadPairsGroundTruth(dir.file("big.txt", "30 4\n"));
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(10, 10, CV_32F, cv::Scalar(1)), pairs); },
              "needs at least 31x5");
}

TEST(GroundTruth, OutOfRangeAnchorOfAnExplicitGroundTruth)
{
  const GroundTruth t({{0}, {7}}, 0, 2, 3, false, "hand-made");
  expectError([&] { t.checkFits(2, 3); }, "pair (1, 7) is out of range for a 2x3 distance matrix");
}

TEST(GroundTruth, PublishedKittiFilesLoad)
{
  struct Case
  {
    std::string file;
    int frames;
    size_t pairs;
    size_t queries;
    int first_i, first_j;
  };
  // Pair counts: lines of the files minus their one comment line; queries: distinct i.
  for (const Case& c : {Case{"groundTruth_KITTI00.txt", 4541, 31922, 788, 1560, 109},
                        Case{"groundTruth_KITTI_05.txt", 2761, 10558, 415, 1300, 537},
                        Case{"kitti06GroundTruth.txt", 1101, 3287, 272, 829, 0}})
  {
    const GroundTruth t = openable::loadPairsGroundTruth(kKitti + "/loop_ground_truth/" + c.file);
    EXPECT_EQ(t.numPairs(), c.pairs) << c.file;
    EXPECT_TRUE(t.exactShape()) << c.file;
    EXPECT_EQ(t.numQueries(), c.frames) << c.file;
    EXPECT_EQ(t.numReferences(), c.frames) << c.file;
    EXPECT_TRUE(t.isMatch(c.first_i, c.first_j)) << c.file;
    EXPECT_FALSE(t.isMatch(c.first_j, c.first_i)) << c.file;  // only the later frame closes the loop
    size_t queries = 0;
    for (int q = 0; q < c.frames; ++q)
    {
      queries += t.hasMatch(q) ? 1 : 0;
    }
    EXPECT_EQ(queries, c.queries) << c.file;
    EXPECT_NO_THROW(t.checkFits(c.frames, c.frames));
    expectError([&] { t.checkFits(c.frames - 1, c.frames - 1); }, "matrix");
  }
}

TEST(GroundTruth, LoopsFromHandMadePositions)
{
  // Out along x and back slightly offset: frame 3 passes frame 1 at 0.5 m, frame 4 passes frame 0 at 1 m.
  const std::vector<cv::Vec3d> p = {{0, 0, 0}, {10, 0, 0}, {20, 0, 0}, {10, 0, 0.5}, {0, 0, 1}};
  const GroundTruth e1 = openable::posesGroundTruth(p, 2.0, 1);
  EXPECT_EQ(e1.numPairs(), 2u);
  EXPECT_EQ(e1.anchors(3), std::vector<int>{1});
  EXPECT_EQ(e1.anchors(4), std::vector<int>{0});
  EXPECT_FALSE(e1.isMatch(1, 3));
  // 3 - 1 = 2 frames is not more than an exclusion of 2.
  const GroundTruth e2 = openable::posesGroundTruth(p, 2.0, 2);
  EXPECT_EQ(e2.numPairs(), 1u);
  EXPECT_FALSE(e2.hasMatch(3));
  // Strictly closer than D: exactly 1 m apart is not a loop at D = 1.
  EXPECT_FALSE(openable::posesGroundTruth(p, 1.0, 1).hasMatch(4));
  EXPECT_TRUE(openable::posesGroundTruth(p, 1.0001, 1).hasMatch(4));
  expectError([&] { openable::posesGroundTruth(p, 0.0, 1); }, "distance > 0");
  expectError([&] { openable::posesGroundTruth(p, 5.0, -1); }, "exclusion >= 0");
  expectError([&] { openable::posesGroundTruth({}, 5.0, 1); }, "no positions");
}

TEST(GroundTruth, KittiPosesFileAndBadLines)
{
  const std::vector<cv::Vec3d> p = openable::loadKittiPositions(kKitti + "/poses/06.txt");
  ASSERT_EQ(p.size(), 1101u);
  EXPECT_LT(cv::norm(p[0]), 1e-9);        // KITTI poses start at the identity (to rounding)
  EXPECT_NEAR(p[1][2], 1.198998, 1e-12);  // 12th number of the second line
  TempDir dir;
  const std::vector<cv::Vec3d> q =
      openable::loadKittiPositions(dir.file("p.txt", "1 0 0 1.5 0 1 0 -2 0 0 1 3.25\n1 0 0 4 0 1 0 5 0 0 1 6\n"));
  ASSERT_EQ(q.size(), 2u);
  EXPECT_EQ(q[0], cv::Vec3d(1.5, -2, 3.25));
  EXPECT_EQ(q[1], cv::Vec3d(4, 5, 6));
  expectError([&] { openable::loadKittiPositions(dir.file("short.txt", "1 0 0 4 0 1 0 5 0 0 1 6\n1 0 0\n")); },
              "line 2 is not a row-major 3x4 pose");
  expectError([&] { openable::loadKittiPositions(dir.file("long.txt", "1 0 0 4 0 1 0 5 0 0 1 6 7\n")); }, "line 1");
  expectError([&] { openable::loadKittiPositions(dir.file("empty.txt", "")); }, "holds no pose");
  expectError([&] { openable::loadKittiPositions(dir.path("missing.txt")); }, "cannot open");
}

TEST(GroundTruth, PosesAgreeWithPublishedKittiGroundTruthAtTheDefaults)
{
  // Measured with `openable_eval --poses ... --compare ...` (doc/results.md): at D = 6 m, E = 100 frames,
  // 06 is reproduced almost exactly; 00 and 05 mark windows of 20..70 frames around each revisit, up to
  // 40 m away, which no distance ball reproduces pair for pair.
  struct Case
  {
    std::string sequence, file;
    size_t pose_pairs, published_pairs, common_pairs, pose_queries, published_queries, common_queries;
  };
  for (const Case& c : {Case{"00", "groundTruth_KITTI00.txt", 15959, 31922, 14404, 819, 788, 781},
                        Case{"05", "groundTruth_KITTI_05.txt", 8106, 10558, 6044, 459, 415, 413},
                        Case{"06", "kitti06GroundTruth.txt", 3253, 3287, 3253, 271, 272, 271}})
  {
    const GroundTruth poses =
        openable::posesGroundTruth(openable::loadKittiPositions(kKitti + "/poses/" + c.sequence + ".txt"));
    const GroundTruth published = openable::loadPairsGroundTruth(kKitti + "/loop_ground_truth/" + c.file);
    const openable::GroundTruthAgreement a = openable::compareGroundTruth(poses, published);
    EXPECT_EQ(a.candidate_pairs, c.pose_pairs) << c.sequence;
    EXPECT_EQ(a.reference_pairs, c.published_pairs) << c.sequence;
    EXPECT_EQ(a.common_pairs, c.common_pairs) << c.sequence;
    EXPECT_EQ(a.candidate_queries, c.pose_queries) << c.sequence;
    EXPECT_EQ(a.reference_queries, c.published_queries) << c.sequence;
    EXPECT_EQ(a.common_queries, c.common_queries) << c.sequence;
  }
}

TEST(GroundTruth, AgreementRatiosByHand)
{
  const GroundTruth a({{0, 1}, {}, {0}}, 0, 3, 3, true, "a");
  const GroundTruth b({{1}, {0}, {1}}, 0, 3, 3, true, "b");
  const openable::GroundTruthAgreement x = openable::compareGroundTruth(a, b);
  // Pairs: a = {(0,0),(0,1),(2,0)}, b = {(0,1),(1,0),(2,1)}, common {(0,1)}, union 5.
  EXPECT_EQ(x.common_pairs, 1u);
  EXPECT_DOUBLE_EQ(x.pairPrecision(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(x.pairRecall(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(x.pairJaccard(), 1.0 / 5.0);
  // Queries with loops: a = {0, 2}, b = {0, 1, 2}.
  EXPECT_DOUBLE_EQ(x.queryJaccard(), 2.0 / 3.0);
}

// ---------------------------------------------------------------------------------------------------
// Masks

TEST(QueryMask, DarkFramesByMeanIntensity)
{
  const std::vector<cv::Mat> images = {cv::Mat(4, 4, CV_8U, cv::Scalar(9)), cv::Mat(4, 4, CV_8U, cv::Scalar(10)),
                                       cv::Mat(4, 4, CV_8UC3, cv::Scalar(0, 0, 29)),  // mean 9.67
                                       cv::Mat(4, 4, CV_8UC3, cv::Scalar(0, 0, 30)),  // mean 10
                                       cv::Mat(2, 2, CV_16U, cv::Scalar(257 * 12))};  // 12 on the 8-bit scale
  EXPECT_EQ(openable::brightFrameMask(images), (std::vector<bool>{false, true, false, true, true}));
  cv::Mat half(2, 2, CV_8U, cv::Scalar(0));
  half.row(0).setTo(20);  // mean exactly 10
  EXPECT_EQ(openable::brightFrameMask({half}), std::vector<bool>{true});
  EXPECT_EQ(openable::brightFrameMask({half}, 10.5), std::vector<bool>{false});
  expectError([] { openable::brightFrameMask(std::vector<cv::Mat>{cv::Mat()}); }, "image 0 is empty");
  expectError(
      [] {
        openable::brightFrameMask({cv::Mat(2, 2, CV_8U), cv::Mat(2, 2, CV_32F, cv::Scalar(0.5))});
      },
      "image 1 is not 8-bit or 16-bit");
}

TEST(QueryMask, NordlandWinterFolderAgreesWithAPixelSum)
{
  const std::string folder = kData + "/nordland/winter";
  const std::vector<bool> mask = openable::brightFrameMask(folder);
  ASSERT_EQ(mask.size(), 1800u);
  // Independent: the 8-bit pixel sum of every file compared with 10 * pixels, in integers.
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder))
    files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 1800u);
  size_t dark = 0;
  for (size_t i = 0; i < files.size(); ++i)
  {
    const cv::Mat image = cv::imread(files[i], cv::IMREAD_UNCHANGED);
    long long sum = 0;
    for (int r = 0; r < image.rows; ++r)
      for (int c = 0; c < image.cols * image.channels(); ++c)
        sum += image.ptr<unsigned char>(r)[c];
    const bool bright = sum >= 10LL * image.rows * image.cols * image.channels();
    EXPECT_EQ(mask[i], bright) << files[i];
    dark += bright ? 0 : 1;
  }
  EXPECT_EQ(static_cast<size_t>(std::count(mask.begin(), mask.end(), false)), dark);
  EXPECT_GT(dark, 0u);  // tunnels exist in the winter traversal
}

TEST(QueryMask, FileRoundTripAndBadLines)
{
  TempDir dir;
  const std::vector<bool> mask = {true, false, false, true};
  openable::saveQueryMask(dir.path("mask.txt"), mask);
  EXPECT_EQ(openable::loadQueryMask(dir.path("mask.txt")), mask);
  expectError([&] { openable::loadQueryMask(dir.file("bad.txt", "1\n0\n2\n")); }, "line 3 is not 1");
  expectError([&] { openable::loadQueryMask(dir.path("missing.txt")); }, "cannot open");
}

// ---------------------------------------------------------------------------------------------------
// Output

// Issue 9 (hardening): a pairs file's indices cost memory by the pairs it holds, not by their value, and
// are checked against the matrix shape.
TEST(GroundTruthHardening, FarPairCostsOneEntryAndIsRefusedByTheShapeCheck)
{
  TempDir dir;
  const std::string path = dir.file("far.txt", "50000000 0\n");
  const auto run =
      openable_test::runWithMemoryLimit(128 << 20, [&] { openable::loadPairsGroundTruth(path).checkFits(4, 4); });
  EXPECT_EQ(run.outcome, openable_test::LimitedRun::kOpenableError) << run.message;
  EXPECT_NE(run.message.find("needs at least 50000001x1"), std::string::npos) << run.message;
}

TEST(GroundTruthHardening, ToleranceNearIntMaxDoesNotWrap)
{
  const GroundTruth truth = openable::alignedGroundTruth(4, 4, 2147483647);
  for (int q = 0; q < 4; ++q)
    for (int r = 0; r < 4; ++r)
      EXPECT_TRUE(truth.isMatch(q, r)) << q << " " << r;
}
