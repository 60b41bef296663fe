#pragma once

#include <string>

#include "openable/evaluation/evaluation.h"
#include "openable/detection/decision_table.h"

namespace openable
{
/// How good the published loop closures of one stream are.
struct PublishedScore
{
  /// Frames of the stream: recall is over frames 0 .. frames - 1.
  int frames = 0;
  /// Published rows (loop closures); a frame published twice counts twice.
  int published = 0;
  /// Published rows whose match is a true match of their query.
  int correct = 0;
  /// Frames with a true loop in the ground truth.
  int positive_frames = 0;
  /// Frames with a true loop that got at least one correct published row (each frame once).
  int recalled_frames = 0;

  int wrong() const
  {
    return published - correct;
  }
  /// correct / published: how many published loop closures can be trusted; NaN when nothing is published.
  double precision() const;
  /// recalled_frames / positive_frames: how many of the loops were closed.
  double recall() const;
};

/// Scores the published rows (status "published") of `table` against `truth` for a stream of `num_frames`
/// frames. Throws Error when a row's query is not a frame of the stream, when a ground truth of fixed shape
/// is for another number of frames, or when no frame has a true loop (recall would be undefined).
PublishedScore scorePublished(const DecisionTable& table, const GroundTruth& truth, int num_frames);

/// Precision-recall over the score of every frame's best match, published or not (a decisions.csv): at
/// threshold s a frame is predicted when score >= s; every distinct score is a threshold, from high to low.
/// Curve, AUC (step-wise average precision), max recall at 100 % precision and recall@1 as for distance
/// matrices; a frame without a match or without a finite score has no prediction. Throws Error for a file
/// that is not per frame (no `accepted` column), a frame listed twice, or the cases of scorePublished.
EvaluationResult scorePrecisionRecall(const DecisionTable& decisions, const GroundTruth& truth, int num_frames);

/// The metrics as one line of JSON (no trailing newline): counts, precision and recall of `score`, and when
/// `curve` is given, its AUC, max recall at 100 % precision and recall@1 as score_*. Undefined values
/// (precision with nothing published) are null.
std::string publishedMetricsJson(const PublishedScore& score, const EvaluationResult* curve, const std::string& name,
                                 const std::string& ground_truth);

}  // namespace openable
