// Ground truth: which reference frames are true matches of each query (aligned traversals, pairs
// files, KITTI poses), and how two ground truths agree.
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
#include "openable/io/kitti.h"

namespace openable
{
using namespace detail;

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
  std::vector<cv::Vec3d> positions;
  for (const KittiMatrix& m : readKittiPoses(path).poses)
    positions.emplace_back(m[3], m[7], m[11]);  // row-major [R|t]: the 4th, 8th and 12th number
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
}  // namespace openable
