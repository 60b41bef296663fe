// Scoring of the loop closures a detector published (loop_closures.csv, decisions.csv) against a ground
// truth: the numbers a user of the published topic cares about, rather than those of the whole matrix.
#include "openable/evaluation/published_scoring.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "openable/error.h"

namespace openable
{
namespace
{
std::string jsonNumber(double value)
{
  if (!std::isfinite(value))
  {
    return "null";
  }
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

/// Frames with a true loop; checks that every row of `table` is a frame of the stream and that a ground
/// truth of fixed shape is for this stream.
int positiveFrames(const DecisionTable& table, const GroundTruth& truth, int num_frames)
{
  if (num_frames <= 0)
  {
    throw Error("published scoring: the stream has no frames");
  }
  if (truth.exactShape() && truth.numQueries() != num_frames)
  {
    throw Error("published scoring: the ground truth (" + truth.description() + ") is for " +
                std::to_string(truth.numQueries()) + " frames, but the stream has " + std::to_string(num_frames));
  }
  for (const DecisionRow& d : table.rows)
  {
    if (d.query >= num_frames)
    {
      throw Error("published scoring: '" + table.path + "' line " + std::to_string(d.line) + ": query " +
                  std::to_string(d.query) + " is not a frame of the " + std::to_string(num_frames) + "-frame stream");
    }
    // A match outside the stream cannot be judged: refused rather than silently counted as wrong (-1 is a
    // frame without a candidate, which a published row cannot be).
    const int references = std::max(num_frames, truth.numReferences());
    if (d.match >= references || d.match < -1 || (d.published() && d.match < 0))
    {
      throw Error("published scoring: '" + table.path + "' line " + std::to_string(d.line) + ": match " +
                  std::to_string(d.match) + " of query " + std::to_string(d.query) + " is not a frame of the " +
                  std::to_string(references) + "-frame stream");
    }
  }
  int positives = 0;
  for (int q = 0; q < num_frames; ++q)
  {
    positives += truth.hasMatch(q) ? 1 : 0;
  }
  if (positives == 0)
  {
    throw Error("published scoring: none of the " + std::to_string(num_frames) +
                " frames has a true loop in the ground truth (" + truth.description() + "), so recall is undefined");
  }
  return positives;
}

/// Best match per frame, one entry per frame in order (match -1 where the frame has none).
std::vector<QueryPrediction> framePredictions(const DecisionTable& decisions, const GroundTruth& truth,
                                              int num_frames, std::vector<double>& scores)
{
  std::vector<QueryPrediction> predictions(num_frames);
  std::vector<int> line_of(num_frames, 0);
  scores.assign(num_frames, std::numeric_limits<double>::quiet_NaN());
  for (const DecisionRow& d : decisions.rows)
  {
    if (line_of[d.query] != 0)
    {
      throw Error("published scoring: '" + decisions.path + "' lists frame " + std::to_string(d.query) +
                  " twice (lines " + std::to_string(line_of[d.query]) + " and " + std::to_string(d.line) +
                  "); decisions.csv has one row per frame");
    }
    line_of[d.query] = d.line;
    // A match that cannot be ranked (no finite score) is not a prediction at any threshold.
    if (d.match >= 0 && std::isfinite(d.score))
    {
      predictions[d.query].match = d.match;
      predictions[d.query].distance = static_cast<float>(d.distance);
      scores[d.query] = d.score;
    }
  }
  for (int q = 0; q < num_frames; ++q)
  {
    QueryPrediction& p = predictions[q];
    p.query = q;
    p.positive = truth.hasMatch(q);
    p.correct = p.match >= 0 && truth.isMatch(q, p.match);
  }
  return predictions;
}

}  // namespace

double PublishedScore::precision() const
{
  return published == 0 ? std::numeric_limits<double>::quiet_NaN()
                        : static_cast<double>(correct) / static_cast<double>(published);
}

double PublishedScore::recall() const
{
  return positive_frames == 0 ? 0.0 : static_cast<double>(recalled_frames) / static_cast<double>(positive_frames);
}

PublishedScore scorePublished(const DecisionTable& table, const GroundTruth& truth, int num_frames)
{
  PublishedScore score;
  score.frames = num_frames;
  score.positive_frames = positiveFrames(table, truth, num_frames);
  std::vector<bool> recalled(num_frames, false);
  for (const DecisionRow& d : table.rows)
  {
    if (!d.published())
    {
      continue;
    }
    ++score.published;
    if (truth.isMatch(d.query, d.match))
    {
      ++score.correct;
      recalled[d.query] = true;
    }
  }
  score.recalled_frames = static_cast<int>(std::count(recalled.begin(), recalled.end(), true));
  return score;
}

EvaluationResult scorePrecisionRecall(const DecisionTable& decisions, const GroundTruth& truth, int num_frames)
{
  if (!decisions.per_frame)
  {
    throw Error(
        "published scoring: the score curve needs a decisions.csv (one row per frame, with an 'accepted' "
        "column), but '" +
        decisions.path + "' is a loop closures file");
  }
  EvaluationResult result;
  result.positive_queries = positiveFrames(decisions, truth, num_frames);
  result.evaluated_queries = num_frames;
  std::vector<double> scores;
  result.predictions = framePredictions(decisions, truth, num_frames, scores);
  std::vector<int> order;
  int correct = 0;
  for (const QueryPrediction& p : result.predictions)
  {
    if (p.match < 0)
    {
      ++result.queries_without_prediction;
      continue;
    }
    order.push_back(p.query);
    correct += p.correct ? 1 : 0;
  }
  result.recall_at_1 = static_cast<double>(correct) / result.positive_queries;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return scores[a] > scores[b]; });
  size_t predicted = 0, true_positives = 0;
  double previous_recall = 0.0;
  while (predicted < order.size())
  {
    // Ties share one threshold: "score >= s" cannot predict one of two equal scores.
    const double threshold = scores[order[predicted]];
    while (predicted < order.size() && scores[order[predicted]] == threshold)
    {
      true_positives += result.predictions[order[predicted]].correct ? 1 : 0;
      ++predicted;
    }
    const double precision = static_cast<double>(true_positives) / static_cast<double>(predicted);
    const double recall = static_cast<double>(true_positives) / result.positive_queries;
    result.curve.push_back({threshold, precision, recall});
    result.auc += (recall - previous_recall) * precision;
    previous_recall = recall;
    if (true_positives == predicted)
    {
      result.max_recall_at_100_precision = recall;
    }
  }
  return result;
}

std::string publishedMetricsJson(const PublishedScore& score, const EvaluationResult* curve, const std::string& name,
                                 const std::string& ground_truth)
{
  std::ostringstream out;
  out << "{\"name\": " << jsonString(name) << ", \"published\": " << score.published
      << ", \"correct\": " << score.correct << ", \"wrong\": " << score.wrong()
      << ", \"precision\": " << jsonNumber(score.precision()) << ", \"recall\": " << jsonNumber(score.recall())
      << ", \"frames\": " << score.frames << ", \"positive_frames\": " << score.positive_frames
      << ", \"recalled_frames\": " << score.recalled_frames;
  if (curve != nullptr)
  {
    out << ", \"score_auc\": " << jsonNumber(curve->auc)
        << ", \"score_max_recall_at_100_precision\": " << jsonNumber(curve->max_recall_at_100_precision)
        << ", \"score_recall_at_1\": " << jsonNumber(curve->recall_at_1)
        << ", \"frames_without_candidate\": " << curve->queries_without_prediction
        << ", \"auc_rule\": \"step-wise average precision\"";
  }
  out << ", \"ground_truth\": " << jsonString(ground_truth) << "}";
  return out.str();
}

}  // namespace openable
