#include "openable/detection/loop_decision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace openable
{
namespace
{
/// How much worse than the run's last unique frame a frame that continues the run may be (continuesPublishedRun).
constexpr double kContinueSlack = 1.05;
}  // namespace

const char* toString(FrameStatus status)
{
  switch (status)
  {
    case FrameStatus::Published:
      return "published";
    case FrameStatus::NotKeyframe:
      return "not_keyframe";
    case FrameStatus::Standstill:
      return "standstill";
    case FrameStatus::TimeJump:
      return "time_jump";
    case FrameStatus::TooEarly:
      return "too_early";
    case FrameStatus::Excluded:
      return "excluded";
    case FrameStatus::AboveThreshold:
      return "above_threshold";
    case FrameStatus::NotUnique:
      return "not_unique";
    case FrameStatus::Inconsistent:
      return "inconsistent";
    case FrameStatus::Featureless:
      return "featureless";
    case FrameStatus::FailedVerification:
      return "failed_verification";
    case FrameStatus::Unverified:
      return "unverified";
    case FrameStatus::Pending:
      return "pending";
    case FrameStatus::Unconfirmed:
      return "unconfirmed";
  }
  return "unknown";
}

float matchUniqueness(float best, std::optional<float> second_best)
{
  if (!second_best)
    return 1.0f;
  return *second_best > 0.0f ? 1.0f - best / *second_best : 0.0f;
}

DecisionOptions DecisionOptions::from(const Config& config)
{
  DecisionOptions o;
  o.threshold = config.threshold;
  o.min_uniqueness = config.min_uniqueness;
  o.continue_uniqueness = config.continue_uniqueness;
  o.min_candidates = config.min_candidates;
  o.consistent_frames = config.consistent_frames;
  o.consistency_tolerance = config.consistency_tolerance;
  o.max_pace = config.max_pace;
  o.verified_min_uniqueness = config.verified_min_uniqueness;
  o.run_start_tolerance = config.run_start_tolerance;
  o.run_resume_frames = config.run_resume_frames;
  o.min_relief = config.min_relief;
  return o;
}

LoopDecision::LoopDecision(const DecisionOptions& options) : options_(options) {}

LoopDecision::LoopDecision(const Config& config) : LoopDecision(DecisionOptions::from(config)) {}

void LoopDecision::setOptions(const DecisionOptions& options)
{
  options_ = options;
  reset();
}

void LoopDecision::reset()
{
  endRun();
  past_.clear();
  reliefs_.clear();
  line_ = Line();
  jumped_ahead_ = Jump();
  frames_since_search_kept_ = SIZE_MAX;
  coasted_ = false;
}

void LoopDecision::endRun()
{
  run_ = 0;
  published_ = false;
  recent_.clear();
}

float LoopDecision::score(const Detection& detection) const
{
  // A best match with no rival outside the uniqueness window (the only distinct place) is "unique" by default.
  const bool has_rival = detection.top.size() >= 2;
  const bool meaningful =
      detection.has_candidates && detection.candidates >= static_cast<size_t>(options_.min_candidates) && has_rival;
  return meaningful ? detection.uniqueness : 0.0f;
}

bool LoopDecision::geometryMayStandIn(const Detection& detection, FrameStatus why) const
{
  // Geometric verification is evidence the appearance rules do not have: on real pairs (doc/results.md) no
  // non-revisit reached 15 inliers (814 pairs), while same-light revisits reach them on about half the frames,
  // many of them where a look-alike neighbour leaves the best match barely unique. So it may stand in for the
  // uniqueness gate and for the minimum of places; never for the distance gate, nor for the consistency of the
  // run: verification accepts a place 3 or 4 frames off as readily as the right one (same room, 30 to 57
  // inliers), and at the start of a revisit the sequences lag by that much. Publishing a verified frame
  // without a consistent run put 9 such near misses among 143 loops on Gardens Point day_right -> day_left.
  // (A frame too early never met the distance gate: it is checked here. A short map's early places, no candidate
  // counted, are only for a run to reach back to: MapMatcher::earlyPicks.)
  const bool wants_evidence = why == FrameStatus::NotUnique || why == FrameStatus::TooEarly;
  return options_.verified_min_uniqueness >= 0.0 && detection.has_candidates && detection.candidates > 0 &&
         wants_evidence && !aboveThreshold(detection) && detection.uniqueness >= options_.verified_min_uniqueness;
}

bool LoopDecision::aboveThreshold(const Detection& detection) const
{
  return options_.threshold >= 0.0 && detection.best.distance > options_.threshold;
}

bool LoopDecision::pressedAgainstExclusion(const Detection& detection) const
{
  // A revisit faster than the first pass catches up with its own recent past: on a short route driven again
  // at 1.5x, the place it shows was seen fewer than exclusion_window frames ago and is not compared. The best
  // sequence then ends at the newest place that is, the edge, and follows it one place a frame, unique (nothing
  // else looks like the route) and consistent: measured on 95 short-route streams, 45 wrong loops of 241 at
  // 1.5x, 40 of them matched to the edge itself. A match at the edge may be the edge, not the place: it starts
  // no run (it is treated as inside the window). A published run goes on through it: a revisit at 1.25x or 2x
  // reaches the edge from behind with its matches right (GP day_right then night_right, frames 0-59 at 1.25x,
  // keeps its 23 right loops, 17 of them within 2 places of the edge).
  return detection.has_exclusion_edge && detection.best.session == detection.exclusion_edge_session &&
         detection.best.id >= detection.exclusion_edge_id;
}

bool LoopDecision::startsNoRun(const Detection& detection) const
{
  // A short map's first place: a path ending there has no past, its cost is the row's typical one plus a few
  // frames, and a short route's end matches its start (GP day_left then day_right 0-59: the first pass's frames 58
  // and 59 at place 0, uniqueness 0.002 and 0.010, joined the revisit's first run: 2 wrong loops).
  return pressedAgainstExclusion(detection) || detection.best_at_session_start;
}

bool LoopDecision::gatesPass(const Detection& detection, FrameStatus& why) const
{
  if (aboveThreshold(detection))
  {
    why = FrameStatus::AboveThreshold;
    return false;
  }
  // The acceptance gate, here only. With neither gate set nothing is a loop: the best match of a frame always
  // exists, a loop does not.
  const bool gated = options_.threshold >= 0.0 || options_.min_uniqueness > 0.0;
  if (!gated || detection.uniqueness < options_.min_uniqueness)
  {
    why = FrameStatus::NotUnique;
    return false;
  }
  return true;
}

bool LoopDecision::featureless() const
{
  // Where the places around the match look alike, a sequence has nothing to place it by: it drifts along the
  // stretch at the pace it came in with, unique (nothing else on the route looks like it) and consistent. Measured
  // on Nordland summer then winter (default.yaml), winter 506-546, every place within 10 of the match about as far
  // from the query as the match (relief 0.4-0.6 where Gardens Point's never falls below 1.1): all 12 wrong loops at 1x,
  // 24 of 24 at 0.5x, about a quarter at changing paces. The right loops lost there (recall 0.917 -> 0.893 at 1x)
  // were right because a stretch ended before the sequence had drifted: nothing in the frames said so.
  if (options_.min_relief <= 0.0 || reliefs_.empty())
    return false;
  std::array<float, kReliefFrames> sorted;
  const auto end = std::copy(reliefs_.begin(), reliefs_.end(), sorted.begin());
  const auto middle = sorted.begin() + static_cast<long>(reliefs_.size() / 2);
  std::nth_element(sorted.begin(), middle, end);
  return *middle < options_.min_relief;
}

bool LoopDecision::advancesWithRun(const Detection& detection) const
{
  // A run follows one route: a match in another session starts a new run.
  if (run_ == 0 || detection.best.direction != previous_direction_ || detection.best.session != previous_session_)
    return false;
  // The match moves along the route (forward, or back for a reverse revisit) at a pace between 1 / max_pace
  // and max_pace places per frame (the revisit may be slower or faster than the first pass; a stop of the
  // camera adds no frame), within consistency_tolerance: per step and over the whole run, so a match that
  // stays put (a "hub" place that every frame matches) never becomes consistent by small steps. At
  // max_pace 1 this is one place per frame.
  const double pace = std::max(1, options_.max_pace);
  const double tolerance = options_.consistency_tolerance;
  const auto advance = [&detection](uint64_t from)
  { return detection.best.direction * (static_cast<double>(detection.best.id) - static_cast<double>(from)); };
  const auto within = [&](double moved, double frames)
  { return moved >= frames / pace - tolerance && moved <= frames * pace + tolerance; };
  return within(advance(previous_match_), 1.0) && within(advance(run_start_match_), run_);
}

bool LoopDecision::recentFramesFollowOneLine() const
{
  // At another pace than the first pass's, the run must also be straight lately: its last consistent_frames
  // matches lie within consistency_tolerance of the line through the first and last of them. A match that
  // stalls (a sequence that kept the old pace after the robot sped up) or jumps about breaks the line. At the
  // slow end the line must advance half a place more than the slowest pace would, with no tolerance: a
  // sequence creeping along a few look-alike places at the slowest pace is a hub, not a revisit (measured on
  // Gardens Point day_left, which has no loop: 12 such frames published without this).
  const size_t n = recent_.size();
  if (options_.max_pace <= 1 || n < 3)
    return true;
  const double first = static_cast<double>(recent_.front()), last = static_cast<double>(recent_.back());
  const double frames = static_cast<double>(n - 1);
  const double advanced = (last - first) * previous_direction_;
  if (advanced < frames / options_.max_pace + 0.5 || advanced > frames * options_.max_pace + options_.consistency_tolerance)
    return false;
  for (size_t k = 1; k + 1 < n; ++k)
  {
    const double expected = first + (last - first) * static_cast<double>(k) / frames;
    if (std::fabs(static_cast<double>(recent_[k]) - expected) > options_.consistency_tolerance)
      return false;
  }
  return true;
}

bool LoopDecision::continuesPublishedRun(const Detection& detection, FrameStatus why) const
{
  // Once a run is published, where the revisit goes is known: a frame whose best match keeps to the run's
  // line (advancesWithRun, then the line of the last frames) is the revisit going on, even where a look-alike
  // neighbour makes it less unique than a run's first frames must be. Measured on Gardens Point day -> night
  // (default.yaml): uniqueness dips break a run for 10 to 20 frames, and each break costs consistent_frames
  // more to start again; recall 0.56 -> 0.785, 0 wrong (doc/results.md).
  // Nor may the sequence grow worse than the run's last unique frame by more than 5 %: a camera
  // that leaves the route (or a stream that jumps) keeps its old sequence a few frames, matching the end of
  // the route with a rising distance (measured: 0.288 after 0.265 in test_map_sessions' jump).
  return published_ && uniqueEnoughToGoOn(detection, why) &&
         detection.best.distance <= kContinueSlack * unique_distance_ && advancesWithRun(detection);
}

bool LoopDecision::uniqueEnoughToGoOn(const Detection& detection, FrameStatus why) const
{
  return why == FrameStatus::NotUnique && !coasted_ && detection.uniqueness >= options_.continue_uniqueness;
}

FrameStatus LoopDecision::decide(const Detection& detection, const GeometryCheck& geometry)
{
  joined_before_.clear();
  if (frames_since_search_kept_ != SIZE_MAX)
    ++frames_since_search_kept_;
  if (jumped_ahead_.frames_since != SIZE_MAX)
    ++jumped_ahead_.frames_since;
  if (detection.has_candidates && std::isfinite(detection.relief))
  {
    reliefs_.push_back(detection.relief);
    if (reliefs_.size() > kReliefFrames)
      reliefs_.pop_front();
  }
  const FrameStatus status = decideFrame(detection, geometry);
  if (status == FrameStatus::Published)
    line_ = Line{detection.best.id, runSlope(), detection.best.direction, detection.best.session, 0, true};
  else if (++line_.frames_since >= static_cast<size_t>(std::max(0, options_.run_resume_frames)))
    line_.valid = false;
  // A short map's revisit begins before its map holds min_candidates places beyond the short window (a route of 40
  // places walked again: frames 40-50 too early with the window of 30), so its first frames are too early, not
  // unknown: their best match is the path's, and a run on its line reaches back to them as to frames not unique.
  // Not at the map's first place, which starts no run either (startsNoRun): the first pass's last frames match it
  // (GP day_right then night_right 125-166, with a run whose line passed a place ahead: frame 41 joined at place 0).
  const bool too_early_in_short_map = status == FrameStatus::TooEarly && detection.has_candidates &&
                                      detection.short_map && !detection.best_at_session_start;
  const bool coasting = status == FrameStatus::Featureless && published_;  // a published run coasts on through it
  const bool may_be_late = status == FrameStatus::Inconsistent ||
                           (status == FrameStatus::NotUnique && detection.has_candidates) || too_early_in_short_map ||
                           coasting;
  const bool may_join = options_.run_start_tolerance >= 0 && may_be_late;
  past_.push_back(Past{detection.best.id, detection.best.direction, detection.best.session, may_join, status,
                       detection.best.pace * detection.best.direction});
  if (past_.size() > kMaxJoined + 1)
    past_.pop_front();
  return status;
}

FrameStatus LoopDecision::decideFrame(const Detection& detection, const GeometryCheck& geometry)
{
  FrameStatus status = FrameStatus::Published;
  if (!detection.has_candidates)
    status = detection.excluded ? FrameStatus::Excluded : FrameStatus::TooEarly;
  else if (detection.candidates < static_cast<size_t>(options_.min_candidates))
    status = FrameStatus::TooEarly;
  else if (!published_ && startsNoRun(detection))
    status = FrameStatus::Excluded;
  else if (featureless())
    return coast(detection);
  else
  {
    const bool passes = gatesPass(detection, status) || continuesPublishedRun(detection, status);
    bool leaves_coast = false;
    if (passes && status == FrameStatus::Published)  // passed the gates itself, not as a continuation
    {
      unique_distance_ = detection.best.distance;
      leaves_coast = coasted_ && published_;
      coasted_ = false;
    }
    if (resumesPublishedLine(detection, status))
      return resumeRun(detection, line_.slope);
    if (passes)
      return joinRun(detection, leaves_coast);
  }
  // Geometry may stand in for the appearance evidence this frame lacks (asked only then: it costs a RANSAC).
  if (geometry && geometryMayStandIn(detection, status) && geometry())
  {
    unique_distance_ = detection.best.distance;
    return joinRun(detection);
  }
  endRun();
  return status;
}

double LoopDecision::runSlope() const
{
  return recent_.size() < 2 ? 0.0
                            : (static_cast<double>(recent_.back()) - static_cast<double>(recent_.front())) /
                                  static_cast<double>(recent_.size() - 1);
}

bool LoopDecision::resumesPublishedLine(const Detection& detection, FrameStatus why) const
{
  // A published run broken by a dip of uniqueness (a look-alike place for a few frames) leaves its line: where
  // the revisit goes on, its next frames' matches lie on that line, extended, though they are seldom unique
  // enough to start a run again (consistent_frames at min_uniqueness). Measured on Gardens Point day_right then
  // day_left: after a dip at frame 163 of the revisit, every match of frames 168 to 199 on the line, at uniqueness
  // 0.04 to 0.085. Within run_resume_frames frames of the line's last published frame, a frame that continues it
  // as a published run's frame would (continue_uniqueness, the distance slack) resumes the run.
  if (published_ || !line_.valid || options_.run_resume_frames <= 0)
    return false;
  const bool unique_enough = why == FrameStatus::Published || uniqueEnoughToGoOn(detection, why);
  if (!unique_enough || detection.best.distance > kContinueSlack * unique_distance_ || !alongLine(detection))
    return false;
  return std::fabs(static_cast<double>(detection.best.id) - lineExtended()) <= options_.consistency_tolerance;
}

bool LoopDecision::alongLine(const Detection& detection) const
{
  return detection.best.direction == line_.direction && detection.best.session == line_.session;
}

double LoopDecision::lineExtended() const
{
  return static_cast<double>(line_.match) + line_.slope * static_cast<double>(line_.frames_since + 1);
}

bool LoopDecision::fasterThanLine(const Detection& detection) const
{
  return detection.best.pace > line_.slope * line_.direction + kFasterPace;
}

bool LoopDecision::catchesUp(const Detection& detection) const
{
  // While a revisit speeds up, the best path keeps its pace and falls a few places behind; when a path of the next pace
  // takes over, the match jumps forward onto the route and the run, broken by its own line, needed consistent_frames
  // more to be published again (GP day_right then night_right, a pace varying over 400 frames: 15 frames lost so, their
  // matches 0 to 1 places off). With placeInHindsight, the matcher searching while the run catches up and the
  // second frame asked for (followsJump), 90 pace streams 44.27 -> 44.84 summed recall at 287 -> 269 wrong loops, 35
  // not tuned on 18.20 -> 18.83 at 234 -> 223 (doc/results.md "A run that catches up"). Only ahead, and only a few
  // places: a match that falls back or leaps is not a path catching up.
  if (options_.max_pace <= 1 || !published_ || !line_.valid || !alongLine(detection))
    return false;  // (at one pace no faster path can take over)
  if (!fasterThanLine(detection))
    return false;  // the path that takes over is faster than the run's line
  const double ahead = (static_cast<double>(detection.best.id) - lineExtended()) * line_.direction;
  return ahead > options_.consistency_tolerance && ahead <= kCatchUpPlaces;
}

bool LoopDecision::followsJump(const Detection& detection) const
{
  if (!alongLine(detection))
    return false;
  const double expected = static_cast<double>(jumped_ahead_.match) + jumped_ahead_.pace * line_.direction;
  return std::fabs(static_cast<double>(detection.best.id) - expected) <= options_.consistency_tolerance &&
         fasterThanLine(detection);
}

FrameStatus LoopDecision::resumeRun(const Detection& detection, double slope)
{
  // The run goes on as if it had never broken: its last consistent_frames matches on a line of its slope through
  // this frame's match, so the frames before it that may join are judged against the line this frame is on
  // (through the old line's extension instead, which this frame may be 2 places off, GP day_right -> night_right
  // lost 6 frames a later run would have reached back to).
  const size_t frames = static_cast<size_t>(std::max(1, options_.consistent_frames));
  recent_.clear();
  for (size_t k = frames - 1; k > 0; --k)
  {
    const double on_line = static_cast<double>(detection.best.id) - slope * static_cast<double>(k);
    recent_.push_back(static_cast<uint64_t>(std::max(0.0, std::round(on_line))));
  }
  recent_.push_back(detection.best.id);
  run_ = static_cast<int>(frames);
  run_start_match_ = recent_.front();
  previous_match_ = detection.best.id;
  previous_direction_ = detection.best.direction;
  previous_session_ = detection.best.session;
  published_ = true;
  joined_before_ = framesOnLineBefore(detection.best.pace * detection.best.direction);
  return FrameStatus::Published;
}

FrameStatus LoopDecision::coast(const Detection& detection)
{
  // Not a loop closure, but not the end of the revisit either: a run whose matches go on along its line through a
  // stretch of look-alike places is the same run after it (its frames before the stretch may still be reached
  // back to, its line still holds). Nordland's short route through a stretch of 8 such places (frames 300-399 at
  // 2x) kept 16 of its 41 right loops where the run ended there, 37 where it coasts.
  // But a run that coasted publishes again only from a frame that passes the gates itself (coasted_): after the
  // stretch its sequence still holds the stretch and may lag the revisit, and frames at continue_uniqueness are then
  // no evidence it does not (Nordland summer then winter, winter 541-548: two places behind after 20 featureless
  // frames, published at uniqueness 0.026-0.053 as the run went on or resumed; 5 wrong loops at 1x wherever a change
  // elsewhere moved them by a thousandth, doc/results.md).
  if (advancesWithRun(detection))  // (never without a run)
  {
    extendRun(detection, true);
    coasted_ = true;
  }
  else
    endRun();
  return FrameStatus::Featureless;
}

void LoopDecision::extendRun(const Detection& detection, bool advances)
{
  if (advances)
    ++run_;
  else
  {
    run_ = 1;
    run_start_match_ = detection.best.id;
    recent_.clear();
  }
  recent_.push_back(detection.best.id);
  while (recent_.size() > static_cast<size_t>(options_.consistent_frames))
    recent_.pop_front();
  previous_match_ = detection.best.id;
  previous_direction_ = detection.best.direction;
  previous_session_ = detection.best.session;
}

FrameStatus LoopDecision::joinRun(const Detection& detection, bool leaves_coast)
{
  // A catch-up takes two frames: the jump ahead (catchesUp, judged against the run as it was), then the next frame on
  // the faster path's line. A jump for one frame is a look-alike place further on, not a lag made up (GP day_left
  // 50-149 continued into day_right and night_right, at one pace: 437 -> 88 to 440 -> 91 on the line, 441 -> 95 at
  // pace 1.15, 442 -> 93 back on it; caught up at 441, loop 438 was placed in hindsight 4 places off).
  const bool catches_up = jumped_ahead_.frames_since == 1 && followsJump(detection);
  if (catchesUp(detection))
    jumped_ahead_ = Jump{detection.best.id, detection.best.pace, 0};
  extendRun(detection, advancesWithRun(detection));
  const bool was_published = published_ && run_ > 1;
  published_ = run_ >= options_.consistent_frames && recentFramesFollowOneLine();
  if (!published_ && catches_up)
  {
    // The run goes on, on a line at the new best path's pace (its old slope is the lagging path's).
    frames_since_search_kept_ = 0;
    return resumeRun(detection, detection.best.pace * detection.best.direction);
  }
  // The run reaches back where it is published from this frame on: its first frames, and the frames before them on
  // its line; or where it comes out of a stretch of look-alike places it coasted through, passing the gates: it was
  // the revisit all along, and its frames in the stretch, on its line, join it now (and its last frames before the
  // stretch, left unconfirmed by it). Counted on the pace and holdout sets' decisions.csv: of the featureless frames
  // between two published ones, 266 and 27, every one was right (Nordland's snowfields). Measured: Nordland summer
  // then winter 1x 0.907 -> 0.937, 2x 0.928 -> 0.972 (doc/results.md "A stretch a published run coasted through").
  if (published_ && (!was_published || leaves_coast))
    joined_before_ = framesOnLineBefore(detection.best.pace * detection.best.direction);
  // A revisit of a short route begins: within exclusion_window frames of the first pass its first frames fit any
  // pace, and the pace prior, off at once, let a slower path take the run 2 to 4 places behind (GP day_left then
  // day_right 0-59, revisit frames 70-79, 10 wrong loops at a window of 30, doc/results.md). A long map's revisit
  // has had its first frames too_early or excluded while the path settled.
  if (published_ && !was_published && detection.short_map && !line_.valid)
    frames_since_search_kept_ = 0;
  return published_ ? FrameStatus::Published : FrameStatus::Inconsistent;
}

std::vector<size_t> LoopDecision::framesOnLineBefore(double pace) const
{
  // The frames a run needs before it is consistent were right where the run is right: its matches were on the
  // line already, and often so were the frames before it that were not unique enough to start it (the revisit
  // had begun, its evidence had not). Published after the fact (a backend takes a loop closure with its own
  // stamp): Gardens Point day_right then night_right, default.yaml, recall 0.765 -> 0.87, day_right then day_left
  // 0.335 -> 0.58 (doc/results.md). Held to a tighter line than the consistency rule: at the start of a revisit,
  // and where the pace changes, the sequence lags the true place by a few places before its matches settle on
  // the line (the run's frames with no line of their own: 30 more wrong loops on 90 pace streams).
  // A published frame is counted too: the last ones of a run that broke before they were confirmed are still
  // held (LoopConfirmation), and a run on their line takes them; the ones that went out are not held any more,
  // and the confirmation joins only what it holds.
  // Up to kMaxSkipped not-unique frames in a row off the line (a look-alike place for a frame or two; or a short map's
  // too-early frames, whose paths are a few frames long) are passed over, not joined: GP day_right then day_left,
  // matches 2 and 3 places off at revisit frames 30-31 ended the reach-back there, with the frames before them on the
  // line. A frame unique enough but off the line is not a look-alike place: the run's own sequence disagreed there (a
  // lagging start), and the reach-back ends (passing over those too joined frames 3 places off at the start of a
  // session continued from a map).
  // A held published frame (its run broke before confirm_frames more went on with it) passed the gates and kept to
  // its own run's line within consistency_tolerance: it joins a run whose line passes that close, when the frame
  // after it joined too. Where the pace eases for a few frames the sequence lags, its run breaks as the match jumps
  // back onto the route, and the lagging frames were 2 places off the new run's line: GP day_right then day_left
  // 0.865 -> 0.900. Not across a gap: a stretch of look-alike places leaves the sequence lagging 2 places, every
  // other frame published and not unique in turn (Nordland summer then winter, default.yaml, 4 wrong at 1x).
  // The run's line is the one through its first and last matches: a place off at either end tilts it, and extended
  // back ten frames a tilt of a tenth of a place a frame misses by one more (GP day_right then night_right at 3x:
  // the run's matches 39 .. 65 over 9 frames, slope 2.89, the frames before it 1.1 and 1.2 places off, at pace 3
  // exactly on). So a frame also joins on the line of the best path's `pace` through the last match, where its own
  // best path held that pace (within kSamePace): a straight line at the pace the path followed, not across a change
  // of it (without that condition, 20 more wrong loops on the pace set, where varying and random paces changed between
  // the run and the frames before it). On the path's line a frame is within run_start_tolerance, never the wider
  // tolerance of a held run frame: a run that broke 3 places behind the revisit (GP day_left then night_right at the
  // place server, night_right 41 as day_left 38) would join the next run's line 2 places off. doc/results.md: 3x
  // 0.761 -> 0.821; summed recall pace 52.13 -> 52.28, holdout 21.63 -> 21.94, short 37.27 -> 37.58, one more wrong
  // loop over the 220 streams.
  // A frame that passed the gates itself (Inconsistent: unique, its run not yet long enough) joins on the run's line
  // even after the reach-back went on along the path's line alone: its own run followed a slower path at the
  // revisit's start, so it is off the path's line, but its matches were the run's. GP day_right then day_left 140-199
  // in the view channel: revisit frames 71-80, uniqueness 0.062-0.082 and 0 or 1 place off, were cut off behind 81-89,
  // joined on the path's line (doc/results.md).
  std::vector<size_t> joined;
  if (options_.run_start_tolerance < 0 || recent_.size() < 2)
    return joined;
  const double last = static_cast<double>(recent_.back());
  const double slope = runSlope();
  const bool path_agrees = std::fabs(slope - pace) <= kPathAgrees * std::fabs(pace);
  bool path_only = false;  // once a frame is on the path's line alone, the run's line is off there: one line on
  size_t back = 0, skipped = 0;
  for (auto p = past_.rbegin(); p != past_.rend() && back < kMaxJoined; ++p)
  {
    ++back;
    const double expected = last - slope * static_cast<double>(back);
    if (p->status == FrameStatus::Featureless)
    {
      // Passed over: not the end of the run's frames before it. A frame a published run coasted through (may_join)
      // joins where it lies on the run's line: the run after the stretch was the revisit all along. By any run's
      // reach-back, not only the coasted run's own: where that run ends in the stretch, the next one takes it.
      if (p->may_join && std::fabs(static_cast<double>(p->id) - expected) <= options_.run_start_tolerance)
        joined.push_back(back);
      continue;
    }
    if (!(p->may_join || p->status == FrameStatus::Published) || p->direction != previous_direction_ || p->session != previous_session_)
      break;
    const bool follows_joined = joined.empty() ? back == 1 : joined.back() + 1 == back;
    const double tolerance = p->status == FrameStatus::Published && follows_joined
                                 ? std::max(options_.run_start_tolerance, options_.consistency_tolerance)
                                 : options_.run_start_tolerance;
    const bool on_path_line = path_agrees && std::fabs(p->pace - pace) <= kSamePace * std::fabs(pace) &&
                              std::fabs(static_cast<double>(p->id) - (last - pace * static_cast<double>(back))) <=
                                  options_.run_start_tolerance;
    const bool run_line_holds = !path_only || p->status == FrameStatus::Inconsistent;
    const bool on_run_line = run_line_holds && std::fabs(static_cast<double>(p->id) - expected) <= tolerance;
    if (on_run_line || on_path_line)
    {
      path_only = path_only || !on_run_line;
      joined.push_back(back);
      skipped = 0;
    }
    else if ((p->status != FrameStatus::NotUnique && p->status != FrameStatus::TooEarly) || ++skipped > kMaxSkipped)
      break;
  }
  return joined;
}

}  // namespace openable
