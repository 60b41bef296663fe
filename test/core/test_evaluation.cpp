// Ground truth and precision-recall: values computed by hand on small matrices, the published KITTI ground
// truth, and agreement with a brute-force computation on real-sized and real data.
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

namespace
{
/// Four queries, four references, aligned. Best matches: q0 -> 0 (0.1, right), q1 -> 0 (0.2, wrong),
/// q2 -> 2 (0.3, right), q3 -> 1 (0.4, wrong).
cv::Mat fourByFour()
{
  return (cv::Mat_<float>(4, 4) << 0.1F, 0.5F, 0.9F, 0.9F,  //
          0.2F, 0.8F, 0.9F, 0.9F,                           //
          0.9F, 0.9F, 0.3F, 0.9F,                           //
          0.9F, 0.4F, 0.9F, 0.9F);
}

/// Five queries, three references: q0 -> {0}, q1 -> {1} (row all NaN), q2 -> nothing (a negative),
/// q3 -> {2}, q4 -> {0}. Best matches: q0 0 (1, right), q2 1 (1, a false positive tied with q0),
/// q3 2 (2, right), q4 0 (3, right).
cv::Mat fiveByThree()
{
  return (cv::Mat_<float>(5, 3) << 1.0F, 5.0F, 5.0F,  //
          kNan, kNan, kNan,                           //
          5.0F, 1.0F, 5.0F,                           //
          5.0F, 5.0F, 2.0F,                           //
          3.0F, 9.0F, 9.0F);
}

GroundTruth fiveByThreeTruth()
{
  return GroundTruth({{0}, {1}, {}, {2}, {0}}, 0, 5, 3, true, "hand-made");
}

void expectCurve(const EvaluationResult& r, const std::vector<openable::PrPoint>& expected)
{
  ASSERT_EQ(r.curve.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i)
  {
    EXPECT_FLOAT_EQ(r.curve[i].threshold, expected[i].threshold) << "point " << i;
    EXPECT_DOUBLE_EQ(r.curve[i].precision, expected[i].precision) << "point " << i;
    EXPECT_DOUBLE_EQ(r.curve[i].recall, expected[i].recall) << "point " << i;
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Precision-recall on hand-made matrices

TEST(Evaluation, FourByFourStrictToleranceByHand)
{
  const EvaluationResult r = openable::evaluatePrecisionRecall(fourByFour(), openable::alignedGroundTruth(4, 4, 0));
  // Thresholds 0.1 .. 0.4 accept 1 .. 4 predictions with 1, 1, 2, 2 true positives out of 4 positives.
  expectCurve(r, {{0.1, 1.0, 0.25}, {0.2, 0.5, 0.25}, {0.3, 2.0 / 3.0, 0.5}, {0.4, 0.5, 0.5}});
  // AUC = 0.25 * 1 + 0 * 0.5 + 0.25 * 2/3 + 0 * 0.5 = 5/12.
  EXPECT_DOUBLE_EQ(r.auc, 5.0 / 12.0);
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 0.25);
  EXPECT_DOUBLE_EQ(r.recall_at_1, 0.5);
  EXPECT_EQ(r.evaluated_queries, 4);
  EXPECT_EQ(r.positive_queries, 4);
  EXPECT_EQ(r.masked_queries, 0);
  EXPECT_EQ(r.queries_without_prediction, 0);
  ASSERT_EQ(r.predictions.size(), 4u);
  EXPECT_EQ(r.predictions[3].match, 1);
  EXPECT_FLOAT_EQ(r.predictions[3].distance, 0.4F);
  EXPECT_FALSE(r.predictions[3].correct);
}

TEST(Evaluation, ToleranceOfOneFrameTurnsTheNeighbourIntoATrueMatch)
{
  // q1 -> 0 is now within one frame; q3 -> 1 is still two frames off.
  const EvaluationResult r = openable::evaluatePrecisionRecall(fourByFour(), openable::alignedGroundTruth(4, 4, 1));
  expectCurve(r, {{0.1, 1.0, 0.25}, {0.2, 1.0, 0.5}, {0.3, 1.0, 0.75}, {0.4, 0.75, 0.75}});
  EXPECT_DOUBLE_EQ(r.auc, 0.75);
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 0.75);
  EXPECT_DOUBLE_EQ(r.recall_at_1, 0.75);
}

TEST(Evaluation, TiesNanRowsAndNegativesByHand)
{
  const EvaluationResult r = openable::evaluatePrecisionRecall(fiveByThree(), fiveByThreeTruth());
  // Positives q0, q1, q3, q4. Threshold 1 accepts the tie q0 (right) and q2 (wrong) together.
  expectCurve(r, {{1.0, 0.5, 0.25}, {2.0, 2.0 / 3.0, 0.5}, {3.0, 0.75, 0.75}});
  EXPECT_DOUBLE_EQ(r.auc, 0.25 * 0.5 + 0.25 * 2.0 / 3.0 + 0.25 * 0.75);
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 0.0);  // the first threshold already holds a false positive
  EXPECT_DOUBLE_EQ(r.recall_at_1, 0.75);                 // q1 has no prediction: a miss, not a crash
  EXPECT_EQ(r.positive_queries, 4);
  EXPECT_EQ(r.queries_without_prediction, 1);
  EXPECT_EQ(r.predictions[1].match, -1);
  EXPECT_FALSE(std::isnan(r.auc));
}

TEST(Evaluation, MaskLeavesQueriesOut)
{
  // Without q4: positives q0, q1, q3; AUC = 1/3 * 1/2 + 1/3 * 2/3 = 7/18.
  const EvaluationResult without_q4 =
      openable::evaluatePrecisionRecall(fiveByThree(), fiveByThreeTruth(), {true, true, true, true, false});
  expectCurve(without_q4, {{1.0, 0.5, 1.0 / 3.0}, {2.0, 2.0 / 3.0, 2.0 / 3.0}});
  EXPECT_DOUBLE_EQ(without_q4.auc, 7.0 / 18.0);
  EXPECT_DOUBLE_EQ(without_q4.recall_at_1, 2.0 / 3.0);
  EXPECT_EQ(without_q4.masked_queries, 1);
  EXPECT_EQ(without_q4.evaluated_queries, 4);

  // Without the false positive q2 every accepted prediction is right.
  const EvaluationResult without_q2 =
      openable::evaluatePrecisionRecall(fiveByThree(), fiveByThreeTruth(), {true, true, false, true, true});
  expectCurve(without_q2, {{1.0, 1.0, 0.25}, {2.0, 1.0, 0.5}, {3.0, 1.0, 0.75}});
  EXPECT_DOUBLE_EQ(without_q2.auc, 0.75);
  EXPECT_DOUBLE_EQ(without_q2.max_recall_at_100_precision, 0.75);
}

TEST(Evaluation, PerfectMatrixHasAucOneAndFloat64IsAccepted)
{
  cv::Mat m(50, 50, CV_64F, cv::Scalar(10.0));
  for (int i = 0; i < 50; ++i)
  {
    m.at<double>(i, i) = 0.01 * i;
  }
  const EvaluationResult r = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(50, 50, 0));
  EXPECT_EQ(r.curve.size(), 50u);
  EXPECT_DOUBLE_EQ(r.auc, 1.0);
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.recall_at_1, 1.0);
}

TEST(Evaluation, InfiniteCellsAreNotCompared)
{
  const float inf = std::numeric_limits<float>::infinity();
  const cv::Mat m = (cv::Mat_<float>(2, 2) << inf, 0.5F, 0.2F, inf);
  // Row 0's only finite cell is column 1 (wrong); row 1's is column 0 (wrong).
  const EvaluationResult r = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(2, 2, 0));
  EXPECT_DOUBLE_EQ(r.recall_at_1, 0.0);
  EXPECT_EQ(r.predictions[0].match, 1);
  EXPECT_EQ(r.predictions[1].match, 0);
  EXPECT_EQ(r.queries_without_prediction, 0);
}

TEST(Evaluation, BadInputsAreClearErrors)
{
  const GroundTruth aligned = openable::alignedGroundTruth(4, 4, 0);
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(), aligned); }, "empty");
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(0, 4, CV_32F), aligned); }, "empty");
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(4, 4, CV_8U, cv::Scalar(1)), aligned); }, "float32");
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(4, 5, CV_32F, cv::Scalar(1)), aligned); },
              "is for a 4x4 matrix, but the distance matrix is 4x5");
  expectError(
      [&] {
        openable::evaluatePrecisionRecall(fourByFour(), aligned, {true, false});
      },
      "mask has 2 entries but the matrix has 4");
  // No positive query: recall would divide by zero.
  const GroundTruth none({{}, {}}, 0, 2, 2, true, "empty");
  expectError([&] { openable::evaluatePrecisionRecall(cv::Mat(2, 2, CV_32F, cv::Scalar(1)), none); },
              "none of the 2 evaluated queries");
  expectError(
      [&] {
        openable::evaluatePrecisionRecall(fiveByThree(), fiveByThreeTruth(), {false, false, true, false, false});
      },
      "none of the 1 evaluated queries");
}

// ---------------------------------------------------------------------------------------------------
// Agreement with a brute-force computation written differently: every threshold recomputed from scratch
// over all queries (O(n^2)), best matches found again, AUC summed over the recomputed points.

namespace
{
struct BruteForce
{
  std::vector<double> thresholds, precision, recall;
  double auc = 0.0, max_recall_full_precision = 0.0, recall_at_1 = 0.0;
};

BruteForce bruteForce(const cv::Mat& m, const std::function<bool(int, int)>& is_true, const std::vector<bool>& keep)
{
  std::vector<int> best(m.rows, -1);
  std::vector<float> best_distance(m.rows, 0.0F);
  std::vector<bool> positive(m.rows, false);
  for (int q = 0; q < m.rows; ++q)
  {
    for (int c = 0; c < m.cols; ++c)
    {
      const float v = m.at<float>(q, c);
      positive[q] = positive[q] || is_true(q, c);
      if (!std::isnan(v) && (best[q] < 0 || v < best_distance[q]))
      {
        best[q] = c;
        best_distance[q] = v;
      }
    }
  }
  std::set<float> distinct;
  int positives = 0, correct = 0;
  for (int q = 0; q < m.rows; ++q)
  {
    if (!keep[q])
      continue;
    positives += positive[q] ? 1 : 0;
    correct += (best[q] >= 0 && is_true(q, best[q])) ? 1 : 0;
    if (best[q] >= 0)
      distinct.insert(best_distance[q]);
  }
  BruteForce b;
  b.recall_at_1 = static_cast<double>(correct) / positives;
  double last_recall = 0.0;
  for (float t : distinct)
  {
    int accepted = 0, tp = 0;
    for (int q = 0; q < m.rows; ++q)
    {
      if (keep[q] && best[q] >= 0 && best_distance[q] <= t)
      {
        ++accepted;
        tp += is_true(q, best[q]) ? 1 : 0;
      }
    }
    b.thresholds.push_back(t);
    b.precision.push_back(static_cast<double>(tp) / accepted);
    b.recall.push_back(static_cast<double>(tp) / positives);
    b.auc += (b.recall.back() - last_recall) * b.precision.back();
    last_recall = b.recall.back();
    if (tp == accepted)
      b.max_recall_full_precision = std::max(b.max_recall_full_precision, b.recall.back());
  }
  return b;
}

void expectSame(const EvaluationResult& r, const BruteForce& b)
{
  ASSERT_EQ(r.curve.size(), b.thresholds.size());
  for (size_t i = 0; i < b.thresholds.size(); ++i)
  {
    ASSERT_EQ(r.curve[i].threshold, b.thresholds[i]) << i;
    ASSERT_EQ(r.curve[i].precision, b.precision[i]) << i;
    ASSERT_EQ(r.curve[i].recall, b.recall[i]) << i;
  }
  EXPECT_NEAR(r.auc, b.auc, 1e-12);
  EXPECT_EQ(r.max_recall_at_100_precision, b.max_recall_full_precision);
  EXPECT_EQ(r.recall_at_1, b.recall_at_1);
}

}  // namespace

TEST(Evaluation, AgreesWithBruteForceOnARealSizedRandomMatrix)
{
  // Nordland size (1800 x 1800): a per-row offset on a coarse grid plus a cell value on 256 levels, so
  // best distances spread over many thresholds and still tie; a dip near the diagonal so there is signal;
  // some NaN cells and rows, and a random mask.
  const int n = 1800;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> level(0, 255), offset(0, 399);
  std::uniform_real_distribution<float> unit(0.0F, 1.0F);
  cv::Mat m(n, n, CV_32F);
  std::vector<bool> keep(n);
  for (int q = 0; q < n; ++q)
  {
    keep[q] = unit(rng) > 0.1F;
    const bool empty_row = unit(rng) < 0.01F;
    const float row_offset = static_cast<float>(offset(rng)) / 100.0F;
    for (int c = 0; c < n; ++c)
    {
      float v = row_offset + static_cast<float>(level(rng)) / 255.0F;
      if (std::abs(q - c) <= 3 && unit(rng) < 0.5F)
        v -= 0.5F;
      m.at<float>(q, c) = (empty_row || unit(rng) < 0.02F) ? kNan : v;
    }
  }
  const int tolerance = 2;
  const EvaluationResult r = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(n, n, tolerance), keep);
  const BruteForce b = bruteForce(
      m, [&](int q, int c) { return std::abs(q - c) <= tolerance; }, keep);
  expectSame(r, b);
  EXPECT_GT(r.queries_without_prediction, 0);
  EXPECT_GT(r.curve.size(), 100u);
}

TEST(Evaluation, AgreesWithBruteForceOnRealNordlandDistances)
{
  // A real result: the first 300 Nordland winter frames (queries) against summer (references), sum of
  // absolute differences of the grey 64x32 images.
  const int n = 300;
  std::vector<cv::Mat> summer, winter;
  for (int i = 0; i < n; ++i)
  {
    char name[32];
    std::snprintf(name, sizeof(name), "images-%05d.png", (i + 1) * 10);
    summer.push_back(cv::imread(kData + "/nordland/summer/" + name, cv::IMREAD_GRAYSCALE));
    winter.push_back(cv::imread(kData + "/nordland/winter/" + name, cv::IMREAD_GRAYSCALE));
    ASSERT_FALSE(summer.back().empty() || winter.back().empty()) << name;
  }
  cv::Mat m(n, n, CV_32F);
  for (int q = 0; q < n; ++q)
  {
    for (int c = 0; c < n; ++c)
    {
      m.at<float>(q, c) = static_cast<float>(cv::norm(winter[q], summer[c], cv::NORM_L1));
    }
  }
  const std::vector<bool> keep = openable::brightFrameMask(winter);
  const EvaluationResult r = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(n, n, 1), keep);
  expectSame(r, bruteForce(
                    m, [](int q, int c) { return std::abs(q - c) <= 1; }, keep));
  const EvaluationResult all = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(n, n, 1));
  expectSame(all, bruteForce(
                      m, [](int q, int c) { return std::abs(q - c) <= 1; }, std::vector<bool>(n, true)));
}

// ---------------------------------------------------------------------------------------------------
// Ground truth

TEST(EvaluationOutput, CsvAndJsonOfTheFourByFour)
{
  const EvaluationResult r = openable::evaluatePrecisionRecall(fourByFour(), openable::alignedGroundTruth(4, 4, 0));
  EXPECT_EQ(openable::prCurveCsv(r),
            "threshold,precision,recall\n0.100000001,1,0.25\n0.200000003,0.5,0.25\n0.300000012,0.666666667,0.5\n"
            "0.400000006,0.5,0.5\n");
  EXPECT_EQ(openable::metricsJson(r, "ldb \"global\"", "aligned"),
            "{\"name\": \"ldb \\\"global\\\"\", \"auc\": 0.416667, \"max_recall_at_100_precision\": 0.25, "
            "\"recall_at_1\": 0.5, \"evaluated_queries\": 4, \"positive_queries\": 4, \"masked_queries\": 0, "
            "\"queries_without_prediction\": 0, \"auc_rule\": \"step-wise average precision\", "
            "\"ground_truth\": \"aligned\"}");
}

TEST(EvaluationOutput, PlotHasTheCurveInItsColourWhereItShouldBe)
{
  cv::Mat m(50, 50, CV_32F, cv::Scalar(10.0F));
  for (int i = 0; i < 50; ++i)
    m.at<float>(i, i) = 0.01F * i;
  const EvaluationResult perfect = openable::evaluatePrecisionRecall(m, openable::alignedGroundTruth(50, 50, 0));
  const cv::Mat plot = openable::drawPrCurves({{"perfect", perfect}}, "test");
  ASSERT_EQ(plot.size(), cv::Size(800, 600));
  ASSERT_EQ(plot.type(), CV_8UC3);
  // Precision 1 at every recall: a horizontal line of the first series colour (BGR 180,119,31) along the
  // top of the plot area, at recall 0.5 (x = 119 + 0.5 * 643) in the top row of the area (y = 68).
  bool found = false;
  for (int y = 64; y <= 72 && !found; ++y)
  {
    const cv::Vec3b px = plot.at<cv::Vec3b>(y, 440);
    found = std::abs(px[0] - 180) < 30 && std::abs(px[1] - 119) < 30 && std::abs(px[2] - 31) < 30;
  }
  EXPECT_TRUE(found);
  // The middle of the plot area stays white apart from grid lines (no curve passes there).
  const cv::Vec3b centre = plot.at<cv::Vec3b>(300, 445);
  EXPECT_EQ(centre, cv::Vec3b(255, 255, 255));
  EXPECT_EQ(openable::drawPrCurves({{"a", perfect}, {"b", perfect}}, "two", cv::Size(640, 480)).size(),
            cv::Size(640, 480));
  expectError([] { openable::drawPrCurves({}, "none"); }, "no curve");
  expectError([&] { openable::drawPrCurves({{"a", perfect}}, "t", cv::Size(100, 100)); }, "too small");
}
