// Ground truth and precision-recall evaluation of distance matrices (the project's version of the
// paper's Fig. 5).
#include "openable/evaluation.h"

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

#include "openable/error.h"
#include "openable/image_source.h"

namespace openable
{
namespace
{
std::string shapeText(int rows, int cols)
{
  return std::to_string(rows) + "x" + std::to_string(cols);
}

/// A double printed with up to 6 significant digits ("0.812", "1", "0.333333"): short for people, exact
/// enough for the plots and tables.
std::string numberText(double value)
{
  if (!std::isfinite(value))
  {
    return value > 0 ? "inf" : (value < 0 ? "-inf" : "nan");
  }
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

std::string jsonEscape(const std::string& text)
{
  std::string out;
  for (char c : text)
  {
    if (c == '"' || c == '\\')
    {
      out.push_back('\\');
      out.push_back(c);
    }
    else if (static_cast<unsigned char>(c) < 0x20)
    {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    }
    else
    {
      out.push_back(c);
    }
  }
  return out;
}

bool isCommentOrBlank(const std::string& line)
{
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

/// Parses `shape=RxC` from a comment line, as the published KITTI ground-truth files declare it.
bool parseDeclaredShape(const std::string& line, int& rows, int& cols)
{
  const size_t pos = line.find("shape=");
  if (pos == std::string::npos)
  {
    return false;
  }
  std::istringstream in(line.substr(pos + 6));
  char times = 0;
  long r = 0, c = 0;
  if (!(in >> r >> times >> c) || times != 'x' || r <= 0 || c <= 0 || r > INT32_MAX || c > INT32_MAX)
  {
    return false;
  }
  rows = static_cast<int>(r);
  cols = static_cast<int>(c);
  return true;
}

std::ifstream openText(const std::string& path, const std::string& what)
{
  std::ifstream in(path);
  if (!in)
  {
    throw Error(what + ": cannot open '" + path + "' (missing or unreadable)");
  }
  return in;
}

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
// GroundTruth

GroundTruth::GroundTruth(std::vector<std::vector<int>> anchors, int tolerance, int num_queries, int num_references,
                         bool exact_shape, std::string description)
  : tolerance_(tolerance),
    num_queries_(num_queries),
    num_references_(num_references),
    exact_shape_(exact_shape),
    description_(std::move(description))
{
  if (tolerance_ < 0)
  {
    throw Error("ground truth: tolerance must be >= 0 frames, got " + std::to_string(tolerance_));
  }
  for (size_t q = 0; q < anchors.size(); ++q)
  {
    std::vector<int>& list = anchors[q];
    if (list.empty())
    {
      continue;
    }
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    anchors_.emplace(static_cast<int>(q), std::move(list));
  }
}

GroundTruth GroundTruth::fromPairs(const std::vector<std::pair<int, int>>& pairs, int tolerance, int num_queries,
                                   int num_references, bool exact_shape, std::string description)
{
  GroundTruth truth({}, tolerance, num_queries, num_references, exact_shape, std::move(description));
  for (const auto& pair : pairs)
  {
    truth.anchors_[pair.first].push_back(pair.second);
  }
  for (auto& entry : truth.anchors_)
  {
    std::sort(entry.second.begin(), entry.second.end());
    entry.second.erase(std::unique(entry.second.begin(), entry.second.end()), entry.second.end());
  }
  return truth;
}

const std::vector<int>& GroundTruth::anchors(int query) const
{
  static const std::vector<int> kNone;
  const auto found = anchors_.find(query);
  return found == anchors_.end() ? kNone : found->second;
}

bool GroundTruth::isMatch(int query, int reference) const
{
  const std::vector<int>& list = anchors(query);
  // The first anchor >= reference - tolerance is the only one that can be within tolerance from below.
  // In 64 bits: a tolerance near INT_MAX (e.g. "every frame matches") must not wrap.
  const int64_t low = int64_t(reference) - tolerance_;
  const auto it = std::lower_bound(list.begin(), list.end(), low, [](int a, int64_t b) { return a < b; });
  return it != list.end() && int64_t(*it) <= int64_t(reference) + tolerance_;
}

size_t GroundTruth::numPairs() const
{
  size_t pairs = 0;
  for (const auto& entry : anchors_)
  {
    pairs += entry.second.size();
  }
  return pairs;
}

void GroundTruth::checkFits(int rows, int cols) const
{
  if (exact_shape_ && (rows != num_queries_ || cols != num_references_))
  {
    throw Error("ground truth (" + description_ + ") is for a " + shapeText(num_queries_, num_references_) +
                " matrix, but the distance matrix is " + shapeText(rows, cols));
  }
  if (!exact_shape_ && (rows < num_queries_ || cols < num_references_))
  {
    throw Error("ground truth (" + description_ + ") needs at least " + shapeText(num_queries_, num_references_) +
                " (queries x references), but the distance matrix is " + shapeText(rows, cols));
  }
  for (const auto& entry : anchors_)
  {
    if (entry.first >= rows || entry.second.back() >= cols)
    {
      throw Error("ground truth (" + description_ + ") pair (" + std::to_string(entry.first) + ", " +
                  std::to_string(entry.second.back()) + ") is out of range for a " + shapeText(rows, cols) +
                  " distance matrix");
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// Ground-truth sources

GroundTruth alignedGroundTruth(int num_queries, int num_references, int tolerance)
{
  if (num_queries <= 0 || num_references <= 0)
  {
    throw Error("aligned ground truth: the matrix has no rows or columns (" + shapeText(num_queries, num_references) +
                ")");
  }
  if (num_queries != num_references)
  {
    throw Error("aligned ground truth: traversals in step need as many queries as references, but the matrix is " +
                shapeText(num_queries, num_references) + " (queries x references)");
  }
  if (tolerance < 0)
  {
    throw Error("aligned ground truth: tolerance must be >= 0 frames, got " + std::to_string(tolerance));
  }
  std::vector<std::vector<int>> anchors(num_queries);
  for (int q = 0; q < num_queries; ++q)
  {
    anchors[q].push_back(q);
  }
  return GroundTruth(std::move(anchors), tolerance, num_queries, num_references, true,
                     "aligned traversals, |i - j| <= " + std::to_string(tolerance));
}

GroundTruth loadPairsGroundTruth(const std::string& path, int pair_tolerance)
{
  if (pair_tolerance < 0)
  {
    throw Error("pairs ground truth: tolerance must be >= 0 frames, got " + std::to_string(pair_tolerance));
  }
  std::ifstream in = openText(path, "pairs ground truth");
  std::vector<std::pair<int, int>> pairs;
  int declared_rows = 0, declared_cols = 0, max_i = -1, max_j = -1;
  bool declared = false;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (isCommentOrBlank(line))
    {
      declared = declared || parseDeclaredShape(line, declared_rows, declared_cols);
      continue;
    }
    std::istringstream fields(line);
    long i = 0, j = 0;
    std::string rest;
    const bool parsed = static_cast<bool>(fields >> i >> j);
    // Anything after the two indices must be a comment.
    const bool trailing = parsed && (fields >> rest) && rest[0] != '#';
    // Below INT32_MAX: the matrix needs index + 1 rows or columns, which must fit an int.
    if (!parsed || trailing || i < 0 || j < 0 || i >= INT32_MAX || j >= INT32_MAX)
    {
      throw Error("pairs ground truth: '" + path + "' line " + std::to_string(number) +
                  " is not two non-negative frame indices 'i j': '" + line + "'");
    }
    if (declared && (i >= declared_rows || j >= declared_cols))
    {
      throw Error("pairs ground truth: '" + path + "' line " + std::to_string(number) + " pair (" + std::to_string(i) +
                  ", " + std::to_string(j) + ") is out of range for its declared shape " +
                  shapeText(declared_rows, declared_cols));
    }
    pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
    max_i = std::max(max_i, static_cast<int>(i));
    max_j = std::max(max_j, static_cast<int>(j));
  }
  std::string description = "pairs from " + path + ", tolerance " + std::to_string(pair_tolerance);
  if (declared)
  {
    return GroundTruth::fromPairs(pairs, pair_tolerance, declared_rows, declared_cols, true, description);
  }
  return GroundTruth::fromPairs(pairs, pair_tolerance, max_i + 1, max_j + 1, false, description);
}

std::vector<cv::Vec3d> loadKittiPositions(const std::string& path)
{
  std::ifstream in = openText(path, "KITTI poses");
  std::vector<cv::Vec3d> positions;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (isCommentOrBlank(line))
    {
      continue;
    }
    std::istringstream fields(line);
    double m[12];
    std::string rest;
    int read = 0;
    while (read < 12 && fields >> m[read])
    {
      ++read;
    }
    if (read != 12 || (fields >> rest))
    {
      throw Error("KITTI poses: '" + path + "' line " + std::to_string(number) +
                  " is not a row-major 3x4 pose (12 numbers)");
    }
    // Row-major [R|t]: the translation is the 4th, 8th and 12th number.
    positions.emplace_back(m[3], m[7], m[11]);
  }
  if (positions.empty())
  {
    throw Error("KITTI poses: '" + path + "' holds no pose");
  }
  return positions;
}

GroundTruth posesGroundTruth(const std::vector<cv::Vec3d>& positions, double distance, int exclusion)
{
  if (!(distance > 0.0) || exclusion < 0)
  {
    throw Error("poses ground truth: need distance > 0 m and exclusion >= 0 frames, got " + numberText(distance) +
                " m and " + std::to_string(exclusion));
  }
  if (positions.empty())
  {
    throw Error("poses ground truth: no positions");
  }
  const int n = static_cast<int>(positions.size());
  const double squared = distance * distance;
  std::vector<std::vector<int>> anchors(n);
  for (int i = 0; i < n; ++i)
  {
    for (int j = 0; j < i - exclusion; ++j)
    {
      const cv::Vec3d d = positions[i] - positions[j];
      if (d.dot(d) < squared)
      {
        anchors[i].push_back(j);
      }
    }
  }
  return GroundTruth(
      std::move(anchors), 0, n, n, true,
      "poses, distance < " + numberText(distance) + " m, more than " + std::to_string(exclusion) + " frames apart");
}

// ---------------------------------------------------------------------------------------------------
// Agreement of two ground truths

double GroundTruthAgreement::pairPrecision() const
{
  return candidate_pairs == 0 ? 0.0 : static_cast<double>(common_pairs) / static_cast<double>(candidate_pairs);
}

double GroundTruthAgreement::pairRecall() const
{
  return reference_pairs == 0 ? 0.0 : static_cast<double>(common_pairs) / static_cast<double>(reference_pairs);
}

double GroundTruthAgreement::pairJaccard() const
{
  const size_t united = candidate_pairs + reference_pairs - common_pairs;
  return united == 0 ? 1.0 : static_cast<double>(common_pairs) / static_cast<double>(united);
}

double GroundTruthAgreement::queryJaccard() const
{
  const size_t united = candidate_queries + reference_queries - common_queries;
  return united == 0 ? 1.0 : static_cast<double>(common_queries) / static_cast<double>(united);
}

GroundTruthAgreement compareGroundTruth(const GroundTruth& candidate, const GroundTruth& reference)
{
  GroundTruthAgreement agreement;
  // Only queries with anchors on either side count, so visit those rather than every possible query.
  std::set<int> queries;
  for (const GroundTruth* truth : {&candidate, &reference})
  {
    for (const auto& entry : truth->anchorsByQuery())
    {
      queries.insert(entry.first);
    }
  }
  std::vector<int> common;
  for (int q : queries)
  {
    const std::vector<int>& a = candidate.anchors(q);
    const std::vector<int>& b = reference.anchors(q);
    common.clear();
    std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common));
    agreement.candidate_pairs += a.size();
    agreement.reference_pairs += b.size();
    agreement.common_pairs += common.size();
    agreement.candidate_queries += a.empty() ? 0 : 1;
    agreement.reference_queries += b.empty() ? 0 : 1;
    agreement.common_queries += (!a.empty() && !b.empty()) ? 1 : 0;
  }
  return agreement;
}

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
// Query masks

std::vector<bool> brightFrameMask(const std::vector<cv::Mat>& images, double min_mean)
{
  std::vector<bool> mask;
  mask.reserve(images.size());
  for (size_t i = 0; i < images.size(); ++i)
  {
    if (images[i].empty())
    {
      throw Error("dark-frame mask: image " + std::to_string(i) + " is empty");
    }
    if (images[i].depth() != CV_8U && images[i].depth() != CV_16U)
    {
      throw Error("dark-frame mask: image " + std::to_string(i) + " is not 8-bit or 16-bit");
    }
    cv::Mat eight_bit = images[i];
    if (images[i].depth() == CV_16U)
    {
      images[i].convertTo(eight_bit, CV_8U, 1.0 / 257.0);  // the threshold is on the 8-bit scale
    }
    const cv::Scalar means = cv::mean(eight_bit);
    double mean = 0.0;
    for (int c = 0; c < eight_bit.channels(); ++c)
    {
      mean += means[c];
    }
    mask.push_back(mean / eight_bit.channels() >= min_mean);
  }
  return mask;
}

std::vector<bool> brightFrameMask(const std::string& image_source, double min_mean)
{
  ImageSource source(image_source);
  std::vector<bool> mask;
  cv::Mat image;
  std::string name;
  while (source.next(image, name))
  {
    if (image.empty())
    {
      throw Error("dark-frame mask: cannot read frame '" + name + "' of '" + image_source + "'");
    }
    mask.push_back(brightFrameMask(std::vector<cv::Mat>{image}, min_mean).front());
  }
  return mask;
}

std::vector<bool> loadQueryMask(const std::string& path)
{
  std::ifstream in = openText(path, "query mask");
  std::vector<bool> mask;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number)
  {
    if (isCommentOrBlank(line))
    {
      continue;
    }
    std::istringstream fields(line);
    std::string value, rest;
    fields >> value;
    if ((value != "0" && value != "1") || (fields >> rest))
    {
      throw Error("query mask: '" + path + "' line " + std::to_string(number) +
                  " is not 1 (evaluated) or 0 (left out): '" + line + "'");
    }
    mask.push_back(value == "1");
  }
  return mask;
}

void saveQueryMask(const std::string& path, const std::vector<bool>& mask)
{
  std::string text = "# one line per query: 1 = evaluated, 0 = left out\n";
  for (bool keep : mask)
  {
    text += keep ? "1\n" : "0\n";
  }
  writeFileAtomically(path, text);
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

// ---------------------------------------------------------------------------------------------------
// Plot

namespace
{
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrid(225, 225, 225);
const int kFont = cv::FONT_HERSHEY_SIMPLEX;

/// Distinguishable colours (BGR) for overlaid curves; repeats after the last.
cv::Scalar seriesColour(size_t index)
{
  static const cv::Scalar kColours[] = {{180, 119, 31},  {14, 127, 255}, {44, 160, 44},   {40, 39, 214},
                                        {189, 103, 148}, {75, 86, 140},  {194, 119, 227}, {34, 189, 188}};
  return kColours[index % (sizeof(kColours) / sizeof(kColours[0]))];
}

void putCentred(cv::Mat& image, const std::string& text, cv::Point centre, double scale, int thickness)
{
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::putText(image, text, cv::Point(centre.x - size.width / 2, centre.y + size.height / 2), kFont, scale, kBlack,
              thickness, cv::LINE_AA);
}

/// Text turned 90 degrees counter-clockwise (the y-axis label), centred on `centre`.
void putVertical(cv::Mat& image, const std::string& text, cv::Point centre, double scale, int thickness)
{
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, thickness, &baseline);
  cv::Mat strip(size.height + baseline + 4, size.width + 4, image.type(), cv::Scalar::all(255));
  cv::putText(strip, text, cv::Point(2, size.height + 2), kFont, scale, kBlack, thickness, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect target(centre.x - turned.cols / 2, centre.y - turned.rows / 2, turned.cols, turned.rows);
  const cv::Rect inside = target & cv::Rect(0, 0, image.cols, image.rows);
  turned(cv::Rect(inside.x - target.x, inside.y - target.y, inside.width, inside.height)).copyTo(image(inside));
}

/// Grid, ticks every 0.1 with labels, axis labels; returns nothing, draws into `image` around `area`.
void drawAxes(cv::Mat& image, const cv::Rect& area, double scale)
{
  for (int k = 0; k <= 10; ++k)
  {
    const int x = area.x + area.width * k / 10;
    const int y = area.y + area.height - area.height * k / 10;
    cv::line(image, cv::Point(x, area.y), cv::Point(x, area.y + area.height), kGrid, 1);
    cv::line(image, cv::Point(area.x, y), cv::Point(area.x + area.width, y), kGrid, 1);
    cv::line(image, cv::Point(x, area.y + area.height), cv::Point(x, area.y + area.height + 6), kBlack, 1);
    cv::line(image, cv::Point(area.x - 6, y), cv::Point(area.x, y), kBlack, 1);
    std::ostringstream label;
    label << std::fixed << std::setprecision(1) << k / 10.0;
    putCentred(image, label.str(), cv::Point(x, area.y + area.height + 20), 0.45 * scale, 1);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(label.str(), kFont, 0.45 * scale, 1, &baseline);
    cv::putText(image, label.str(), cv::Point(area.x - 10 - size.width, y + size.height / 2), kFont, 0.45 * scale,
                kBlack, 1, cv::LINE_AA);
  }
  cv::rectangle(image, area, kBlack, 1);
  putCentred(image, "recall", cv::Point(area.x + area.width / 2, area.y + area.height + 45), 0.6 * scale, 1);
  putVertical(image, "precision", cv::Point(area.x - 55, area.y + area.height / 2), 0.6 * scale, 1);
}

cv::Point plotPoint(const cv::Rect& area, double recall, double precision)
{
  return cv::Point(area.x + static_cast<int>(std::lround(recall * area.width)),
                   area.y + area.height - static_cast<int>(std::lround(precision * area.height)));
}

void drawCurve(cv::Mat& image, const cv::Rect& area, const std::vector<PrPoint>& curve, const cv::Scalar& colour)
{
  std::vector<cv::Point> points;
  for (const PrPoint& p : curve)
  {
    points.push_back(plotPoint(area, p.recall, p.precision));
  }
  if (points.size() == 1)
  {
    cv::circle(image, points.front(), 3, colour, cv::FILLED, cv::LINE_AA);
  }
  cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
}

/// The corner of the plot area where a box of `size` covers the fewest curve pixels (`ink`, non-zero where
/// a curve is drawn), so the legend hides as little as possible; lower right first, where PR curves
/// rarely go (high recall at low precision).
cv::Rect quietestCorner(const cv::Mat& ink, const cv::Rect& area, cv::Size size)
{
  const int margin = 10;
  const int left = area.x + margin, right = area.x + area.width - margin - size.width;
  const int top = area.y + margin, bottom = area.y + area.height - margin - size.height;
  const cv::Point corners[] = {{right, bottom}, {left, bottom}, {right, top}, {left, top}};
  cv::Rect best;
  int best_ink = -1;
  for (const cv::Point& corner : corners)
  {
    const cv::Rect box = cv::Rect(corner, size) & cv::Rect(0, 0, ink.cols, ink.rows);
    const int covered = cv::countNonZero(ink(box));
    if (best_ink < 0 || covered < best_ink)
    {
      best = box;
      best_ink = covered;
    }
  }
  return best;
}

void drawLegend(cv::Mat& image, const cv::Mat& ink, const cv::Rect& area, const std::vector<PrPlotSeries>& series,
                double scale)
{
  const int line_height = static_cast<int>(22 * scale);
  int width = 0;
  std::vector<std::string> labels;
  for (const PrPlotSeries& s : series)
  {
    labels.push_back(s.name + " (AUC " + numberText(std::round(s.result.auc * 1000.0) / 1000.0) + ")");
    int baseline = 0;
    width = std::max(width, cv::getTextSize(labels.back(), kFont, 0.45 * scale, 1, &baseline).width);
  }
  const cv::Rect box =
      quietestCorner(ink, area, cv::Size(width + 50, line_height * static_cast<int>(series.size()) + 8));
  cv::rectangle(image, box, cv::Scalar::all(255), cv::FILLED);
  cv::rectangle(image, box, kBlack, 1);
  for (size_t i = 0; i < series.size(); ++i)
  {
    const int y = box.y + 4 + line_height * static_cast<int>(i) + line_height / 2;
    cv::line(image, cv::Point(box.x + 8, y), cv::Point(box.x + 36, y), seriesColour(i), 2, cv::LINE_AA);
    cv::putText(image, labels[i], cv::Point(box.x + 44, y + 5), kFont, 0.45 * scale, kBlack, 1, cv::LINE_AA);
  }
}

}  // namespace

cv::Mat drawPrCurves(const std::vector<PrPlotSeries>& series, const std::string& title, cv::Size size)
{
  if (series.empty())
  {
    throw Error("PR plot: no curve to draw");
  }
  if (size.width < 320 || size.height < 240)
  {
    throw Error("PR plot: size " + shapeText(size.width, size.height) + " is too small (at least 320x240)");
  }
  // Text scales with the image so labels stay readable from 320x240 to poster size.
  const double scale = std::min(size.width / 800.0, size.height / 600.0) * 1.25;
  cv::Mat image(size, CV_8UC3, cv::Scalar::all(255));
  const int left = static_cast<int>(95 * scale), bottom = static_cast<int>(70 * scale);
  const int top = static_cast<int>(55 * scale), right = static_cast<int>(30 * scale);
  const cv::Rect area(left, top, size.width - left - right, size.height - top - bottom);
  drawAxes(image, area, scale);
  cv::Mat ink(size, CV_8U, cv::Scalar(0));
  for (size_t i = 0; i < series.size(); ++i)
  {
    drawCurve(image, area, series[i].result.curve, seriesColour(i));
    drawCurve(ink, area, series[i].result.curve, cv::Scalar(255));
  }
  drawLegend(image, ink, area, series, scale);
  std::string heading = title;
  if (series.size() == 1)
  {
    heading += (heading.empty() ? "" : " - ") + std::string("AUC ") +
               numberText(std::round(series.front().result.auc * 1000.0) / 1000.0);
  }
  // A long title is set smaller rather than cut off at the image edges.
  const int thickness = std::max(1, static_cast<int>(std::lround(scale)));
  double title_scale = 0.7 * scale;
  int baseline = 0;
  while (title_scale > 0.3 &&
         cv::getTextSize(heading, kFont, title_scale, thickness, &baseline).width > size.width - 20)
  {
    title_scale *= 0.95;
  }
  putCentred(image, heading, cv::Point(size.width / 2, top / 2), title_scale, thickness);
  return image;
}

}  // namespace openable
