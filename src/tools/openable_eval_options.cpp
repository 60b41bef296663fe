#include "openable_eval_options.h"

#include <climits>
#include <set>
#include <string>

namespace openable_eval
{
extern const char kUsage[];
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

Options parseArguments(int argc, char** argv)
{
  Options o;
  openable::cli::Arguments args(argc, argv);
  while (args.next())
  {
    if (args.isHelp())
      o.help = true;
    else if (args.is("--matrix"))
      o.matrices.push_back(args.value());
    else if (args.is("--name"))
    {
      if (o.names.size() + 1 != o.matrices.size())
        throw UsageError("--name must follow its --matrix (one name per matrix)");
      o.names.push_back(args.value());
    }
    else if (args.is("--mask"))
      o.mask = args.value();
    else if (args.is("--mask-dark"))
      o.mask_dark = args.value();
    else if (args.is("--tolerance"))
      o.tolerance = args.integer(0, INT_MAX, "frames");
    else if (args.is("--pairs"))
      o.pairs = args.value();
    else if (args.is("--joined"))
      o.joined = args.integer(0, INT_MAX, "a frame");
    else if (args.is("--truth-matrix"))
      o.truth_matrix = args.value();
    else if (args.is("--published"))
      o.published = args.value();
    else if (args.is("--decisions"))
      o.decisions = args.value();
    else if (args.is("--frames"))
      o.frames = args.integer(0, INT_MAX, "frames");
    else if (args.is("--pair-tolerance"))
      o.pair_tolerance = args.integer(0, INT_MAX, "frames");
    else if (args.is("--poses"))
      o.poses = args.value();
    else if (args.is("--distance"))
      o.distance = args.positive("metres");
    else if (args.is("--exclusion"))
      o.exclusion = args.integer(0, INT_MAX, "frames");
    else if (args.is("--output"))
      o.output = args.value();
    else if (args.is("--title"))
      o.title = args.value();
    else if (args.is("--compare"))
      o.compare = args.value();
    else if (args.is("--sweep"))
      o.sweep = true;
    else if (args.is("--quiet"))
      o.quiet = true;
    else
      args.unknown();
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

}  // namespace openable_eval
