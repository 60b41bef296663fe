#pragma once

#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace openable
{
/// Which reference frames (matrix columns) are true matches of each query frame (matrix rows).
///
/// Stored as a sorted list of "anchor" reference frames per query plus a tolerance in frames: query q
/// truly matches reference r when some anchor a of q has |r - a| <= tolerance. Aligned traversals are
/// anchors {q} with tolerance T; a pairs file is its pairs with the pair tolerance; poses give their loop
/// pairs with tolerance 0. Only queries with anchors take memory, so a pairs file naming frame 2^31 - 2
/// costs one entry, not an array of that many queries.
class GroundTruth
{
public:
  /// `anchors[q]` lists the anchors of query q (any order, duplicates allowed). `num_queries` and
  /// `num_references` are the matrix shape the ground truth was made for; `exact_shape` says whether a
  /// matrix must have exactly that shape (true) or at least that many rows and columns (false).
  GroundTruth(std::vector<std::vector<int>> anchors, int tolerance, int num_queries, int num_references,
              bool exact_shape, std::string description);
  /// The same from (query, anchor) pairs (any order, duplicates allowed): memory follows the pairs, not
  /// the largest index.
  static GroundTruth fromPairs(const std::vector<std::pair<int, int>>& pairs, int tolerance, int num_queries,
                               int num_references, bool exact_shape, std::string description);

  int tolerance() const
  {
    return tolerance_;
  }
  int numQueries() const
  {
    return num_queries_;
  }
  int numReferences() const
  {
    return num_references_;
  }
  bool exactShape() const
  {
    return exact_shape_;
  }
  /// Human-readable origin, e.g. "aligned traversals, |i - j| <= 2" (goes into metrics.json).
  const std::string& description() const
  {
    return description_;
  }

  /// Sorted, unique anchors of `query` (empty for a query beyond the stored ones).
  const std::vector<int>& anchors(int query) const;
  bool isMatch(int query, int reference) const;
  /// Whether the query has any true match at all.
  bool hasMatch(int query) const
  {
    return !anchors(query).empty();
  }
  /// Number of (query, anchor) pairs.
  size_t numPairs() const;
  /// Every query that has anchors, with its sorted, unique anchors, by ascending query.
  const std::map<int, std::vector<int>>& anchorsByQuery() const
  {
    return anchors_;
  }

  /// Throws Error when a `rows` x `cols` distance matrix cannot be judged with this ground truth:
  /// wrong shape, or an anchor outside the matrix.
  void checkFits(int rows, int cols) const;

private:
  std::map<int, std::vector<int>> anchors_;
  int tolerance_;
  int num_queries_;
  int num_references_;
  bool exact_shape_;
  std::string description_;
};

/// Two traversals recorded frame by frame in step (Gardens Point, Nordland): query i matches reference j
/// when |i - j| <= tolerance. Throws Error for a negative tolerance, a non-positive size or
/// num_queries != num_references (aligned traversals have as many frames on both sides).
GroundTruth alignedGroundTruth(int num_queries, int num_references, int tolerance);

/// A file of `i j` lines (0-based; frame i closes a loop with frame j; `#` starts a comment, on its own
/// line or after the two indices), as in the published KITTI loop ground truth. Query i also matches
/// references within `pair_tolerance` frames of j. A comment holding `shape=RxC` (as the published files
/// do) fixes the matrix shape exactly; otherwise the matrix needs at least max(i)+1 rows and max(j)+1
/// columns. Throws Error for a missing file, a malformed line (with its number), a negative index, or an
/// index outside a declared shape.
GroundTruth loadPairsGroundTruth(const std::string& path, int pair_tolerance = 0);

/// Camera positions (translation column) of a KITTI odometry poses file: one row-major 3x4 [R|t] per
/// line. Throws Error for a missing file or a line without 12 numbers (with its number).
std::vector<cv::Vec3d> loadKittiPositions(const std::string& path);

/// Defaults for loops from poses, chosen by comparing with the published ground truth of KITTI 00, 05 and
/// 06 (doc/results.md, "KITTI ground truth from poses").
constexpr double kDefaultLoopDistance = 6.0;
constexpr int kDefaultLoopExclusion = 100;

/// Loops of one sequence from its positions: frame i closes a loop with an earlier frame j when
/// |p_i - p_j| < distance (metres) and i - j > exclusion (frames). Only earlier frames, like the
/// published files: the query row of an online detector only holds its history. Exact shape N x N.
GroundTruth posesGroundTruth(const std::vector<cv::Vec3d>& positions, double distance = kDefaultLoopDistance,
                             int exclusion = kDefaultLoopExclusion);

/// How well a candidate ground truth reproduces a reference one, pair by pair (anchors; tolerances are
/// ignored) and query by query (does the query have any loop).
struct GroundTruthAgreement
{
  size_t candidate_pairs = 0;
  size_t reference_pairs = 0;
  size_t common_pairs = 0;
  size_t candidate_queries = 0;
  size_t reference_queries = 0;
  size_t common_queries = 0;

  /// common / candidate: how many of the candidate's loops the reference confirms.
  double pairPrecision() const;
  /// common / reference: how many of the reference's loops the candidate finds.
  double pairRecall() const;
  /// common / union (intersection over union of the pair sets).
  double pairJaccard() const;
  double queryJaccard() const;
};
GroundTruthAgreement compareGroundTruth(const GroundTruth& candidate, const GroundTruth& reference);

/// One point of a precision-recall curve: predictions with distance <= threshold are accepted.
struct PrPoint
{
  double threshold;
  double precision;
  double recall;
};

/// The best match of one query row.
struct QueryPrediction
{
  int query = -1;
  /// Column of the smallest finite distance; -1 when the row has none ("no prediction").
  int match = -1;
  float distance = 0.0F;
  /// The query has a true match in the ground truth.
  bool positive = false;
  /// The best match is a true match.
  bool correct = false;
};

struct EvaluationResult
{
  /// One point per distinct best-match distance, thresholds ascending.
  std::vector<PrPoint> curve;
  /// Area under the PR curve as step-wise average precision: sum over the curve of
  /// (recall_k - recall_{k-1}) * precision_k with recall_0 = 0 (no interpolation, no trapezoids, so a
  /// curve is never credited with precision it does not reach).
  double auc = 0.0;
  /// Largest recall of a threshold that accepts no false positive (0 when even the first one does).
  double max_recall_at_100_precision = 0.0;
  /// Fraction of positive queries whose best match is correct (no threshold).
  double recall_at_1 = 0.0;
  int evaluated_queries = 0;
  int positive_queries = 0;
  int masked_queries = 0;
  /// Evaluated queries whose row holds no finite distance.
  int queries_without_prediction = 0;
  /// One per evaluated query, in row order.
  std::vector<QueryPrediction> predictions;
};

/// Precision-recall of `distances` (queries x references, CV_32F or CV_64F; NaN or infinite cells mean
/// "not compared") against `ground_truth`. `query_mask`, when not empty, has one entry per row: true =
/// evaluated, false = left out (e.g. near-black frames). A query is a positive when it has any true
/// match; its prediction is its row's best match; at threshold t it is accepted when distance <= t and
/// is a true positive when the match is true. Throws Error for an empty matrix, a matrix that does not
/// fit the ground truth, a mask of the wrong size, or no positive query (the curve would be undefined).
EvaluationResult evaluatePrecisionRecall(const cv::Mat& distances, const GroundTruth& ground_truth,
                                         const std::vector<bool>& query_mask = {});

/// Mean intensity below which a frame counts as near-black (tunnels, night stations in Nordland).
constexpr double kDarkFrameIntensity = 10.0;

/// One entry per image: true when its mean intensity (all channels, 8-bit scale) is >= min_mean, i.e. the
/// frame should be evaluated. Throws Error for an empty image (names its index).
std::vector<bool> brightFrameMask(const std::vector<cv::Mat>& images, double min_mean = kDarkFrameIntensity);
/// The same for the images of a folder or video (ImageSource order). Throws Error for unreadable frames.
std::vector<bool> brightFrameMask(const std::string& image_source, double min_mean = kDarkFrameIntensity);

/// Query mask file: one line per query, `1` = evaluated, `0` = left out; `#` starts a comment line.
std::vector<bool> loadQueryMask(const std::string& path);
void saveQueryMask(const std::string& path, const std::vector<bool>& mask);

/// `threshold,precision,recall` with a header line.
std::string prCurveCsv(const EvaluationResult& result);
/// The metrics as one line of JSON (no trailing newline); `name` labels the run.
std::string metricsJson(const EvaluationResult& result, const std::string& name, const std::string& ground_truth);
/// `text` as a JSON string literal: quoted, with quotes, backslashes and control characters escaped.
std::string jsonString(const std::string& text);

/// One curve of a PR plot.
struct PrPlotSeries
{
  std::string name;
  EvaluationResult result;
};
/// A PR plot (BGR, `size`, at least 320x240): recall on x, precision on y, both 0..1 with ticks every
/// 0.1 and labels, one coloured curve per series with a legend giving its AUC; the title names the AUC
/// when there is one series. Throws Error for no series or a too small size.
cv::Mat drawPrCurves(const std::vector<PrPlotSeries>& series, const std::string& title,
                     cv::Size size = cv::Size(800, 600));

}  // namespace openable
