// Joined-stream and truth-matrix ground truths: known answers on hand-made streams, images and .npy files,
// and a clear error for every bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/evaluation/evaluation.h"
#include "openable/evaluation/ground_truth_sources.h"
#include "openable/io/npy.h"

namespace fs = std::filesystem;
using openable::GroundTruth;

namespace
{
const float kNan = std::numeric_limits<float>::quiet_NaN();

class TruthFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("openable_test_truth_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const
  {
    return (dir_ / name).string();
  }
  void write(const std::string& name, const std::string& bytes) const
  {
    std::ofstream(path(name), std::ios::binary) << bytes;
  }
  fs::path dir_;
};

/// A .npy file of `dict` and raw `data`, built by hand like numpy's writer (version 1, 64-byte aligned).
std::string npyBytes(const std::string& dict, const std::string& data)
{
  std::string header = dict;
  header.append((64 - (10 + header.size() + 1) % 64) % 64, ' ');
  header.push_back('\n');
  std::string bytes("\x93NUMPY\x01\x00", 8);
  bytes.push_back(static_cast<char>(header.size() & 0xff));
  bytes.push_back(static_cast<char>(header.size() >> 8));
  return bytes + header + data;
}

template <typename T>
std::string rawBytes(const std::vector<T>& values)
{
  std::string bytes(values.size() * sizeof(T), '\0');
  std::memcpy(&bytes[0], values.data(), bytes.size());
  return bytes;
}

/// Every (query, reference) the ground truth calls a match, row by row.
std::vector<std::pair<int, int>> matches(const GroundTruth& truth, int rows, int cols)
{
  std::vector<std::pair<int, int>> out;
  for (int q = 0; q < rows; ++q)
    for (int r = 0; r < cols; ++r)
      if (truth.isMatch(q, r))
        out.emplace_back(q, r);
  return out;
}

template <typename Call>
void expectError(Call call, const std::string& needle)
{
  try
  {
    call();
    ADD_FAILURE() << "no error, expected one containing '" << needle << "'";
  }
  catch (const openable::Error& e)
  {
    const std::string what = e.what();
    EXPECT_NE(what.find(needle), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
  }
}

}  // namespace

TEST(JoinedGroundTruth, FramesBeforeTheJoinNeverMatchAndFrameNPlusIMatchesIWithinTolerance)
{
  const GroundTruth truth = openable::joinedGroundTruth(10, 6, 1);
  for (int q = 0; q < 6; ++q)
  {
    EXPECT_FALSE(truth.hasMatch(q)) << q;
    for (int r = 0; r < 10; ++r)
      EXPECT_FALSE(truth.isMatch(q, r)) << q << " " << r;
  }
  const std::vector<std::pair<int, int>> expected = {{6, 0}, {6, 1}, {7, 0}, {7, 1}, {7, 2}, {8, 1},
                                                     {8, 2}, {8, 3}, {9, 2}, {9, 3}, {9, 4}};
  EXPECT_EQ(matches(truth, 10, 10), expected);
  EXPECT_TRUE(truth.exactShape());
  EXPECT_EQ(truth.numQueries(), 10);
  EXPECT_EQ(truth.numReferences(), 10);
  EXPECT_EQ(truth.description(), "joined stream, frame 6 + i is frame i, |match - i| <= 1");
  // Tolerance 0 is the default: only the anchor itself.
  EXPECT_EQ(matches(openable::joinedGroundTruth(4, 2), 4, 4), (std::vector<std::pair<int, int>>{{2, 0}, {3, 1}}));
}

TEST(JoinedGroundTruth, JoinOutsideTheStreamOrNegativeToleranceIsAClearError)
{
  for (int joined : {0, -1, 10, 11})
    expectError([&] { openable::joinedGroundTruth(10, joined, 0); }, "must start at a frame in [1, 9]");
  expectError([] { openable::joinedGroundTruth(10, 5, -1); }, "tolerance must be >= 0");
  expectError([] { openable::joinedGroundTruth(1, 1, 0); }, "1-frame stream");
}

TEST(JoinedGroundTruth, AcceptancesBeforeTheJoinAreFalsePositivesInTheMatrixCurve)
{
  // Six frames joined at 3. Best matches: q0 none, q1 -> 0 (0.2, before the join: false positive),
  // q2 -> 0 (0.9, false positive), q3 -> 0 (0.1, right), q4 -> 1 (0.3, right), q5 -> 0 (0.4, wrong; 2 is right).
  const cv::Mat m = (cv::Mat_<float>(6, 6) << kNan, kNan, kNan, kNan, kNan, kNan,  //
                     0.2F, kNan, kNan, kNan, kNan, kNan,                           //
                     0.9F, 0.95F, kNan, kNan, kNan, kNan,                          //
                     0.1F, 0.5F, 0.6F, kNan, kNan, kNan,                           //
                     0.7F, 0.3F, 0.8F, 0.9F, kNan, kNan,                           //
                     0.4F, 0.9F, 0.5F, 0.9F, 0.9F, kNan);
  const openable::EvaluationResult r = openable::evaluatePrecisionRecall(m, openable::joinedGroundTruth(6, 3));
  EXPECT_EQ(r.positive_queries, 3);
  EXPECT_EQ(r.queries_without_prediction, 1);
  ASSERT_EQ(r.curve.size(), 5u);
  const double precision[] = {1.0, 0.5, 2.0 / 3.0, 0.5, 0.4};
  const double recall[] = {1.0 / 3.0, 1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0};
  for (size_t i = 0; i < 5; ++i)
  {
    EXPECT_DOUBLE_EQ(r.curve[i].precision, precision[i]) << i;
    EXPECT_DOUBLE_EQ(r.curve[i].recall, recall[i]) << i;
  }
  EXPECT_DOUBLE_EQ(r.auc, 1.0 / 3.0 + (1.0 / 3.0) * (2.0 / 3.0));
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(r.recall_at_1, 2.0 / 3.0);
  // A joined truth is for a square matrix of its stream.
  expectError([&] { openable::evaluatePrecisionRecall(m.colRange(0, 5), openable::joinedGroundTruth(6, 3)); },
              "is for a 6x6 matrix, but the distance matrix is 6x5");
}

TEST_F(TruthFiles, PngAnyNonZeroChannelIsTheSamePlaceAndAlphaIsIgnored)
{
  cv::Mat colour(3, 4, CV_8UC3, cv::Scalar::all(0));
  colour.at<cv::Vec3b>(0, 1) = cv::Vec3b(0, 0, 7);  // red only
  colour.at<cv::Vec3b>(1, 0) = cv::Vec3b(255, 255, 255);
  colour.at<cv::Vec3b>(2, 3) = cv::Vec3b(1, 0, 0);  // faint blue
  ASSERT_TRUE(cv::imwrite(path("truth.png"), colour));
  const GroundTruth truth = openable::loadTruthMatrix(path("truth.png"));
  EXPECT_EQ(matches(truth, 3, 4), (std::vector<std::pair<int, int>>{{0, 1}, {1, 0}, {2, 3}}));
  EXPECT_TRUE(truth.exactShape());
  EXPECT_EQ(truth.numQueries(), 3);
  EXPECT_EQ(truth.numReferences(), 4);
  EXPECT_EQ(truth.description(), "truth matrix " + path("truth.png"));

  // Opaque black is "not the same place": alpha alone marks nothing.
  cv::Mat rgba(2, 2, CV_8UC4, cv::Scalar(0, 0, 0, 255));
  rgba.at<cv::Vec4b>(1, 1) = cv::Vec4b(0, 9, 0, 255);
  ASSERT_TRUE(cv::imwrite(path("alpha.png"), rgba));
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("alpha.png")), 2, 2), (std::vector<std::pair<int, int>>{{1, 1}}));

  // 16-bit grey: a value of 1 is not rounded away.
  cv::Mat deep(2, 3, CV_16U, cv::Scalar(0));
  deep.at<uint16_t>(0, 2) = 1;
  ASSERT_TRUE(cv::imwrite(path("deep.png"), deep));
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("deep.png")), 2, 3), (std::vector<std::pair<int, int>>{{0, 2}}));
}

TEST_F(TruthFiles, NpyOfFloatBoolAndInt64NonZeroIsTheSamePlace)
{
  const cv::Mat values = (cv::Mat_<float>(2, 3) << 0.0F, 0.5F, -0.0F, kNan, 0.0F, -2.0F);
  openable::writeNpy(path("float.npy"), values);
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("float.npy")), 2, 3),
            (std::vector<std::pair<int, int>>{{0, 1}, {1, 0}, {1, 2}}));

  write("bool.npy",
        npyBytes("{'descr': '|b1', 'fortran_order': False, 'shape': (2, 2), }", std::string("\1\0\0\1", 4)));
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("bool.npy")), 2, 2),
            (std::vector<std::pair<int, int>>{{0, 0}, {1, 1}}));

  // numpy's default integer; 256 has a zero low byte, so every byte must be looked at.
  write("int.npy",
        npyBytes("{'descr': '<i8', 'fortran_order': False, 'shape': (1, 3), }", rawBytes<int64_t>({0, 256, -1})));
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("int.npy")), 1, 3),
            (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}}));

  write("double.npy",
        npyBytes("{'descr': '<f8', 'fortran_order': False, 'shape': (1, 2), }", rawBytes<double>({-0.0, 1e-300})));
  EXPECT_EQ(matches(openable::loadTruthMatrix(path("double.npy")), 1, 2), (std::vector<std::pair<int, int>>{{0, 1}}));
}

TEST_F(TruthFiles, ShapeMismatchAndUnreadableFilesAreClearErrors)
{
  cv::Mat mask(3, 4, CV_8U, cv::Scalar(0));
  mask.at<uint8_t>(1, 1) = 255;
  ASSERT_TRUE(cv::imwrite(path("truth.png"), mask));
  const cv::Mat distances(3, 3, CV_32F, cv::Scalar(0.5));
  expectError([&] { openable::evaluatePrecisionRecall(distances, openable::loadTruthMatrix(path("truth.png"))); },
              "is for a 3x4 matrix, but the distance matrix is 3x3");

  expectError([&] { openable::loadTruthMatrix(path("missing.png")); }, "cannot open");
  write("text.png", "not an image\n");
  expectError([&] { openable::loadTruthMatrix(path("text.png")); }, "cannot read");
  expectError([&] { openable::loadTruthMatrix(path("missing.npy")); }, "cannot open");
  write("complex.npy", npyBytes("{'descr': '<c8', 'fortran_order': False, 'shape': (1, 1), }", std::string(8, '\0')));
  expectError([&] { openable::loadTruthMatrix(path("complex.npy")); }, "dtype '<c8'");
  write("short.npy", npyBytes("{'descr': '|u1', 'fortran_order': False, 'shape': (2, 2), }", std::string(3, '\1')));
  expectError([&] { openable::loadTruthMatrix(path("short.npy")); }, "(truncated)");
  write("cube.npy", npyBytes("{'descr': '|u1', 'fortran_order': False, 'shape': (1, 1, 1), }", std::string(1, '\1')));
  expectError([&] { openable::loadTruthMatrix(path("cube.npy")); }, "3 dimensions");
}
