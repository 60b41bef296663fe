#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_set>
#include <vector>

#include "openable/detection/frame_outcome.h"
#include "openable/error.h"

namespace openable
{
/// Publishes a frame's loop closure only once the next `frames` stored frames went on with its run.
///
/// Why: at a changing pace the end of the best sequence lags (or leads) the true place by a few places, and
/// the revisit's next frames show it: the run breaks (its match jumps back onto the route) within a frame
/// or two. Waiting for them drops those loops. Measured on the pace streams of doc/results.md (simulated
/// on decisions.csv, then run): Gardens Point, 22 streams, 35 -> 6 wrong at 3 frames, recall 0.254 -> 0.232;
/// Nordland, 8 streams, 327 -> 178 wrong, recall 0.478 -> 0.463 (the last frames of every run are lost). A
/// loop closure arrives `frames` keyframes late, with its own frame's stamp.
///
/// A frame standing still repeats the last stored frame's decision: while that one is pending, the repeats
/// wait with it (up to kMaxRepeats) and are confirmed or dropped with it.
///
/// A run's first frames and the frames before it (LoopDecision::joinedBefore): the frames that may join a run
/// (LoopDecision::mayJoinLater) just before a published one are held with their repeats; the ones the decision
/// says join the run's loop closure wait with it and are confirmed with it, each with status_before its own
/// status (Inconsistent, NotUnique, or Standstill for a repeat). A published frame whose run broke before it was
/// confirmed is held again with the frames it took; a later run that takes it back among its own frames
/// (LoopDecision::ownFramesBefore) takes those too (joining()).
///
/// Outcome: what a pipeline decides for one frame, with a FrameStatus `status` and `published()`
/// (FrameOutcome in OnlineDetector and the map replay, MergedOutcome in the place servers' CandidateMerger).
template <typename Outcome>
class BasicLoopConfirmation
{
public:
  /// Repeats of one pending frame kept for its confirmation (a standstill of about 5 minutes at 10 Hz).
  static constexpr size_t kMaxRepeats = 3000;

  /// frames: 0 publishes at once (the outcome passes through unchanged). Throws Error when negative.
  explicit BasicLoopConfirmation(int frames)
  {
    setFrames(frames);
  }

  /// A stored frame, after the decision and verification. A Published outcome becomes Pending (frames > 0); the
  /// held frames `joined_before` frames back from it (LoopDecision::joinedBefore; 1: the frame just before) join it,
  /// those not held are passed over. Returns the earlier
  /// outcomes it confirms, oldest first, each Published (frames 0: the frames that joined it); when the frame is
  /// not Published itself, the run ended and every pending one is dropped, and it is held when it `may_join` a
  /// later run (LoopDecision::mayJoinLater, and whatever else the caller requires of it). `own_before`: how many of
  /// the stored frames just before it are its run's own (LoopDecision::ownFramesBefore; see joining()).
  std::vector<Outcome> stored(Outcome& outcome, const std::vector<size_t>& joined_before = {}, bool may_join = false,
                              size_t own_before = 0)
  {
    std::vector<Outcome> confirmed;
    const uint64_t index = ++stored_;
    if (!outcome.published())
    {
      dropped_ += pendingOwn();  // the run ended (or never was): what waited for it is not confirmed
      holdUnconfirmed();
      hold(outcome, may_join, index);
      return confirmed;
    }
    for (Waiting& w : waiting_)
      ++w.confirmations;
    while (!waiting_.empty() && waiting_.front().confirmations >= frames_)
    {
      confirm(waiting_.front(), confirmed);
      waiting_.pop_front();
    }
    // The run's first frames that join it: confirmed with this frame, oldest first.
    const std::vector<bool> joins = joining(joined_before, index, own_before);
    for (size_t i = 0; i < held_.size(); ++i)
      if (joins[i])
      {
        Waiting& w = held_[i];
        w.joined_by = index;
        if (frames_ == 0)
          confirm(w, confirmed);
        else
          waiting_.push_back(std::move(w));
      }
    held_.clear();
    if (frames_ > 0)
    {
      outcome.status = FrameStatus::Pending;
      waiting_.push_back(Waiting{{outcome}, 0, false, index});
    }
    return confirmed;
  }

  /// A frame standing still that repeats the last stored one's outcome: it waits with it when that one is Pending
  /// or held as a run's first frame.
  void repeated(const Outcome& outcome)
  {
    std::deque<Waiting>& to = outcome.status == FrameStatus::Pending ? waiting_ : held_;
    if (outcome.published() || to.empty())
      return;
    std::vector<Outcome>& outcomes = to.back().outcomes;
    if (outcomes.size() <= kMaxRepeats)
      outcomes.push_back(outcome);
  }

  /// Drops what is pending (a reset of the stream).
  void reset()
  {
    waiting_.clear();
    held_.clear();
  }
  /// New `frames`; what is pending is dropped. Throws Error when negative.
  void setFrames(int frames)
  {
    if (frames < 0)
      throw Error("confirm_frames " + std::to_string(frames) + " is out of range; expected frames >= 0");
    frames_ = frames;
    reset();
  }

  int frames() const
  {
    return frames_;
  }
  /// Outcomes, repeats included, whose run ended before they were confirmed, since construction (a reset
  /// or new frames drop what is pending without counting it).
  uint64_t dropped() const
  {
    return dropped_;
  }
  /// Outcomes waiting, repeats included (a run's first frames that joined it too).
  size_t pending() const
  {
    size_t count = 0;
    for (const Waiting& w : waiting_)
      count += w.outcomes.size();
    return count;
  }

  /// Frames held for a run that may still become consistent: at most as many as a run reaches back.
  static constexpr size_t kMaxHeld = LoopDecision::kMaxJoined;

private:
  struct Waiting
  {
    std::vector<Outcome> outcomes;  ///< the stored frame, then its repeats
    int confirmations = 0;          ///< stored frames since it that went on with its run
    bool joined = false;            ///< a frame the run reached back to (not Pending, not counted as dropped)
    uint64_t index = 0;             ///< which stored frame it is (stored() calls, from 1): what joinedBefore counts
    uint64_t joined_by = 0;         ///< the stored frame whose run took it last (its index; 0: none)

    /// A published frame whose run broke before it was confirmed (held again by holdUnconfirmed).
    bool wasPublished() const
    {
      return !outcomes.empty() && outcomes.front().status == FrameStatus::Unconfirmed;
    }
  };

  /// Which held frames join the run of stored frame `index` (one flag a held frame): those the decision says
  /// (`joined_before` back from it), and those that a held published frame among the run's own frames (the
  /// `own_before` stored frames before it) had taken into its run when it was published. Held frames need not be
  /// consecutive: a frame the reach-back passed over (or one it did not take) leaves a gap when the ones around it
  /// are held again after their run broke.
  /// Why the second: a run published and broken before its confirmation holds its frames again, those it reached
  /// back to with it. When a later run's own frames include the old one's published frame (its line bent for a frame
  /// or two), it is the same run, and what the old one judged on its line joins as it would have; the new run's
  /// reach-back, on its own line, can end where a lagging sequence's first frames lie 2 places off (GP day_right then
  /// night_right at a random pace: the frame before a stop of 102 frames, place 68 matched as 66, was lost with its
  /// repeats). Only then: taken by a reach-back alone, ten frames and more later, a broken run brought loops 3 places
  /// off with it (GP day_right then night_right at 2.1x: 0 -> 3 wrong; doc/results.md "A broken run's reach-back").
  std::vector<bool> joining(const std::vector<size_t>& joined_before, uint64_t index, size_t own_before) const
  {
    std::unordered_set<uint64_t> wanted, takers;
    for (size_t back : joined_before)
      if (back > 0 && back < index)
        wanted.insert(index - back);
    std::vector<bool> joins(held_.size(), false);
    for (size_t i = held_.size(); i-- > 0;)  // newest first: a frame's run comes after it
    {
      const Waiting& w = held_[i];
      joins[i] = wanted.count(w.index) > 0 || (w.joined_by > 0 && takers.count(w.joined_by) > 0 && !w.wasPublished());
      if (joins[i] && w.wasPublished() && w.index + own_before >= index)
        takers.insert(w.index);
    }
    return joins;
  }

  void confirm(Waiting& w, std::vector<Outcome>& confirmed)
  {
    for (Outcome& o : w.outcomes)
    {
      o.status_before = w.joined ? o.status : FrameStatus::Pending;
      o.status = FrameStatus::Published;
      confirmed.push_back(std::move(o));
    }
  }
  /// The run ended: what waited for its confirmation is Unconfirmed, held in case a run on its line takes it
  /// after all (the frames the decision counts in joinedBefore() include published ones for that). A look-alike
  /// place for a frame or two breaks a run and a new one starts on the same line: measured on 90 pace streams
  /// (doc/results.md "A run reaches further back"), summed recall 38.84 -> 39.37 for 2 more wrong loops.
  void holdUnconfirmed()
  {
    for (Waiting& w : waiting_)
    {
      for (Outcome& o : w.outcomes)
        if (o.status == FrameStatus::Pending)
          o.status = FrameStatus::Unconfirmed;
      w.confirmations = 0;
      w.joined = true;
      held_.push_back(std::move(w));
    }
    waiting_.clear();
    while (held_.size() > kMaxHeld)
      held_.pop_front();
  }
  /// A frame that may join a later run is held (a Featureless one where a published run coasts through it: the run
  /// that comes out of the stretch takes it); another Featureless one is passed over (the run goes on through it,
  /// LoopDecision::joinedBefore skips it); any other ends what was held.
  void hold(const Outcome& outcome, bool may_join, uint64_t index)
  {
    if (outcome.status == FrameStatus::Featureless && !may_join)
      return;
    if (!may_join)
    {
      held_.clear();
      return;
    }
    held_.push_back(Waiting{{outcome}, 0, true, index});
    if (held_.size() > kMaxHeld)
      held_.pop_front();
  }
  /// Outcomes waiting that were Pending themselves (not frames the run reached back to), repeats included.
  size_t pendingOwn() const
  {
    size_t count = 0;
    for (const Waiting& w : waiting_)
      count += w.joined ? 0 : w.outcomes.size();
    return count;
  }

  int frames_ = 0;
  uint64_t dropped_ = 0;
  uint64_t stored_ = 0;  ///< stored() calls so far: the index of the last stored frame
  std::deque<Waiting> waiting_;
  std::deque<Waiting> held_;  ///< the frames that may join a run, just before the next stored one, oldest first
};

using LoopConfirmation = BasicLoopConfirmation<FrameOutcome>;

/// Where the loop closures that `confirming` just confirmed lie in hindsight: its best path, drawn back at its pace,
/// says where the revisit was at each of them. A loop closure of a forward run at most kHindsightFrames stored frames
/// back, whose best path had another pace than the confirming frame's, moves there when that is kHindsightMin to
/// kHindsightMax places from its own match (Candidate::id and position; has_match_info is cleared, the caller looks
/// the place up again). Why: when a path of a faster pace takes over from one that lagged the revisit, it places the
/// frames before it better than they were placed (doc/results.md "A loop placed in hindsight"); fewer places are the
/// rounding of the line, more are another path, and at one pace the later path is not the better one.
void placeInHindsight(std::vector<FrameOutcome>& confirmed, const FrameOutcome& confirming);
constexpr uint64_t kHindsightFrames = 8;
constexpr long kHindsightMin = 2;
constexpr long kHindsightMax = 4;

/// A stream's outcomes, in the order process() gave them, with every status final: a Pending frame that a
/// later frame confirmed is Published (with the confirmed copy's fields), one that none confirmed is
/// Unconfirmed. `confirmed` lists are emptied. What openable_offline writes to decisions.csv, for tests and tools
/// that score a whole stream.
std::vector<FrameOutcome> settled(std::vector<FrameOutcome> outcomes);

}  // namespace openable
