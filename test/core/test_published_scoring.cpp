// Published loop closures: reading loop_closures.csv and decisions.csv, precision and recall of the published
// set and the score PR curve, with values worked out by hand, and a clear error for every bad file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/evaluation/ground_truth_sources.h"
#include "openable/detection/loop_csv.h"
#include "openable/evaluation/loop_list.h"
#include "openable/evaluation/published_scoring.h"

namespace fs = std::filesystem;
using openable::DecisionTable;

namespace
{
class PublishedFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() /
           ("openable_test_published_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override
  {
    fs::remove_all(dir_);
  }
  std::string file(const std::string& name, const std::string& text) const
  {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  DecisionTable load(const std::string& text) const
  {
    return openable::loadDecisionTable(file("table.csv", text));
  }
  fs::path dir_;
};

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

/// Ten frames joined at 5: frames 5..9 have a loop (5 positives). Five published rows, two wrong: 7 -> 0
/// (its place is 2) and 3 -> 0 (before the join). Frame 6 is published twice, both right: recalled once.
const char kFivePublished[] =
    "query,match,distance,score,status\n"
    "5,0,0.1,0.9,published\n"
    "6,1,0.1,0.8,published\n"
    "6,1,0.12,0.7,published\n"
    "7,0,0.2,0.7,published\n"
    "3,0,0.2,0.6,published\n";

/// Eight frames joined at 4 (positives 4..7), one row per frame. By score: 0.95 f4 right; 0.9 f2 wrong
/// (before the join); 0.8 f5 right and f6 wrong (a tie); 0.6 f7 right; 0.5 f3 wrong; 0.2 f1 wrong; f0 has no
/// candidate. Published: f4, f5, f7 (f2 passed the gates but was inconsistent).
const char kEightDecisions[] =
    "query,match,distance,score,status,accepted\n"
    "0,-1,nan,nan,too_early,0\n"
    "1,0,0.5,0.2,not_unique,0\n"
    "2,0,0.4,0.9,inconsistent,1\n"
    "3,1,0.3,0.5,above_threshold,0\n"
    "4,0,0.1,0.95,published,1\n"
    "5,1,0.1,0.8,published,1\n"
    "6,0,0.2,0.8,not_unique,0\n"
    "7,3,0.1,0.6,published,1\n";

}  // namespace

TEST_F(PublishedFiles, LoopClosuresWithPanoramicColumnsInAnyOrder)
{
  const DecisionTable t = load(
      "query,match,distance,score,status,direction,shift\n"
      "12, 3, 0.25, 0.75, published, -1, 4\n"
      "\n"
      "13,4,0.3,1e-3,published,1,0\r\n");
  EXPECT_FALSE(t.per_frame);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].query, 12);
  EXPECT_EQ(t.rows[0].match, 3);
  EXPECT_DOUBLE_EQ(t.rows[0].distance, 0.25);
  EXPECT_DOUBLE_EQ(t.rows[0].score, 0.75);
  EXPECT_TRUE(t.rows[0].published());
  EXPECT_EQ(t.rows[0].line, 2);
  EXPECT_EQ(t.rows[1].line, 4);
  EXPECT_DOUBLE_EQ(t.rows[1].score, 1e-3);

  const DecisionTable swapped = load("status,score,distance,match,query\npublished,0.5,0.2,1,9\n");
  ASSERT_EQ(swapped.rows.size(), 1u);
  EXPECT_EQ(swapped.rows[0].query, 9);
  EXPECT_EQ(swapped.rows[0].match, 1);
}

TEST_F(PublishedFiles, DecisionsWithoutCandidateAndAcceptedFlags)
{
  const DecisionTable t = load(kEightDecisions);
  EXPECT_TRUE(t.per_frame);
  ASSERT_EQ(t.rows.size(), 8u);
  EXPECT_EQ(t.rows[0].match, -1);
  EXPECT_TRUE(std::isnan(t.rows[0].distance));
  EXPECT_TRUE(std::isnan(t.rows[0].score));
  EXPECT_EQ(t.rows[0].status, "too_early");
  EXPECT_FALSE(t.rows[0].accepted);
  EXPECT_TRUE(t.rows[2].accepted);
  EXPECT_FALSE(t.rows[2].published());
}

TEST_F(PublishedFiles, BadFilesAreOneLineErrorsNamingTheLine)
{
  expectError([&] { openable::loadDecisionTable(file("none/x.csv", "")); }, "cannot open");
  expectError([&] { load(""); }, "is empty");
  // loop_closures.csv of an openable_offline without scores.
  expectError([&] { load("query,match,distance\n1,0,0.2\n"); }, "has no 'score' column (header 'query,match,distance'");
  expectError([&] { load("query,match,distance,score\n1,0,0.2,0.5\n"); }, "has no 'status' column");
  expectError([&] { load("query,match,distance,score,status\n1,0,0.2,0.5,published\n2,0,0.2,published\n"); },
              "line 3 has 4 fields, the header 5");
  expectError([&] { load("query,match,distance,score,status,accepted\n1,0,0.2,0.5,maybe,0\n"); },
              "line 2: unknown status 'maybe' (known: published, not_keyframe, standstill, time_jump, too_early,");
  expectError([&] { load("query,match,distance,score,status,accepted\n1,0,0.2,0.5,published,yes\n"); },
              "accepted 'yes' is not 0 or 1");
  expectError([&] { load("query,match,distance,score,status\nx,0,0.2,0.5,published\n"); },
              "query 'x' is not an integer >= 0");
  expectError([&] { load("query,match,distance,score,status\n-1,0,0.2,0.5,published\n"); }, "query '-1'");
  expectError([&] { load("query,match,distance,score,status,accepted\n1,-2,0.2,0.5,too_early,0\n"); },
              "match '-2' is not an integer >= -1");
  expectError([&] { load("query,match,distance,score,status\n1,0,0.2,high,published\n"); },
              "score 'high' is not a number");
  expectError([&] { load("query,match,distance,score,status,accepted\n1,-1,nan,nan,published,1\n"); },
              "a published loop closure without a match");
  expectError([&] { load("query,match,distance,score,status\n1,0,0.2,0.5,not_unique\n"); },
              "line 2: status 'not_unique' in a loop closures file");
}

TEST_F(PublishedFiles, FivePublishedTwoWrongIsPrecisionPointSixAndRecallCountsFrames)
{
  const openable::PublishedScore s =
      openable::scorePublished(load(kFivePublished), openable::joinedGroundTruth(10, 5), 10);
  EXPECT_EQ(s.frames, 10);
  EXPECT_EQ(s.published, 5);
  EXPECT_EQ(s.correct, 3);
  EXPECT_EQ(s.wrong(), 2);
  EXPECT_DOUBLE_EQ(s.precision(), 0.6);
  EXPECT_EQ(s.positive_frames, 5);
  EXPECT_EQ(s.recalled_frames, 2);  // 5 and 6, frame 6 once although published twice
  EXPECT_DOUBLE_EQ(s.recall(), 0.4);

  // With tolerance 2, 7 -> 0 is right too (|0 - 2| <= 2): frame 7 is recalled.
  const openable::PublishedScore tolerant =
      openable::scorePublished(load(kFivePublished), openable::joinedGroundTruth(10, 5, 2), 10);
  EXPECT_EQ(tolerant.wrong(), 1);
  EXPECT_EQ(tolerant.recalled_frames, 3);

  // A frame published once right and once wrong: recalled, and both rows count for precision.
  const openable::PublishedScore mixed = openable::scorePublished(
      load("query,match,distance,score,status\n6,1,0.1,0.9,published\n6,4,0.3,0.5,published\n"),
      openable::joinedGroundTruth(10, 5), 10);
  EXPECT_DOUBLE_EQ(mixed.precision(), 0.5);
  EXPECT_EQ(mixed.recalled_frames, 1);
}

TEST_F(PublishedFiles, DecisionsFilePublishesOnlyStatusPublished)
{
  const openable::PublishedScore s =
      openable::scorePublished(load(kEightDecisions), openable::joinedGroundTruth(8, 4), 8);
  EXPECT_EQ(s.published, 3);  // not frame 2, accepted but inconsistent
  EXPECT_EQ(s.correct, 3);
  EXPECT_DOUBLE_EQ(s.precision(), 1.0);
  EXPECT_DOUBLE_EQ(s.recall(), 0.75);
}

TEST_F(PublishedFiles, NothingPublishedHasNoPrecisionAndJsonSaysNull)
{
  const openable::PublishedScore s =
      openable::scorePublished(load("query,match,distance,score,status\n"), openable::joinedGroundTruth(4, 2), 4);
  EXPECT_EQ(s.published, 0);
  EXPECT_TRUE(std::isnan(s.precision()));
  EXPECT_DOUBLE_EQ(s.recall(), 0.0);
  EXPECT_EQ(openable::publishedMetricsJson(s, nullptr, "run \"a\"", "joined"),
            "{\"name\": \"run \\\"a\\\"\", \"published\": 0, \"correct\": 0, \"wrong\": 0, \"precision\": null, "
            "\"recall\": 0, \"frames\": 4, \"positive_frames\": 2, \"recalled_frames\": 0, \"ground_truth\": "
            "\"joined\"}");
}

TEST_F(PublishedFiles, StreamAndGroundTruthThatDoNotFitAreClearErrors)
{
  const DecisionTable five = load(kFivePublished);
  expectError([&] { openable::scorePublished(five, openable::joinedGroundTruth(7, 3), 7); },
              "line 5: query 7 is not a frame of the 7-frame stream");
  expectError([&] { openable::scorePublished(five, openable::joinedGroundTruth(12, 6), 10); },
              "is for 12 frames, but the stream has 10");
  const openable::GroundTruth empty = openable::truthMatrixGroundTruth(cv::Mat::zeros(10, 10, CV_8U), "of zeros");
  expectError([&] { openable::scorePublished(five, empty, 10); }, "recall is undefined");
  expectError([&] { openable::scorePublished(five, openable::joinedGroundTruth(10, 5), 0); }, "no frames");
}

TEST_F(PublishedFiles, ScoreCurveOfEightFramesByHand)
{
  const openable::EvaluationResult r =
      openable::scorePrecisionRecall(load(kEightDecisions), openable::joinedGroundTruth(8, 4), 8);
  const std::vector<openable::PrPoint> expected = {{0.95, 1.0, 0.25}, {0.9, 0.5, 0.25}, {0.8, 0.5, 0.5},
                                                   {0.6, 0.6, 0.75},  {0.5, 0.5, 0.75}, {0.2, 3.0 / 7.0, 0.75}};
  ASSERT_EQ(r.curve.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i)
  {
    EXPECT_DOUBLE_EQ(r.curve[i].threshold, expected[i].threshold) << i;
    EXPECT_DOUBLE_EQ(r.curve[i].precision, expected[i].precision) << i;
    EXPECT_DOUBLE_EQ(r.curve[i].recall, expected[i].recall) << i;
  }
  EXPECT_DOUBLE_EQ(r.auc, 0.25 * 1.0 + 0.25 * 0.5 + 0.25 * 0.6);
  EXPECT_DOUBLE_EQ(r.max_recall_at_100_precision, 0.25);
  EXPECT_DOUBLE_EQ(r.recall_at_1, 0.75);
  EXPECT_EQ(r.evaluated_queries, 8);
  EXPECT_EQ(r.positive_queries, 4);
  EXPECT_EQ(r.queries_without_prediction, 1);
  ASSERT_EQ(r.predictions.size(), 8u);
  EXPECT_EQ(r.predictions[6].match, 0);
  EXPECT_FALSE(r.predictions[6].correct);

  const openable::PublishedScore s =
      openable::scorePublished(load(kEightDecisions), openable::joinedGroundTruth(8, 4), 8);
  EXPECT_EQ(openable::publishedMetricsJson(s, &r, "run", "joined"),
            "{\"name\": \"run\", \"published\": 3, \"correct\": 3, \"wrong\": 0, \"precision\": 1, \"recall\": 0.75, "
            "\"frames\": 8, \"positive_frames\": 4, \"recalled_frames\": 3, \"score_auc\": 0.525, "
            "\"score_max_recall_at_100_precision\": 0.25, \"score_recall_at_1\": 0.75, "
            "\"frames_without_candidate\": 1, \"auc_rule\": \"step-wise average precision\", \"ground_truth\": "
            "\"joined\"}");
}

TEST_F(PublishedFiles, ScoreCurveNeedsOneRowPerFrame)
{
  const openable::GroundTruth truth = openable::joinedGroundTruth(10, 5);
  expectError([&] { openable::scorePrecisionRecall(load(kFivePublished), truth, 10); }, "needs a decisions.csv");
  expectError(
      [&]
      {
        openable::scorePrecisionRecall(load("query,match,distance,score,status,accepted\n"
                                            "5,0,0.1,0.9,published,1\n"
                                            "5,0,0.1,0.9,published,1\n"),
                                       truth, 10);
      },
      "lists frame 5 twice (lines 2 and 3)");
  // A match that has no finite score cannot be ranked: no prediction.
  const openable::EvaluationResult r = openable::scorePrecisionRecall(
      load("query,match,distance,score,status,accepted\n5,0,0.1,nan,too_early,0\n6,1,0.1,0.5,published,1\n"), truth,
      10);
  EXPECT_EQ(r.queries_without_prediction, 9);
  ASSERT_EQ(r.curve.size(), 1u);
  EXPECT_DOUBLE_EQ(r.curve[0].recall, 0.2);
}

// The one home of the format: what LoopCsvWriter writes is what both readers (loadDecisionTable for
// openable_eval, loadLoopPairs for openable_trajectory) read.
TEST_F(PublishedFiles, WhatTheWriterWritesTheReadersRead)
{
  openable::LoopCsvWriter writer(true);
  openable::LoopCsvFrame early;
  early.query = 0;
  writer.add(early);  // no candidate: match -1, nan
  openable::LoopCsvFrame loop;
  loop.query = 5;
  loop.match = 1;
  loop.has_candidates = true;
  loop.distance = 0.25f;
  loop.score = 0.5f;
  loop.status = openable::FrameStatus::Published;
  loop.direction = -1;
  loop.shift = 2;
  loop.query_session = 3;
  loop.match_session = 1;
  loop.inliers = 23;
  writer.add(loop);
  openable::LoopCsvFrame rival = loop;
  rival.query = 6;
  rival.inliers = -1;
  rival.status = openable::FrameStatus::NotUnique;
  rival.pace = 1.5f;
  writer.add(rival);
  EXPECT_EQ(writer.decisions(),
            "query,match,distance,score,status,accepted,pace,inliers\n"
            "0,-1,nan,nan,too_early,0,nan,-1\n"
            "5,1,0.25,0.5,published,1,1,23\n"
            "6,1,0.25,0.5,not_unique,0,1.5,-1\n");
  EXPECT_EQ(writer.loopClosures(),
            "query,match,distance,score,status,direction,shift,query_session,match_session\n"
            "5,1,0.25,0.5,published,-1,2,3,1\n");
  EXPECT_EQ(openable::LoopCsvWriter(false).loopClosures(),
            "query,match,distance,score,status,query_session,match_session\n");

  const DecisionTable decisions = openable::loadDecisionTable(file("decisions.csv", writer.decisions()));
  ASSERT_TRUE(decisions.per_frame);
  ASSERT_EQ(decisions.rows.size(), 3u);
  EXPECT_TRUE(std::isnan(decisions.rows[0].distance));
  EXPECT_TRUE(decisions.rows[1].accepted);
  EXPECT_EQ(decisions.rows[2].status, "not_unique");
  const std::string loops = file("loop_closures.csv", writer.loopClosures());
  const DecisionTable published = openable::loadDecisionTable(loops);
  ASSERT_FALSE(published.per_frame);
  ASSERT_EQ(published.rows.size(), 1u);
  EXPECT_EQ(published.rows[0].query, 5);
  EXPECT_EQ(published.rows[0].match, 1);
  const std::vector<openable::LoopPair> pairs = openable::loadLoopPairs(loops);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].query, 5);
  EXPECT_EQ(pairs[0].match, 1);
}
