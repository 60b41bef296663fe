// openable_eval end to end: runs the built binary on small .npy files written here and checks what it
// writes and prints, and that bad input gives a non-zero exit with a one-line reason.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "openable/evaluation/evaluation.h"
#include "openable/io/npy.h"

#ifndef OPENABLE_EVAL_BINARY
#error "OPENABLE_EVAL_BINARY (path of the openable_eval executable) must be defined by the build"
#endif

namespace fs = std::filesystem;

namespace
{
const std::string kKitti = OPENABLE_SOURCE_DIR "/../shared/data/kitti";

std::string readText(const std::string& path)
{
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<std::string> lines(const std::string& text)
{
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    out.push_back(line);
  return out;
}

struct ToolRun
{
  int status = -1;
  std::string out;
  std::string err;
};

class EvalToolTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("openable_test_eval_tool_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // The hand-computed four-by-four of test_evaluation.cpp: AUC 5/12, max recall at 100 % 0.25, R@1 0.5.
    matrix_ = (cv::Mat_<float>(4, 4) << 0.1F, 0.5F, 0.9F, 0.9F, 0.2F, 0.8F, 0.9F, 0.9F, 0.9F, 0.9F, 0.3F, 0.9F, 0.9F,
               0.4F, 0.9F, 0.9F);
    openable::writeNpy(path("m.npy"), matrix_);
  }
  void TearDown() override
  {
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const
  {
    return (dir_ / name).string();
  }
  /// Runs openable_eval with `arguments` (already shell-quoted where needed).
  ToolRun run(const std::string& arguments) const
  {
    const std::string command = std::string("'") + OPENABLE_EVAL_BINARY + "' " + arguments + " >'" + path("stdout") +
                                "' 2>'" + path("stderr") + "'";
    const int raw = std::system(command.c_str());
    ToolRun r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    r.out = readText(path("stdout"));
    r.err = readText(path("stderr"));
    return r;
  }
  fs::path dir_;
  cv::Mat matrix_;
};

}  // namespace

TEST_F(EvalToolTest, WritesCurvePlotAndMetricsAndPrintsThem)
{
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --tolerance 0 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 4u) << r.out;
  EXPECT_EQ(printed[0], "auc: 0.416667");
  EXPECT_EQ(printed[1], "max_recall_at_100_precision: 0.25");
  EXPECT_EQ(printed[2], "recall_at_1: 0.5");
  EXPECT_EQ(printed[3],
            "{\"name\": \"m\", \"auc\": 0.416667, \"max_recall_at_100_precision\": 0.25, \"recall_at_1\": 0.5, "
            "\"evaluated_queries\": 4, \"positive_queries\": 4, \"masked_queries\": 0, "
            "\"queries_without_prediction\": 0, \"auc_rule\": \"step-wise average precision\", "
            "\"ground_truth\": \"aligned traversals, |i - j| <= 0\"}");
  EXPECT_EQ(readText(path("out/metrics.json")), printed[3] + "\n");
  EXPECT_EQ(readText(path("out/pr_curve.csv")),
            "threshold,precision,recall\n0.100000001,1,0.25\n0.200000003,0.5,0.25\n0.300000012,0.666666667,0.5\n"
            "0.400000006,0.5,0.5\n");
  const cv::Mat plot = cv::imread(path("out/pr_curve.png"));
  EXPECT_EQ(plot.size(), cv::Size(800, 600));
  EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST_F(EvalToolTest, AcceptsAFolderAMaskAndPairs)
{
  fs::create_directories(path("run"));
  openable::writeNpy(path("run/distance_matrix.npy"), matrix_);
  // Leave out the two wrong queries (1 and 3): every prediction is right.
  openable::saveQueryMask(path("mask.txt"), {true, false, true, false});
  std::ofstream(path("pairs.txt")) << "# shape=4x4\n0 0\n1 1\n2 2\n3 3\n";
  const ToolRun r = run("--matrix '" + path("run") + "' --mask '" + path("mask.txt") + "' --pairs '" +
                        path("pairs.txt") + "' --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 4u);
  EXPECT_EQ(printed[0], "auc: 1");
  EXPECT_EQ(printed[1], "max_recall_at_100_precision: 1");
  EXPECT_EQ(printed[2], "recall_at_1: 1");
  EXPECT_NE(printed[3].find("\"name\": \"run\""), std::string::npos);
  EXPECT_NE(printed[3].find("\"masked_queries\": 2"), std::string::npos);
}

TEST_F(EvalToolTest, MasksNearBlackQueryImages)
{
  // Query images 1 and 3 (the two wrong predictions) are near-black (mean 9 < 10), 0 and 2 are not (10).
  fs::create_directories(path("queries"));
  for (int i = 0; i < 4; ++i)
  {
    const cv::Mat image(32, 64, CV_8UC3, cv::Scalar::all(i % 2 == 1 ? 9 : 10));
    ASSERT_TRUE(cv::imwrite(path("queries/frame_" + std::to_string(i) + ".png"), image));
  }
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --mask-dark '" + path("queries") +
                        "' --tolerance 0 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 4u);
  EXPECT_EQ(printed[0], "auc: 1");
  EXPECT_EQ(printed[2], "recall_at_1: 1");
  EXPECT_EQ(openable::loadQueryMask(path("out/query_mask.txt")), (std::vector<bool>{true, false, true, false}));
}

TEST_F(EvalToolTest, OverlaysSeveralMatrices)
{
  cv::Mat perfect(4, 4, CV_32F, cv::Scalar(1.0F));
  perfect.diag().setTo(0.0F);
  openable::writeNpy(path("p.npy"), perfect);
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --name 'ldb global' --matrix '" + path("p.npy") +
                        "' --name perfect --tolerance 0 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 9u) << r.out;
  EXPECT_EQ(printed[0], "name: ldb global");
  EXPECT_EQ(printed[1], "auc: 0.416667");
  EXPECT_EQ(printed[4], "name: perfect");
  EXPECT_EQ(printed[5], "auc: 1");
  EXPECT_EQ(printed[8].front(), '[');
  EXPECT_TRUE(fs::exists(path("out/pr_curve_ldb_global.csv")));
  EXPECT_TRUE(fs::exists(path("out/pr_curve_perfect.csv")));
  EXPECT_EQ(cv::imread(path("out/pr_curve.png")).size(), cv::Size(800, 600));
}

TEST_F(EvalToolTest, JoinedStreamMakesAcceptancesBeforeTheJoinFalsePositives)
{
  // The four-by-four as one stream joined at 2: rows 0 and 1 have no loop, 2 -> 0 and 3 -> 1 are the truth.
  // Best matches: q0 -> 0 (0.1, false positive), q1 -> 0 (0.2, false positive), q2 -> 2 (0.3, wrong),
  // q3 -> 1 (0.4, right): one true positive, at the last threshold.
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --joined 2 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 4u) << r.out;
  EXPECT_EQ(printed[0], "auc: 0.125");
  EXPECT_EQ(printed[1], "max_recall_at_100_precision: 0");
  EXPECT_EQ(printed[2], "recall_at_1: 0.5");
  EXPECT_NE(printed[3].find("\"ground_truth\": \"joined stream, frame 2 + i is frame i, |match - i| <= 0\""),
            std::string::npos);
  // --tolerance is the joined truth's tolerance: 2 -> 2 is within 2 of 0.
  const ToolRun tolerant =
      run("--matrix '" + path("m.npy") + "' --joined 2 --tolerance 2 --output '" + path("out") + "'");
  ASSERT_EQ(tolerant.status, 0) << tolerant.err;
  EXPECT_EQ(lines(tolerant.out)[2], "recall_at_1: 1");
}

TEST_F(EvalToolTest, TruthMatrixPngMustHaveTheMatrixShape)
{
  cv::Mat truth(4, 4, CV_8U, cv::Scalar(0));
  truth.diag().setTo(255);
  ASSERT_TRUE(cv::imwrite(path("truth.png"), truth));
  ToolRun r = run("--matrix '" + path("m.npy") + "' --truth-matrix '" + path("truth.png") + "' --output '" +
                  path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(lines(r.out)[0], "auc: 0.416667");  // the diagonal is the aligned truth with tolerance 0

  ASSERT_TRUE(cv::imwrite(path("wide.png"), cv::Mat(4, 5, CV_8U, cv::Scalar(255))));
  r = run("--matrix '" + path("m.npy") + "' --truth-matrix '" + path("wide.png") + "' --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find("is for a 4x5 matrix, but the distance matrix is 4x4"), std::string::npos) << r.err;
}

TEST_F(EvalToolTest, ScoresPublishedLoopClosuresAndTheScoreCurveOfAJoinedStream)
{
  // Eight frames joined at 4 (see test_published_scoring.cpp): three published, all right, recall 3/4;
  // over the score, AUC 0.525.
  std::ofstream(path("loop_closures.csv")) << "query,match,distance,score,status\n"
                                              "4,0,0.1,0.95,published\n5,1,0.1,0.8,published\n"
                                              "7,3,0.1,0.6,published\n";
  std::ofstream(path("decisions.csv")) << "query,match,distance,score,status,accepted\n"
                                          "0,-1,nan,nan,too_early,0\n1,0,0.5,0.2,not_unique,0\n"
                                          "2,0,0.4,0.9,inconsistent,1\n3,1,0.3,0.5,above_threshold,0\n"
                                          "4,0,0.1,0.95,published,1\n5,1,0.1,0.8,published,1\n"
                                          "6,0,0.2,0.8,not_unique,0\n7,3,0.1,0.6,published,1\n";
  const ToolRun r = run("--published '" + path("loop_closures.csv") + "' --decisions '" + path("decisions.csv") +
                        "' --joined 4 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 8u) << r.out;
  EXPECT_EQ(printed[0], "published: 3");
  EXPECT_EQ(printed[1], "wrong: 0");
  EXPECT_EQ(printed[2], "precision: 1");
  EXPECT_EQ(printed[3], "recall: 0.75");
  EXPECT_EQ(printed[4], "score_auc: 0.525");
  EXPECT_EQ(printed[5], "score_max_recall_at_100_precision: 0.25");
  EXPECT_EQ(printed[6], "score_recall_at_1: 0.75");
  EXPECT_EQ(printed[7].rfind("{\"name\": \"openable_test_eval_tool_", 0), 0u) << printed[7];
  EXPECT_NE(printed[7].find("\"published\": 3, \"correct\": 3, \"wrong\": 0, \"precision\": 1, \"recall\": 0.75"),
            std::string::npos);
  EXPECT_EQ(readText(path("out/metrics.json")), printed[7] + "\n");
  EXPECT_EQ(readText(path("out/published_pr.csv")),
            "threshold,precision,recall\n0.95,1,0.25\n0.9,0.5,0.25\n0.8,0.5,0.5\n0.6,0.6,0.75\n0.5,0.5,0.75\n"
            "0.2,0.428571429,0.75\n");
  EXPECT_EQ(cv::imread(path("out/published_pr.png")).size(), cv::Size(800, 600));
  EXPECT_TRUE(r.err.empty()) << r.err;

  // The decisions alone: the published set is their 'published' rows, the curve the same; no --decisions.
  const ToolRun alone =
      run("--published '" + path("decisions.csv") + "' --joined 4 --output '" + path("alone") + "'");
  ASSERT_EQ(alone.status, 0) << alone.err;
  EXPECT_EQ(lines(alone.out)[0], "published: 3");
  EXPECT_EQ(lines(alone.out)[4], "score_auc: 0.525");

  // Without decisions: no curve; the stream's length from --frames.
  const ToolRun plain = run("--published '" + path("loop_closures.csv") + "' --joined 4 --frames 8 --tolerance 1" +
                            " --output '" + path("plain") + "'");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(lines(plain.out).size(), 5u) << plain.out;
  EXPECT_FALSE(fs::exists(path("plain/published_pr.csv")));
}

TEST_F(EvalToolTest, BadPublishedInputGivesANonZeroExitAndOneLineReason)
{
  std::ofstream(path("old.csv")) << "query,match,distance\n4,0,0.1\n";
  ToolRun r = run("--published '" + path("old.csv") + "' --joined 4 --frames 8 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find("has no 'score' column"), std::string::npos) << r.err;

  std::ofstream(path("odd.csv")) << "query,match,distance,score,status,accepted\n4,0,0.1,0.9,sure,1\n";
  r = run("--published '" + path("odd.csv") + "' --joined 4 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("unknown status 'sure'"), std::string::npos) << r.err;

  std::ofstream(path("lc.csv")) << "query,match,distance,score,status\n4,0,0.1,0.9,published\n";
  r = run("--published '" + path("lc.csv") + "' --joined 4 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("need the stream's length"), std::string::npos) << r.err;

  r = run("--published '" + path("lc.csv") + "' --joined 9 --frames 8 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("must start at a frame in [1, 7]"), std::string::npos) << r.err;

  // Issue 22: a published match outside the stream was silently counted as wrong.
  std::ofstream(path("far.csv")) << "query,match,distance,score,status\n"
                                    "4,0,0.1,0.9,published\n5,40,0.1,0.9,published\n";
  r = run("--published '" + path("far.csv") + "' --joined 4 --frames 8 --output '" + path("far") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find("line 3: match 40 of query 5 is not a frame of the 8-frame stream"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("far/metrics.json")));

  r = run("--matrix '" + path("m.npy") + "' --joined 0 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;

  r = run("--published '" + path("lc.csv") + "' --matrix '" + path("m.npy") + "' --joined 2 --output x");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no --matrix"), std::string::npos) << r.err;

  r = run("--matrix '" + path("m.npy") + "' --decisions '" + path("lc.csv") + "' --joined 2 --output x");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("need --published"), std::string::npos) << r.err;

  r = run("--published '" + path("lc.csv") + "' --joined 2 --truth-matrix x.png --output x");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("exactly one ground truth"), std::string::npos) << r.err;
}

TEST_F(EvalToolTest, HelpDocumentsThePublishedScoringOptions)
{
  const ToolRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* option : {"--joined", "--truth-matrix", "--published", "--decisions", "--frames",
                             "published_pr.csv", "published_pr.png"})
  {
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  }
}

TEST_F(EvalToolTest, ComparesPosesWithThePublishedKittiGroundTruth)
{
  const ToolRun r =
      run("--poses '" + kKitti + "/poses/06.txt' --compare '" + kKitti + "/loop_ground_truth/kitti06GroundTruth.txt'");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> printed = lines(r.out);
  ASSERT_EQ(printed.size(), 2u);
  // Measured: at the defaults (6 m, 100 frames) every pose loop is a published one, 3253 of 3287.
  EXPECT_EQ(printed[1], "6,100,3253,3287,3253,1,0.989656,0.989656,271,272,271,0.996324");
}

TEST_F(EvalToolTest, BadInputGivesANonZeroExitAndOneLineReason)
{
  std::ofstream(path("far.txt")) << "2 9\n";
  ToolRun r = run("--matrix '" + path("m.npy") + "' --pairs '" + path("far.txt") + "' --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find("needs at least 3x10"), std::string::npos) << r.err;

  r = run("--matrix '" + path("missing.npy") + "' --tolerance 2 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cannot open"), std::string::npos) << r.err;

  std::ofstream(path("text.npy")) << "not a matrix\n";
  r = run("--matrix '" + path("text.npy") + "' --tolerance 2 --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("not a .npy file"), std::string::npos) << r.err;

  r = run("--matrix '" + path("m.npy") + "' --poses '" + kKitti + "/poses/06.txt' --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("is for a 1101x1101 matrix, but the distance matrix is 4x4"), std::string::npos) << r.err;

  r = run("--matrix '" + path("m.npy") + "' --tolerance 2 --pairs '" + path("far.txt") + "' --output x");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("exactly one ground truth"), std::string::npos) << r.err;

  r = run("--matrix '" + path("m.npy") + "' --tolerance two --output x");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;

  r = run("--bogus");
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(path("out/metrics.json")));
}

TEST_F(EvalToolTest, HelpDocumentsEveryOption)
{
  const ToolRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* option :
       {"--matrix", "--name", "--mask", "--mask-dark", "--tolerance", "--pairs", "--pair-tolerance", "--poses",
        "--distance", "--exclusion", "--output", "--compare", "--sweep", "step-wise average precision"})
  {
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  }
}

// Issue 9 (hardening): numbers at the edge of int give the right answer or a one-line error.
TEST_F(EvalToolTest, HugeToleranceMatchesEverythingInsteadOfWrapping)
{
  // Every reference is within 2^31 - 1 frames of every query: each query's best match is correct.
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --tolerance 2147483647 --output '" + path("out") + "'");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("recall_at_1: 1\n"), std::string::npos) << r.out;
}

TEST_F(EvalToolTest, PairBeyondTheMatrixIsAOneLineErrorNotBadAlloc)
{
  const std::string pairs = OPENABLE_SOURCE_DIR "/test/data/repro/p_2147483646.txt";  // "5 5", "2147483646 0"
  const ToolRun r = run("--matrix '" + path("m.npy") + "' --pairs '" + pairs + "' --output '" + path("out") + "'");
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(r.err.find("needs at least 2147483647x6"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("bad_alloc"), std::string::npos) << r.err;
}

// The sweep over D and E (390 settings, each a pass over all frame pairs) shows its progress on stderr
// unless --quiet; the results on stdout are the same either way.
TEST_F(EvalToolTest, SweepShowsProgressUnlessQuiet)
{
  const std::string args =
      "--poses " + kKitti + "/poses/06.txt --compare " + kKitti + "/loop_ground_truth/kitti06GroundTruth.txt --sweep";
  const ToolRun loud = run(args);
  ASSERT_EQ(loud.status, 0) << loud.err;
  EXPECT_NE(loud.err.find("openable_eval: sweep: 390/390 settings (100%), "), std::string::npos) << loud.err;
  EXPECT_NE(loud.out.find("best: distance "), std::string::npos);
  const ToolRun quiet = run(args + " --quiet");
  ASSERT_EQ(quiet.status, 0) << quiet.err;
  EXPECT_TRUE(quiet.err.empty()) << quiet.err;
  EXPECT_EQ(quiet.out, loud.out);
}
