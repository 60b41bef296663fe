#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "openable/config.h"
#include "openable/detection/map_matcher.h"

namespace openable
{
/// What became of one frame: published, or the first reason it gave no loop closure.
enum class FrameStatus
{
  Published,           ///< a loop closure went out
  NotKeyframe,         ///< not stored: the camera has not moved enough since the last keyframe
  Standstill,          ///< not stored: the image is the last stored one again (the camera stands still)
  TimeJump,            ///< not stored: its stamp is earlier than the previous frame's
  TooEarly,            ///< fewer than min_candidates places with a long enough sequence to compare with
  Excluded,            ///< history exists, but every frame of it is inside the exclusion (frames or seconds), or
                       ///< the best match is the exclusion's edge (the newest place compared) or a short map's first
                       ///< place, and starts no run
  AboveThreshold,      ///< best normalised distance > threshold
  NotUnique,           ///< uniqueness (1 - best / second best) < min_uniqueness, or no gate is set at all
  Inconsistent,        ///< fewer than consistent_frames consecutive frames agree on where the loop is
  Featureless,         ///< the places around the best match look alike (min_relief): where it is cannot be told
  FailedVerification,  ///< geometric verification rejected the candidate
  Unverified,          ///< verification is required but could not run (no camera, no features)
  Pending,             ///< passed every rule; published once confirm_frames more frames go on with its run
  Unconfirmed,         ///< passed every rule, but its run ended within confirm_frames frames: not published
};

/// The word used in outputs (loop_closures.csv, decisions.csv, LoopClosure.status): "published",
/// "not_keyframe", "standstill", "time_jump", "too_early", "excluded", "above_threshold", "not_unique", "inconsistent",
/// "featureless", "failed_verification", "unverified", "pending", "unconfirmed".
const char* toString(FrameStatus status);

/// How unique a best match is, higher = surer: 1 - best / second best (0 when the second best is 0), 1
/// without a rival. The one definition of uniqueness: MapMatcher and CandidateMerger fill
/// Detection::uniqueness with it, LoopDecision gates and scores on it.
float matchUniqueness(float best, std::optional<float> second_best);

/// The part of the loop-closure decision that needs no images: the gates and temporal consistency.
///
/// Measured in loop-closure mode (one stream revisiting itself, doc/results.md): the false loops of a
/// uniqueness gate alone come from the first traversal, where there is no loop at all, and almost all of
/// them while only a few places can be compared (the "second best" then comes from a handful of frames,
/// and a single candidate was even called unique). So a frame must have min_candidates places to choose
/// from, pass every gate that is set, and agree with the consistent_frames - 1 frames before it: their
/// best matches advance together, one place per frame within consistency_tolerance (a revisit at about
/// the same speed, as sequence matching assumes anyway), step by step and over the whole run.
/// What LoopDecision reads of a Config (the keys of the same names): the gates and the consistency rule.
struct DecisionOptions
{
  double threshold;             ///< -1: off
  double min_uniqueness;        ///< 0: off
  double continue_uniqueness;   ///< a published run goes on through frames at least this unique
  int min_candidates;           ///< candidate places a frame must have to choose from
  int consistent_frames;        ///< frames that must agree before a loop is published
  int consistency_tolerance;    ///< places a match may be off the run's line
  int max_pace;                 ///< a run advances from 1 / max_pace to max_pace places per frame
  double verified_min_uniqueness;  ///< geometry stands in for min_uniqueness down to this uniqueness (-1: off)
  int run_start_tolerance;         ///< frames before a run within this of its line join it once published (-1: off)
  int run_resume_frames;           ///< frames after a published run breaks that a frame on its line resumes it (0: off)
  double min_relief;               ///< the median relief of the last kReliefFrames frames must reach this (0: off)

  static DecisionOptions from(const Config& config);
};

class LoopDecision
{
public:
  explicit LoopDecision(const DecisionOptions& options);
  /// Shorthand: LoopDecision(DecisionOptions::from(config)).
  explicit LoopDecision(const Config& config);

  /// Whether geometry confirms the frame's best match (geometric verification); asked at most once a frame.
  using GeometryCheck = std::function<bool()>;

  /// Decides on one matched frame. Returns Published when every rule passes; verification comes after.
  /// With `geometry` (and verified_min_uniqueness >= 0), a frame that fails only the uniqueness gate or the
  /// minimum of places, but is at least verified_min_uniqueness unique and within the distance gate, joins the
  /// run when geometry confirms its best match: published once the run is consistent, as any other.
  FrameStatus decide(const Detection& detection, const GeometryCheck& geometry = GeometryCheck());
  /// After a Published decision: which of the stored frames just before this one join its loop closure now,
  /// published after the fact, as frames back from this one (1: the frame just before), nearest first. Not empty
  /// only where the run becomes consistent (or resumes): counted back from this frame, the frames that may join
  /// (mayJoinLater: the run's first frames, and before them frames not unique enough) or were published (the last of
  /// an earlier run may have broken before they were confirmed) whose matches lie within run_start_tolerance of the
  /// run's line, passing over at most kMaxSkipped NotUnique frames in a row that do not, up to the first frame that
  /// may not join or is off the line otherwise (at most kMaxJoined back). The confirmation joins those it
  /// still holds (published ones that went out are not held). Empty after any other decision.
  const std::vector<size_t>& joinedBefore() const
  {
    return joined_before_;
  }
  /// After a Published decision: how many of the stored frames just before this one are its run's own frames (the
  /// consecutive frames that passed and agree, less this one; at most kMaxJoined). A run that broke and goes on
  /// within them is the same run (LoopConfirmation takes back what it had reached back to).
  size_t ownFramesBefore() const
  {
    return published_ && run_ > 1 ? std::min<size_t>(static_cast<size_t>(run_ - 1), kMaxJoined) : 0;
  }
  /// Whether the last decided frame may join a run published later: it was Inconsistent (one of a run's first
  /// frames), or NotUnique with a best match (a revisit whose evidence was still too weak). A caller holds such
  /// frames (LoopConfirmation) until joinedBefore() says which join. Never with run_start_tolerance -1.
  bool mayJoinLater() const
  {
    return !past_.empty() && past_.back().may_join;
  }
  /// The most frames a run reaches back (joinedBefore).
  static constexpr size_t kMaxJoined = 256;
  /// Not-unique frames in a row off the run's line that a reach-back passes over (joinedBefore): a look-alike place
  /// for a frame or two. Measured on 90 pace streams (doc/results.md "A run reaches further back"): summed recall
  /// +0.26 / +0.49 / +0.54 for 1 / 2 / 14 more wrong loops at 1 / 2 / 3 frames.
  static constexpr size_t kMaxSkipped = 2;
  /// A frame before a run joins on the line of the run's best path's pace only where its own best path's pace was
  /// within this fraction of it (framesOnLineBefore): the same pace of the 17 followed (they lie 15 % apart).
  static constexpr double kSamePace = 0.05;
  /// ... and where the run's own line (through its first and last matches) lies within this fraction of that pace:
  /// one step of the grid, the run and its path telling the same pace.
  static constexpr double kPathAgrees = 0.15;
  /// Frames whose Detection::relief the min_relief gate takes the median of: one frame's is noisy (a passing
  /// train, a lamp post), a stretch of look-alike places lasts tens of frames.
  static constexpr size_t kReliefFrames = 5;
  /// The decision score, higher = surer: the uniqueness of the best match; 0 while it means nothing (no
  /// candidates, fewer than min_candidates, or no rival place: a lone candidate would score 1).
  float score(const Detection& detection) const;

  /// Takes new values of the decision keys (threshold, min_uniqueness, min_candidates, consistent_frames,
  /// consistency_tolerance); the consistency run restarts.
  void setOptions(const DecisionOptions& options);
  /// Forgets the consistency run and the frames decided so far (a new stream, or a gap in it).
  void reset();
  /// The matcher should go on searching (its pace prior on) although the last frame was published, as it would
  /// while a broken run became consistent again: for consistent_frames frames after a published run caught up
  /// (followsJump), or after a short map's run was first published with no published line before it (a revisit
  /// begins: its first frames fit any pace, and off at once the prior let a slower path take the run).
  bool keepsSearching() const
  {
    return frames_since_search_kept_ < static_cast<size_t>(std::max(0, options_.consistent_frames));
  }
  /// The most places a published run's match may jump ahead of its line and the run goes on (catchesUp).
  static constexpr double kCatchUpPlaces = 5.0;
  /// How much faster (places a frame) than the run's line the path that catches up must be.
  static constexpr double kFasterPace = 0.05;

private:
  bool gatesPass(const Detection& detection, FrameStatus& why) const;
  /// The places around the recent frames' matches look alike (min_relief).
  bool featureless() const;
  /// The best match is the newest place compared: the exclusion window's edge.
  bool pressedAgainstExclusion(const Detection& detection) const;
  /// The best match may start no run: the exclusion's edge, or a short map's first place.
  bool startsNoRun(const Detection& detection) const;
  /// The distance gate is set and the best match fails it.
  bool aboveThreshold(const Detection& detection) const;
  /// Geometry may stand in for the rule the frame failed, `why`: the uniqueness gate or the minimum of places.
  bool geometryMayStandIn(const Detection& detection, FrameStatus why) const;
  /// The frame passed the gates (or geometry stood in for them): the run goes on or starts with it. Returns
  /// Published once the run is consistent, else Inconsistent. `leaves_coast`: the frame passed the gates itself
  /// right after the published run coasted through a featureless stretch.
  FrameStatus joinRun(const Detection& detection, bool leaves_coast = false);
  /// The run goes on with the frame's match where it `advances` with it (advancesWithRun), else starts again
  /// from it: its count, its line, its last match.
  void extendRun(const Detection& detection, bool advances);
  /// A featureless frame: the run goes on through it where its match advances with the run, and it is never
  /// published (Featureless).
  FrameStatus coast(const Detection& detection);
  bool advancesWithRun(const Detection& detection) const;
  bool recentFramesFollowOneLine() const;
  FrameStatus decideFrame(const Detection& detection, const GeometryCheck& geometry);
  /// Forgets the consistency run (a frame that failed); the frames decided before it stay (a run may reach back).
  void endRun();
  /// The frames before this one that may join, with matches within run_start_tolerance of the run's line
  /// (joinedBefore).
  /// `pace`: the best path's pace at this frame (places a frame, signed by direction).
  /// Featureless frames are passed over, those a published run coasted through joining where they lie on its line.
  std::vector<size_t> framesOnLineBefore(double pace) const;
  /// The slope of the run's recent matches (places per frame; 0 with fewer than two).
  double runSlope() const;
  /// The last published frame is at most run_resume_frames frames back, its run broke, and this frame's match lies
  /// on its line extended (within consistency_tolerance), as unique as a published run's frame must be
  /// (continue_uniqueness; after the run coasted, min_uniqueness).
  bool resumesPublishedLine(const Detection& detection, FrameStatus why) const;
  /// The published run's match jumps ahead of its line, by more than consistency_tolerance and at most
  /// kCatchUpPlaces, on a path faster than the line: a path of a faster pace may be taking over from one that lagged
  /// the revisit (followsJump decides on the next frame).
  bool catchesUp(const Detection& detection) const;
  /// The match follows the published line's route: its direction, in its session.
  bool alongLine(const Detection& detection) const;
  /// Where the published line puts this frame's match: extended by its slope over the frames decided since.
  double lineExtended() const;
  /// The best path is faster than the published line by more than kFasterPace.
  bool fasterThanLine(const Detection& detection) const;
  /// The frame after a jump ahead (catchesUp) is on the faster path's line from it: the run has caught up.
  bool followsJump(const Detection& detection) const;
  /// The run resumes as published, on a line of `slope` places a frame through this frame's match
  /// (resumesPublishedLine: the old line's; followsJump: the new best path's pace).
  FrameStatus resumeRun(const Detection& detection, double slope);
  /// A frame that failed only the uniqueness gate continues the published run: continue_uniqueness (not after the run
  /// coasted, until a frame passes the gates itself).
  bool continuesPublishedRun(const Detection& detection, FrameStatus why) const;
  /// A frame that failed only the uniqueness gate is unique enough for a run to go on or resume with it:
  /// continue_uniqueness, and not after the run coasted until a frame passes the gates itself (coasted_).
  bool uniqueEnoughToGoOn(const Detection& detection, FrameStatus why) const;

  DecisionOptions options_;
  int run_ = 0;                   ///< consecutive frames (ending at the previous one) that passed and agree
  bool published_ = false;        ///< the previous frame was published (its run is a loop)
  double unique_distance_ = 0.0;  ///< distance of the last frame that passed the gates itself
  uint64_t run_start_match_ = 0;  ///< best match of the run's first frame
  uint64_t previous_match_ = 0;   ///< best match of the previous frame
  int previous_direction_ = 1;
  uint32_t previous_session_ = 0;
  std::deque<uint64_t> recent_;  ///< the run's last consistent_frames matches
  std::vector<size_t> joined_before_;  ///< joinedBefore() of the last decision
  /// The line of the last published frame, kept after its run breaks (resumesPublishedLine).
  struct Line
  {
    uint64_t match = 0;
    double slope = 0.0;
    int direction = 1;
    uint32_t session = 0;
    size_t frames_since = 0;  ///< frames decided after it
    bool valid = false;
  };
  Line line_;
  /// Each decided frame's best match, for a run that reaches back; the last kMaxJoined + 1, oldest first.
  struct Past
  {
    uint64_t id;
    int direction;
    uint32_t session;
    bool may_join;
    /// As decided: a Published frame's loop closure may still be pending when its run breaks; a NotUnique one off a
    /// later run's line is a look-alike place the reach-back may pass over.
    FrameStatus status;
    double pace;  ///< its best path's pace (places a frame, signed by direction)
  };
  std::deque<Past> past_;
  std::deque<float> reliefs_;  ///< Detection::relief of the last kReliefFrames frames that had one
  /// The last frame's match, when it jumped ahead of the published run's line (catchesUp).
  struct Jump
  {
    uint64_t match = 0;
    double pace = 1.0;
    size_t frames_since = SIZE_MAX;  ///< frames decided after it
  };
  Jump jumped_ahead_;
  /// Frames decided since the last catch-up or short map's first published run (keepsSearching).
  size_t frames_since_search_kept_ = SIZE_MAX;
  /// The run coasted through featureless frames (coast) and no frame has passed the gates itself since: it neither
  /// goes on nor resumes at continue_uniqueness.
  bool coasted_ = false;
};

}  // namespace openable
