// openable_eval: precision-recall of distance matrices against a ground truth (see --help).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "openable/error.h"
#include "openable/evaluation.h"
#include "openable/ground_truth_sources.h"
#include "openable/image_source.h"
#include "openable/npy.h"
#include "openable/progress.h"
#include "openable/published_scoring.h"

namespace
{
namespace fs = std::filesystem;

const char kUsage[] = R"(openable_eval: precision-recall of OpenABLE distance matrices against a ground truth.

Usage:
  openable_eval --matrix PATH [--name LABEL] [--matrix PATH --name LABEL ...]
                [--mask FILE | --mask-dark IMAGES]
                (--tolerance T | --pairs FILE [--pair-tolerance K] | --poses FILE [--distance D] [--exclusion E]
                 | --joined N [--tolerance T] | --truth-matrix PATH)
                --output DIR [--title TEXT]
  openable_eval --published FILE [--decisions FILE] [--frames M] (ground truth as above) --output DIR
  openable_eval --poses FILE --compare FILE [--distance D] [--exclusion E] [--sweep] [--quiet]

Distance matrix:
  --matrix PATH        distance_matrix.npy (float32 or float64, 2-D, rows = queries, columns = references),
                       or a folder holding one (as written by openable_offline). Repeat it, each with a
                       --name, to overlay several matrices in one plot. NaN or infinite cells are "not
                       compared"; a row without any finite cell is a query without prediction. A matrix
                       of one sequence against itself must hold NaN where the detector did not look
                       (the frame itself and its recent past), or the frame will match itself.
  --name LABEL         label of the preceding --matrix in the plot and the JSON (default: the folder or
                       file name).
  --mask FILE          query mask: one line per query row, 1 = evaluated, 0 = left out (# comments).
  --mask-dark IMAGES   compute the mask from the query images (folder or video, in row order): frames with
                       mean intensity < 10 are left out (e.g. Nordland tunnels); written to
                       DIR/query_mask.txt.

Ground truth (exactly one):
  --tolerance T        aligned traversals: query i matches reference j when |i - j| <= T (frames).
  --pairs FILE         'i j' lines (0-based; frame i closes a loop with earlier frame j; # comments), as in
                       the published KITTI loop ground truth; a 'shape=RxC' comment fixes the matrix shape.
  --pair-tolerance K   with --pairs: query i also matches references within K frames of j (default 0).
  --poses FILE         KITTI poses (row-major 3x4 per line): frame i closes a loop with earlier frame j
                       when they are closer than D metres and more than E frames apart.
  --distance D         with --poses: metres (default 6).
  --exclusion E        with --poses: frames (default 100). The defaults reproduce the published ground
                       truth of KITTI 00, 05 and 06 best (doc/results.md).
  --joined N           one stream of two traversals joined at frame N (loop-closure mode): frame N + i is the
                       place of frame i and matches frames within --tolerance T of i (default 0); frames
                       before N have no loop, so any match accepted there is a false positive.
  --truth-matrix PATH  PNG (any non-zero pixel = same place) or .npy (bool, integer or float; non-zero = same
                       place), rows = queries, columns = references; its shape must be the distance matrix's.

Output:
  --output DIR         created if missing; receives pr_curve.csv (threshold,precision,recall; with several
                       matrices pr_curve_LABEL.csv each), pr_curve.png (the PR plot) and metrics.json.
  --title TEXT         plot title (default "Precision-recall").

Printed on stdout, one per line: auc, max_recall_at_100_precision, recall_at_1 (preceded by 'name: LABEL'
with several matrices), then the metrics as one line of JSON.
  auc                  area under the PR curve as step-wise average precision:
                       sum over thresholds of (recall_k - recall_{k-1}) * precision_k.
  max_recall_at_100_precision  largest recall of a threshold without any false positive.
  recall_at_1          fraction of queries with a true match whose best match is a true match.
A query's prediction is its row's smallest distance; at threshold t it is accepted when distance <= t and
is a true positive when its column is a true match; every distinct distance is a threshold.

Published loop closures (instead of --matrix):
  --published FILE     loop_closures.csv (query,match,distance,score,status[,direction,shift]) or
                       decisions.csv (the same plus accepted, one row per frame) of openable_offline; the rows
                       with status 'published' are scored. Prints published, wrong (published rows whose
                       match is not a true match), precision (correct / published rows) and recall (frames
                       with a true loop that got a correct published match / frames with a true loop; a
                       frame published twice counts once), then the metrics as one line of JSON, also
                       written to DIR/metrics.json.
  --decisions FILE     decisions.csv: every frame's best match, published or not, gives a PR curve over its
                       score (a frame is predicted when score >= s, s from high to low), written to
                       DIR/published_pr.csv (threshold = score) and DIR/published_pr.png, and score_auc,
                       score_max_recall_at_100_precision, score_recall_at_1. Without it, a decisions.csv
                       given to --published serves.
  --frames M           frames in the stream (default: from the decisions, or the ground truth's shape);
                       --joined and --tolerance need it or a decisions.csv.
  --tolerance alone means aligned traversals (query i matches reference j when |i - j| <= T): only sensible
  for the decisions of a localisation run.

Ground-truth comparison:
  --compare FILE       with --poses: compare the loops from the poses with a pairs file (pair precision,
                       recall, intersection over union, and the same for queries with any loop).
  --sweep              with --compare: try a grid of D and E and print the best by intersection over union.
                       Shows its progress on stderr (settings done, per second, time left).
  --quiet              no progress on stderr.

Exit status: 0 on success, 1 with a one-line reason on stderr for bad input, 2 for bad usage.
)";

struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

struct Options
{
  std::vector<std::string> matrices;
  std::vector<std::string> names;
  std::string mask;
  std::string mask_dark;
  int tolerance = -1;
  int joined = -1;
  std::string truth_matrix;
  std::string published;
  std::string decisions;
  int frames = 0;
  std::string pairs;
  int pair_tolerance = 0;
  std::string poses;
  double distance = openable::kDefaultLoopDistance;
  int exclusion = openable::kDefaultLoopExclusion;
  std::string output;
  std::string title = "Precision-recall";
  std::string compare;
  bool sweep = false;
  bool quiet = false;
  bool help = false;
};

int parseInt(const std::string& flag, const std::string& text)
{
  size_t used = 0;
  int value = 0;
  try
  {
    value = std::stoi(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used == 0 || used != text.size() || value < 0)
  {
    throw UsageError(flag + " expects a non-negative integer, got '" + text + "'");
  }
  return value;
}

double parsePositive(const std::string& flag, const std::string& text)
{
  size_t used = 0;
  double value = 0.0;
  try
  {
    value = std::stod(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(value > 0.0) || !std::isfinite(value))
  {
    throw UsageError(flag + " expects a positive number, got '" + text + "'");
  }
  return value;
}

/// Takes the next argument as the flag's value.
std::string takeValue(int argc, char** argv, int& i)
{
  if (i + 1 >= argc)
  {
    throw UsageError(std::string(argv[i]) + " needs a value");
  }
  return argv[++i];
}

Options parseArguments(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h")
      o.help = true;
    else if (flag == "--matrix")
      o.matrices.push_back(takeValue(argc, argv, i));
    else if (flag == "--name")
    {
      if (o.names.size() + 1 != o.matrices.size())
        throw UsageError("--name must follow its --matrix (one name per matrix)");
      o.names.push_back(takeValue(argc, argv, i));
    }
    else if (flag == "--mask")
      o.mask = takeValue(argc, argv, i);
    else if (flag == "--mask-dark")
      o.mask_dark = takeValue(argc, argv, i);
    else if (flag == "--tolerance")
      o.tolerance = parseInt(flag, takeValue(argc, argv, i));
    else if (flag == "--pairs")
      o.pairs = takeValue(argc, argv, i);
    else if (flag == "--joined")
      o.joined = parseInt(flag, takeValue(argc, argv, i));
    else if (flag == "--truth-matrix")
      o.truth_matrix = takeValue(argc, argv, i);
    else if (flag == "--published")
      o.published = takeValue(argc, argv, i);
    else if (flag == "--decisions")
      o.decisions = takeValue(argc, argv, i);
    else if (flag == "--frames")
      o.frames = parseInt(flag, takeValue(argc, argv, i));
    else if (flag == "--pair-tolerance")
      o.pair_tolerance = parseInt(flag, takeValue(argc, argv, i));
    else if (flag == "--poses")
      o.poses = takeValue(argc, argv, i);
    else if (flag == "--distance")
      o.distance = parsePositive(flag, takeValue(argc, argv, i));
    else if (flag == "--exclusion")
      o.exclusion = parseInt(flag, takeValue(argc, argv, i));
    else if (flag == "--output")
      o.output = takeValue(argc, argv, i);
    else if (flag == "--title")
      o.title = takeValue(argc, argv, i);
    else if (flag == "--compare")
      o.compare = takeValue(argc, argv, i);
    else if (flag == "--sweep")
      o.sweep = true;
    else if (flag == "--quiet")
      o.quiet = true;
    else
      throw UsageError("unknown argument '" + flag + "' (see --help)");
  }
  return o;
}

void checkOptions(const Options& o)
{
  // With --joined, --tolerance is the joined truth's tolerance, not a ground truth of its own.
  const int sources = (o.tolerance >= 0 || o.joined >= 0 ? 1 : 0) + (o.pairs.empty() ? 0 : 1) +
                      (o.poses.empty() ? 0 : 1) + (o.truth_matrix.empty() ? 0 : 1);
  if (o.published.empty() && (!o.decisions.empty() || o.frames > 0))
    throw UsageError("--decisions and --frames need --published");
  if (!o.published.empty() && (!o.compare.empty() || o.sweep))
    throw UsageError("--published does not go with --compare or --sweep");
  if (!o.compare.empty())
  {
    if (o.poses.empty() || !o.matrices.empty() || sources != 1)
      throw UsageError("--compare needs --poses and no --matrix, --tolerance or --pairs");
    return;
  }
  if (o.sweep)
    throw UsageError("--sweep needs --poses and --compare");
  if (!o.published.empty())
  {
    if (!o.matrices.empty() || !o.mask.empty() || !o.mask_dark.empty())
      throw UsageError("--published scores a loop closures file: no --matrix, --mask or --mask-dark with it");
  }
  else if (o.matrices.empty())
    throw UsageError("no --matrix given (see --help)");
  if (sources != 1)
    throw UsageError("give exactly one ground truth: --tolerance, --pairs, --poses, --joined or --truth-matrix");
  if (o.output.empty())
    throw UsageError("no --output folder given");
  if (!o.mask.empty() && !o.mask_dark.empty())
    throw UsageError("give --mask or --mask-dark, not both");
  if (o.matrices.size() > 1 && o.names.size() != o.matrices.size())
    throw UsageError("with several --matrix, give each a --name");
  if (std::set<std::string>(o.names.begin(), o.names.end()).size() != o.names.size())
    throw UsageError("--name labels must differ");
}

std::string matrixFile(const std::string& path)
{
  return fs::is_directory(path) ? (fs::path(path) / "distance_matrix.npy").string() : path;
}

std::string defaultName(const std::string& path)
{
  const fs::path p = fs::path(path).lexically_normal();
  if (fs::is_directory(p))
    return p.has_filename() ? p.filename().string() : p.parent_path().filename().string();
  return p.stem().string();
}

/// A label usable in a file name: anything but letters, digits, '-', '_' and '.' becomes '_'.
std::string fileSafe(const std::string& name)
{
  std::string safe = name;
  for (char& c : safe)
  {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
      c = '_';
  }
  return safe;
}

/// The ground truth of the options for a `rows` x `cols` matrix (the shape matters to aligned and joined).
openable::GroundTruth makeGroundTruth(const Options& o, int rows, int cols)
{
  if (o.joined >= 0)
  {
    if (rows != cols)
      throw openable::Error("--joined: a joined stream is matched against itself, but the matrix is " +
                            std::to_string(rows) + "x" + std::to_string(cols));
    return openable::joinedGroundTruth(rows, o.joined, std::max(o.tolerance, 0));
  }
  if (!o.truth_matrix.empty())
    return openable::loadTruthMatrix(o.truth_matrix);
  if (o.tolerance >= 0)
    return openable::alignedGroundTruth(rows, cols, o.tolerance);
  if (!o.pairs.empty())
    return openable::loadPairsGroundTruth(o.pairs, o.pair_tolerance);
  return openable::posesGroundTruth(openable::loadKittiPositions(o.poses), o.distance, o.exclusion);
}

std::vector<bool> makeMask(const Options& o)
{
  if (!o.mask.empty())
    return openable::loadQueryMask(o.mask);
  if (!o.mask_dark.empty())
  {
    std::vector<bool> mask = openable::brightFrameMask(o.mask_dark);
    openable::saveQueryMask((fs::path(o.output) / "query_mask.txt").string(), mask);
    return mask;
  }
  return {};
}

void printMetrics(const openable::EvaluationResult& r)
{
  std::cout << "auc: " << r.auc << "\n"
            << "max_recall_at_100_precision: " << r.max_recall_at_100_precision << "\n"
            << "recall_at_1: " << r.recall_at_1 << "\n";
}

int evaluate(const Options& o)
{
  fs::create_directories(o.output);
  const std::vector<bool> mask = makeMask(o);
  std::vector<openable::PrPlotSeries> series;
  std::string json;
  const bool several = o.matrices.size() > 1;
  for (size_t i = 0; i < o.matrices.size(); ++i)
  {
    const cv::Mat matrix = openable::readNpy(matrixFile(o.matrices[i]));
    const openable::GroundTruth truth = makeGroundTruth(o, matrix.rows, matrix.cols);
    const std::string name = i < o.names.size() ? o.names[i] : defaultName(o.matrices[i]);
    openable::EvaluationResult result = openable::evaluatePrecisionRecall(matrix, truth, mask);
    const std::string csv_name = several ? "pr_curve_" + fileSafe(name) + ".csv" : "pr_curve.csv";
    openable::writeFileAtomically((fs::path(o.output) / csv_name).string(), openable::prCurveCsv(result));
    json += (json.empty() ? "" : ", ") + openable::metricsJson(result, name, truth.description());
    if (several)
      std::cout << "name: " << name << "\n";
    printMetrics(result);
    series.push_back({name, std::move(result)});
  }
  if (several)
    json = "[" + json + "]";
  openable::writeFileAtomically((fs::path(o.output) / "metrics.json").string(), json + "\n");
  std::vector<unsigned char> png;
  cv::imencode(".png", openable::drawPrCurves(series, o.title), png);
  openable::writeFileAtomically((fs::path(o.output) / "pr_curve.png").string(), std::string(png.begin(), png.end()));
  std::cout << json << std::endl;
  return 0;
}

void printAgreement(double distance, int exclusion, const openable::GroundTruthAgreement& a)
{
  std::cout << distance << "," << exclusion << "," << a.candidate_pairs << "," << a.reference_pairs << ","
            << a.common_pairs << "," << a.pairPrecision() << "," << a.pairRecall() << "," << a.pairJaccard() << ","
            << a.candidate_queries << "," << a.reference_queries << "," << a.common_queries << "," << a.queryJaccard()
            << "\n";
}

/// Loops from poses against a published pairs file, at the given D and E or over a grid of them.
int compareGroundTruth(const Options& o)
{
  const std::vector<cv::Vec3d> positions = openable::loadKittiPositions(o.poses);
  const openable::GroundTruth reference = openable::loadPairsGroundTruth(o.compare);
  reference.checkFits(static_cast<int>(positions.size()), static_cast<int>(positions.size()));
  std::cout << "distance,exclusion,pose_pairs,published_pairs,common_pairs,pair_precision,pair_recall,"
               "pair_iou,pose_queries,published_queries,common_queries,query_iou\n";
  if (!o.sweep)
  {
    printAgreement(
        o.distance, o.exclusion,
        openable::compareGroundTruth(openable::posesGroundTruth(positions, o.distance, o.exclusion), reference));
    return 0;
  }
  double best_iou = -1.0, best_distance = 0.0;
  int best_exclusion = 0;
  const std::vector<int> exclusions = {0, 10, 25, 50, 75, 100, 150, 200, 300, 500};
  const int distances = 39;  // 1.0 .. 20.0 m in steps of 0.5 m
  // Each setting is a pass over all pairs of frames: minutes on a long sequence, so say how far it is.
  openable::Progress progress("openable_eval: sweep", distances * exclusions.size(), o.quiet, "settings");
  for (int step = 0; step < distances; ++step)
  {
    const double distance = 1.0 + 0.5 * step;
    for (int exclusion : exclusions)
    {
      const openable::GroundTruthAgreement a =
          openable::compareGroundTruth(openable::posesGroundTruth(positions, distance, exclusion), reference);
      progress.step();
      printAgreement(distance, exclusion, a);
      if (a.pairJaccard() > best_iou)
      {
        best_iou = a.pairJaccard();
        best_distance = distance;
        best_exclusion = exclusion;
      }
    }
  }
  progress.finish();
  std::cout << "best: distance " << best_distance << " exclusion " << best_exclusion << " pair_iou " << best_iou
            << "\n";
  return 0;
}

/// Frames of the stream for published scoring: --frames, else one past the last frame of the per-frame
/// decisions, else the ground truth's queries (or one past the last published query if that is more).
int streamFrames(const Options& o, const openable::DecisionTable& published,
                 const std::optional<openable::DecisionTable>& decisions, const openable::GroundTruth* truth)
{
  if (o.frames > 0)
    return o.frames;
  int last = -1;
  for (const openable::DecisionRow& d : decisions ? decisions->rows : published.rows)
    last = std::max(last, d.query);
  if (decisions || truth == nullptr)
    return last + 1;
  return truth->exactShape() ? truth->numQueries() : std::max(truth->numQueries(), last + 1);
}

/// The run's label: the folder openable_offline wrote the file into, or the file's name without one.
std::string publishedName(const std::string& path)
{
  const fs::path folder = fs::path(path).lexically_normal().parent_path();
  return folder.has_filename() ? folder.filename().string() : fs::path(path).stem().string();
}

/// Published loop closures (and, with decisions, the score curve) of one stream against a ground truth.
int scorePublishedSet(const Options& o)
{
  fs::create_directories(o.output);
  const openable::DecisionTable published = openable::loadDecisionTable(o.published);
  std::optional<openable::DecisionTable> decisions;
  if (!o.decisions.empty())
    decisions = openable::loadDecisionTable(o.decisions);
  else if (published.per_frame)
    decisions = published;
  // Aligned and joined truths are made for a length; the others bring their own.
  const bool needs_length =
      o.joined >= 0 || (o.tolerance >= 0 && o.pairs.empty() && o.poses.empty() && o.truth_matrix.empty());
  int frames = 0;
  if (needs_length)
  {
    if (o.frames == 0 && !decisions)
      throw openable::Error("--joined and --tolerance need the stream's length: give --frames M or a decisions.csv");
    frames = streamFrames(o, published, decisions, nullptr);
  }
  const openable::GroundTruth truth = makeGroundTruth(o, frames, frames);
  frames = needs_length ? frames : streamFrames(o, published, decisions, &truth);
  const openable::PublishedScore score = openable::scorePublished(published, truth, frames);
  std::optional<openable::EvaluationResult> curve;
  if (decisions)
  {
    curve = openable::scorePrecisionRecall(*decisions, truth, frames);
    openable::writeFileAtomically((fs::path(o.output) / "published_pr.csv").string(), openable::prCurveCsv(*curve));
    std::vector<unsigned char> png;
    cv::imencode(".png", openable::drawPrCurves({{"score", *curve}}, o.title), png);
    openable::writeFileAtomically((fs::path(o.output) / "published_pr.png").string(),
                                  std::string(png.begin(), png.end()));
  }
  const std::string json =
      openable::publishedMetricsJson(score, curve ? &*curve : nullptr, publishedName(o.published), truth.description());
  openable::writeFileAtomically((fs::path(o.output) / "metrics.json").string(), json + "\n");
  std::cout << "published: " << score.published << "\n"
            << "wrong: " << score.wrong() << "\n"
            << "precision: " << score.precision() << "\n"
            << "recall: " << score.recall() << "\n";
  if (curve)
    std::cout << "score_auc: " << curve->auc << "\n"
              << "score_max_recall_at_100_precision: " << curve->max_recall_at_100_precision << "\n"
              << "score_recall_at_1: " << curve->recall_at_1 << "\n";
  std::cout << json << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    options = parseArguments(argc, argv);
    if (options.help || argc == 1)
    {
      std::cout << kUsage;
      return argc == 1 ? 2 : 0;
    }
    checkOptions(options);
  }
  catch (const UsageError& e)
  {
    std::cerr << "openable_eval: " << e.what() << "\n";
    return 2;
  }
  try
  {
    if (!options.published.empty())
      return scorePublishedSet(options);
    return options.compare.empty() ? evaluate(options) : compareGroundTruth(options);
  }
  catch (const std::exception& e)
  {
    // Error messages of the core are one line naming what and why; keep it one line whatever the source.
    std::string reason = e.what();
    for (char& c : reason)
      c = (c == '\n') ? ' ' : c;
    std::cerr << "openable_eval: error: " << reason << "\n";
    return 1;
  }
}
