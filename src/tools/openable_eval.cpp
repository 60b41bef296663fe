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

#include "openable/io/atomic_file.h"
#include "openable/error.h"
#include "openable/evaluation/evaluation.h"
#include "openable/evaluation/ground_truth_sources.h"
#include "openable/io/image_source.h"
#include "openable/detection/loop_csv.h"
#include "openable/io/npy.h"
#include "progress.h"
#include "openable/io/staged_output.h"
#include "openable/evaluation/published_scoring.h"
#include "openable_eval_options.h"

namespace
{
namespace fs = std::filesystem;

using openable_eval::kUsage;
using openable_eval::Options;
using openable_eval::UsageError;

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

std::vector<bool> makeMask(const Options& o, openable::StagedOutput& output)
{
  if (!o.mask.empty())
    return openable::loadQueryMask(o.mask);
  if (!o.mask_dark.empty())
  {
    std::vector<bool> mask = openable::brightFrameMask(o.mask_dark);
    openable::saveQueryMask(output.path("query_mask.txt"), mask);
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
  openable::StagedOutput output(o.output, "openable_eval");  // one set: a failed run leaves the earlier one
  const std::vector<bool> mask = makeMask(o, output);
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
    openable::writeFileAtomically(output.path(csv_name), openable::prCurveCsv(result));
    json += (json.empty() ? "" : ", ") + openable::metricsJson(result, name, truth.description());
    if (several)
      std::cout << "name: " << name << "\n";
    printMetrics(result);
    series.push_back({name, std::move(result)});
  }
  if (several)
    json = "[" + json + "]";
  openable::writeFileAtomically(output.path("metrics.json"), json + "\n");
  std::vector<unsigned char> png;
  cv::imencode(".png", openable::drawPrCurves(series, o.title), png);
  openable::writeFileAtomically(output.path("pr_curve.png"), std::string(png.begin(), png.end()));
  output.publish();
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
  openable::StagedOutput output(o.output, "openable_eval");  // one set: a failed run leaves the earlier one
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
    openable::writeFileAtomically(output.path("published_pr.csv"), openable::prCurveCsv(*curve));
    std::vector<unsigned char> png;
    cv::imencode(".png", openable::drawPrCurves({{"score", *curve}}, o.title), png);
    openable::writeFileAtomically(output.path("published_pr.png"),
                                  std::string(png.begin(), png.end()));
  }
  const std::string json =
      openable::publishedMetricsJson(score, curve ? &*curve : nullptr, publishedName(o.published), truth.description());
  openable::writeFileAtomically(output.path("metrics.json"), json + "\n");
  output.publish();
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
    options = openable_eval::parseArguments(argc, argv);
    if (options.help || argc == 1)
    {
      std::cout << kUsage;
      return argc == 1 ? 2 : 0;
    }
    openable_eval::checkOptions(options);
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
