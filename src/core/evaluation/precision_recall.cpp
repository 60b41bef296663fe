// Precision-recall of a distance matrix against a ground truth (the paper's Fig. 5), and its outputs.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "evaluation/evaluation_text.h"
#include "openable/error.h"
#include "openable/evaluation/evaluation.h"

namespace openable
{
using namespace detail;

namespace
{
/// Best match of one row: the column of the smallest finite distance, or -1.
template <typename T>
int bestColumn(const T* row, int cols, float& distance)
{
  int best = -1;
  T best_value = std::numeric_limits<T>::infinity();
  for (int c = 0; c < cols; ++c)
  {
    // Infinite cells are "not compared", like NaN: an infinite distance is no prediction.
    if (std::isfinite(row[c]) && (best < 0 || row[c] < best_value))
    {
      best = c;
      best_value = row[c];
    }
  }
  distance = best < 0 ? 0.0F : static_cast<float>(best_value);
  return best;
}

std::vector<QueryPrediction> predictQueries(const cv::Mat& distances, const GroundTruth& ground_truth,
                                            const std::vector<bool>& query_mask)
{
  std::vector<QueryPrediction> predictions;
  for (int q = 0; q < distances.rows; ++q)
  {
    if (!query_mask.empty() && !query_mask[q])
    {
      continue;
    }
    QueryPrediction p;
    p.query = q;
    p.match = distances.type() == CV_32F ? bestColumn(distances.ptr<float>(q), distances.cols, p.distance)
                                         : bestColumn(distances.ptr<double>(q), distances.cols, p.distance);
    p.positive = ground_truth.hasMatch(q);
    p.correct = p.match >= 0 && ground_truth.isMatch(q, p.match);
    predictions.push_back(p);
  }
  return predictions;
}

/// Sweeps every distinct distance as a threshold; fills curve, AUC and max recall at 100 % precision.
void sweepThresholds(EvaluationResult& result)
{
  std::vector<const QueryPrediction*> order;
  for (const QueryPrediction& p : result.predictions)
  {
    if (p.match >= 0)
    {
      order.push_back(&p);
    }
  }
  std::sort(order.begin(), order.end(),
            [](const QueryPrediction* a, const QueryPrediction* b) { return a->distance < b->distance; });
  const double positives = result.positive_queries;
  size_t accepted = 0, true_positives = 0;
  double previous_recall = 0.0;
  while (accepted < order.size())
  {
    // Ties share one threshold: a threshold cannot accept one of two equal distances.
    const float threshold = order[accepted]->distance;
    while (accepted < order.size() && order[accepted]->distance == threshold)
    {
      true_positives += order[accepted]->correct ? 1 : 0;
      ++accepted;
    }
    const double precision = static_cast<double>(true_positives) / static_cast<double>(accepted);
    const double recall = static_cast<double>(true_positives) / positives;
    result.curve.push_back({threshold, precision, recall});
    result.auc += (recall - previous_recall) * precision;
    previous_recall = recall;
    if (true_positives == accepted)
    {
      result.max_recall_at_100_precision = recall;
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Precision-recall

EvaluationResult evaluatePrecisionRecall(const cv::Mat& distances, const GroundTruth& ground_truth,
                                         const std::vector<bool>& query_mask)
{
  if (distances.empty() || distances.rows <= 0 || distances.cols <= 0)
  {
    throw Error("evaluation: the distance matrix is empty");
  }
  if (distances.dims != 2 || (distances.type() != CV_32FC1 && distances.type() != CV_64FC1))
  {
    throw Error("evaluation: the distance matrix must be 2-D single-channel float32 or float64");
  }
  ground_truth.checkFits(distances.rows, distances.cols);
  if (!query_mask.empty() && query_mask.size() != static_cast<size_t>(distances.rows))
  {
    throw Error("evaluation: the query mask has " + std::to_string(query_mask.size()) + " entries but the matrix has " +
                std::to_string(distances.rows) + " query rows");
  }
  EvaluationResult result;
  result.predictions = predictQueries(distances, ground_truth, query_mask);
  result.evaluated_queries = static_cast<int>(result.predictions.size());
  result.masked_queries = distances.rows - result.evaluated_queries;
  int correct = 0;
  for (const QueryPrediction& p : result.predictions)
  {
    result.positive_queries += p.positive ? 1 : 0;
    result.queries_without_prediction += p.match < 0 ? 1 : 0;
    correct += p.correct ? 1 : 0;
  }
  if (result.positive_queries == 0)
  {
    throw Error("evaluation: none of the " + std::to_string(result.evaluated_queries) +
                " evaluated queries has a true match in the ground truth (" + ground_truth.description() +
                "), so recall is undefined");
  }
  result.recall_at_1 = static_cast<double>(correct) / result.positive_queries;
  sweepThresholds(result);
  return result;
}

// ---------------------------------------------------------------------------------------------------
// Output

std::string prCurveCsv(const EvaluationResult& result)
{
  std::ostringstream out;
  out << "threshold,precision,recall\n" << std::setprecision(9);
  for (const PrPoint& p : result.curve)
  {
    out << p.threshold << ',' << p.precision << ',' << p.recall << '\n';
  }
  return out.str();
}

std::string metricsJson(const EvaluationResult& result, const std::string& name, const std::string& ground_truth)
{
  std::ostringstream out;
  out << "{\"name\": \"" << jsonEscape(name) << "\", \"auc\": " << numberText(result.auc)
      << ", \"max_recall_at_100_precision\": " << numberText(result.max_recall_at_100_precision)
      << ", \"recall_at_1\": " << numberText(result.recall_at_1)
      << ", \"evaluated_queries\": " << result.evaluated_queries
      << ", \"positive_queries\": " << result.positive_queries << ", \"masked_queries\": " << result.masked_queries
      << ", \"queries_without_prediction\": " << result.queries_without_prediction
      << ", \"auc_rule\": \"step-wise average precision\", \"ground_truth\": \"" << jsonEscape(ground_truth) << "\"}";
  return out.str();
}

std::string jsonString(const std::string& text)
{
  return "\"" + jsonEscape(text) + "\"";
}

}  // namespace openable
