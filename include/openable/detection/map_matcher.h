#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "openable/config.h"
#include "openable/map/session_map.h"
#include "openable/matching/row_matcher.h"
#include "openable/matching/sequence_matcher.h"

namespace openable
{
/// One matched reference frame.
struct Candidate
{
  uint64_t id = 0;        ///< id of the reference frame (unique within its session)
  uint32_t session = 0;   ///< the session it belongs to (index in the map)
  size_t position = 0;    ///< its position in that session's frames (0 = oldest stored)
  float distance = 1.0f;  ///< normalised sequence distance in [0, 1], 0 = identical
  int8_t direction = 1;   ///< +1 same direction, -1 reverse (bidirectional matching)
  /// Panoramic: the circular shift of sub-panoramas that matched best. Mono with lateral_shift: the query's view
  /// nearest the place, -1 its left edge, +1 its right edge, 0 its centre (what the place stores): -1 means the place's
  /// centre appears lateral_shift of the width further left in the query (the camera turned, or stands, that far to
  /// the right of the place's view); 0 otherwise.
  int16_t shift = 0;
  uint16_t sequence_length = 0;  ///< terms in the sequence (L, or fewer at the start of a chain)
  float pace = 1.0f;  ///< places of the reference per query frame along the sequence (1: the first pass's pace)
};

/// The outcome of one frame.
struct Detection
{
  uint64_t query_id = 0;
  /// false while nothing can be compared yet (start, exclusion window). True with `candidates` 0: a short map's early
  /// places (MapMatcher::earlyPicks), named for a later run to reach back to, too early for a decision.
  bool has_candidates = false;
  bool excluded = false;        ///< no candidates although frames are stored: all inside the exclusion
  bool own_excluded = false;    ///< the query's own session holds frames, all of them inside the exclusion
  size_t candidates = 0;        ///< reference frames compared with a sequence long enough to be a candidate
  Candidate best;
  std::vector<Candidate> top;  ///< up to top_k distinct places, best first
  /// matchUniqueness (loop_decision.h) of the best and the second best place (outside uniqueness_window).
  /// Whether the frame passes the gates is LoopDecision's to say.
  float uniqueness = 0.0f;
  /// How much the query's own frame distances to the places within uniqueness_window of the best match vary
  /// (largest minus smallest), in standard deviations of its distances to every place compared
  /// (RowMatcher::rowSpread): below 1 the places around the match look alike (a snowfield, a tunnel, a bare
  /// wall), and no sequence can tell which of them it is on. NaN when unknown (no candidate, a matcher that
  /// keeps no spread, a merged answer of the place server). LoopDecision gates on it (min_relief).
  float relief = std::nanf("");
  /// Where the exclusion cut the query's own session: the newest of its places that was compared (the ones
  /// after it are inside the exclusion window). Unset when the exclusion cut nothing, or in localisation.
  bool has_exclusion_edge = false;
  uint32_t exclusion_edge_session = 0;
  uint64_t exclusion_edge_id = 0;
  /// The query's own session was matched with the short map's window (MatchOptions::short_map_exclusion): its
  /// candidates and the exclusion's edge above are the second matcher's.
  bool short_map = false;
  /// With the short map's window: the best match is the own session's first place, forwards. A sequence ending
  /// there has no past and its cost is the row's typical one plus a few frames: the end of a short route "matches"
  /// its start (LoopDecision starts no run from it).
  bool best_at_session_start = false;
};

/// Detection::best_at_session_start: the query's own session was a short map, and `best` is its first place
/// (`first_id`, in session `own_session`), forwards. MapMatcher and CandidateMerger fill the field with it.
bool atShortMapStart(const Candidate& best, bool short_map, uint32_t own_session, uint64_t first_id);

/// Detection::excluded: no candidate, the query's own past is stored but all of it inside the exclusion
/// (Detection::own_excluded), and no other session holds a frame (`other_frames`).
bool onlyExcludedPast(const Detection& detection, size_t other_frames);

/// Matches one stream of query frames against every session of a map it does not own: one SequenceMatcher
/// per session, so a sequence never spans two sessions. The stream's own session (when its frames are
/// stored in the map) is matched except its last `exclusion_window` frames and those stamped less than
/// `exclusion_seconds` before the query; other sessions are matched whole. The best places of all
/// sessions compete: the second best that makes a match unique may come from any session.
///
/// Sequences: in loop-closure use (`partial_sequences` false) a sequence is a candidate once it has
/// min_loop_sequence_length frames (21 by default, at most L): partial chains of a few frames at the start of
/// a stream were the main source of false loops (measured, doc/results.md), while waiting for all L frames
/// left a short route (60 places) without a loop. Localisation accepts min_sequence_length terms, because
/// there every query has a true match.
///
/// A short map: while the own session holds at most 2 x exclusion_window + sequence_length frames, a second matcher
/// of that session leaves out only its last short_map_exclusion frames and answers for the session's candidates, so
/// a route walked again within exclusion_window frames (a corridor, a small room) is compared at all. The session's
/// own matcher goes on matching behind it as without it: what a long stream decides once its map has grown does not
/// depend on the short window (one matcher serving both windows moved GP day_left then night_right 1x 0.750 ->
/// 0.290, doc/results.md).
/// What MapMatcher reads of a Config (the keys of the same names): sequences, paces, the exclusion, top-k.
struct MatchOptions
{
  int sequence_length;
  int min_sequence_length;       ///< localisation (partial_sequences): fewer frames are not candidates
  int min_loop_sequence_length;  ///< loop-closure use: the same (0: only full sequences of L frames)
  bool bidirectional;
  int max_pace;  ///< 1: the paper's sequences (SequenceMatcher); more: PaceMatcher
  double pace_penalty;
  int pace_tolerance;
  int screen_places;         ///< PaceMatcher: a row of more places is screened (0 = never)
  double slip_penalty;       ///< a fraction of pace_penalty (PaceMatcher)
  double pace_prior;         ///< a fraction of pace_penalty (PaceMatcher), while searching
  int exclusion_window;      ///< own-session frames too recent to be candidates
  int short_map_exclusion;   ///< the same while the own map is short (-1 or >= exclusion_window: off)
  double exclusion_seconds;  ///< the same in seconds of stamp
  int top_k;
  int uniqueness_window;

  static MatchOptions from(const Config& config);
};

class MapMatcher
{
public:
  MapMatcher(const MatchOptions& options, const DescriptorLayout& layout, bool partial_sequences);
  /// Shorthand: MapMatcher(MatchOptions::from(config), layout, partial_sequences).
  MapMatcher(const Config& config, const DescriptorLayout& layout, bool partial_sequences);

  /// Matches the next query frame. own_session is the session the stream stores its frames in (-1: none).
  /// The map may have gained sessions or frames, or lost its oldest frames, since the last call. `shifted`: the
  /// query's shifted views (Config::lateral_shift), whole descriptors one after another, or none.
  Detection match(const FrameDescriptor& query, const SessionMap& map, int own_session, double stamp,
                  const FrameDescriptor& shifted = FrameDescriptor());

  /// The last query's normalised distance to every frame of the map, sessions one after another in map
  /// order, each by position; NaN where no comparison was made.
  void lastRow(const SessionMap& map, std::vector<float>& out) const;

  /// New matching keys (sequence_length and bidirectional restart every sequence). The caller validates.
  void setOptions(const MatchOptions& options);
  /// Forgets the query stream.
  void reset();
  /// Whether the stream is looking for a loop (RowMatcher::setSearching), for every session's matcher from the next
  /// frame on; matchers made later start searching.
  void setSearching(bool searching);

  int sequenceLength() const
  {
    return options_.sequence_length;
  }

private:
  /// The own-session exclusion, here only: the positions [0, result) of `frames` a query stamped `stamp`
  /// may be compared with (all of them when the session is not the query's own).
  size_t candidateColumns(const PlaceDatabase& frames, bool own, double stamp, int excluded_frames) const;
  /// The short map's matcher when the own session's `frames` are a short map (the short window is on and they hold
  /// at most 2 x exclusion_window + sequence_length frames), made when first needed; else null, and dropped.
  RowMatcher* shortMapMatcher(const PlaceDatabase& frames);
  /// The matcher whose answers stand for `session` in the last match: the short map's for the own session then.
  const RowMatcher& matcherOf(uint32_t session) const;
  /// The candidate in `column` of `session`'s matcher, its sequence of at least `min_terms` frames.
  Candidate candidateAt(const SessionMap& map, uint32_t session, size_t column, int min_terms) const;
  int minTerms() const;
  /// Candidate::shift with shifted views: which of the last query's views (-1 left, 0 centre, +1 right) is nearest
  /// `place`.
  int viewNearest(const uint64_t* place) const;
  /// Detection::relief of the best candidate of `detection`.
  float reliefAround(const SessionMap& map, const Candidate& best) const;

  MatchOptions options_;
  bool partial_sequences_;
  FrameMetric metric_;
  /// A session's matcher: sequences at any pace (PaceMatcher), or at the first pass's pace (max_pace 1).
  std::unique_ptr<RowMatcher> makeMatcher(const DescriptorLayout& layout) const;

  std::vector<std::unique_ptr<RowMatcher>> matchers_;  ///< one per session of the map, in map order
  std::unique_ptr<RowMatcher> short_matcher_;  ///< the own session's, with the short map's window (null: none)
  int short_session_ = -1;  ///< the session short_matcher_ answered for in the last match (-1: none)
  bool searching_ = true;   ///< setSearching's last value, for a matcher made later
  FrameDescriptor last_query_;
  FrameDescriptor last_shifted_;  ///< the last query's shifted views (left, right), empty without
  /// One session's candidate column and its distance.
  struct Pick
  {
    float distance;
    uint32_t session;
    size_t column;
  };
  /// A short map's candidates before the map holds enough evidence for any (the frames of a revisit's start on a
  /// route shorter than the exclusion window): its best paths of any length, counted as no candidate.
  void earlyPicks(std::vector<Pick>& picks, size_t wanted, size_t window);
  /// The frames of evidence an early place needs: any.
  static constexpr int kEarlyTerms = 1;
  std::vector<size_t> taken_;  ///< scratch: one session's best distinct columns
  std::vector<Pick> picks_;    ///< scratch: every session's, then the best of them
};

}  // namespace openable
