#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "openable/config.h"
#include "openable/place_database.h"
#include "openable/sequence_matcher.h"

namespace openable
{
/// One matched reference frame.
struct Candidate
{
  uint64_t id = 0;               ///< global id of the reference frame
  size_t position = 0;           ///< its position in the database (0 = oldest stored)
  float distance = 1.0f;         ///< normalised sequence distance in [0, 1], 0 = identical
  int8_t direction = 1;          ///< +1 same direction, -1 reverse (bidirectional matching)
  int16_t shift = 0;             ///< circular shift of sub-panoramas that matched best (panoramic)
  uint16_t sequence_length = 0;  ///< terms in the sequence (L, or fewer at the start of a chain)
};

/// The outcome of one frame.
struct Detection
{
  uint64_t query_id = 0;
  bool has_candidates = false;  ///< false while nothing can be compared yet (start, exclusion window)
  bool excluded = false;        ///< no candidates although frames are stored: all inside the exclusion
  size_t candidates = 0;        ///< reference frames compared with a sequence long enough to be a candidate
  Candidate best;
  std::vector<Candidate> top;  ///< up to top_k distinct places, best first
  float uniqueness = 0.0f;     ///< 1 - best / second best (second best outside uniqueness_window); 1 without rival
  bool accepted = false;       ///< distance <= threshold (if set) and uniqueness >= min_uniqueness (if set);
                               ///< false when neither gate is set
};

/// Adds frames, matches them and decides. Two modes:
/// - loop closure (first constructor): each frame is matched against the stream's own past, except the
///   last `exclusion_window` frames and those stamped less than `exclusion_seconds` before it, then stored
///   (bounded by max_history). Only full sequences of L frames are candidates here: the partial chains at
///   the start of a stream compare a few frames only and were the main source of false loops (measured,
///   doc/results.md); min_sequence_length applies to localisation, where every query has a true match;
/// - localisation (second constructor): each frame is matched against a fixed reference map, nothing is stored.
///
/// The normalised distance is the mean per-frame distance of the sequence divided by the largest possible
/// frame distance (all bits different, or unit vectors opposite): it is causal, comparable between frames
/// and sessions, and lies in [0, 1]. The offline tool can also render the paper's global Eq. 5.
class LoopDetector
{
public:
  explicit LoopDetector(const Config& config);
  LoopDetector(const Config& config, PlaceDatabase reference_map);

  bool localisationMode() const
  {
    return localisation_;
  }
  const Config& config() const
  {
    return config_;
  }
  const PlaceDatabase& database() const
  {
    return database_;
  }
  const SequenceMatcher& matcher() const
  {
    return matcher_;
  }

  /// Matches a frame, then (loop-closure mode) stores it. info.id is assigned by the detector.
  Detection process(const FrameDescriptor& descriptor, FrameInfo info = FrameInfo());

  /// The last frame's normalised distance to every stored reference frame, by position; NaN where no
  /// comparison was made (exclusion window, the frame itself).
  void lastRow(std::vector<float>& out) const;

  /// Changes what can change without touching the descriptors: threshold, sequence_length (restarts
  /// sequences), min_sequence_length, exclusion_window, top_k, min_uniqueness, uniqueness_window, bidirectional,
  /// color_map. Throws Error when the new config is invalid or changes a descriptor key.
  void updateMatching(const Config& config);
  /// Forgets the stream (loop-closure mode: the whole history; localisation mode: the query sequences).
  void reset();

private:
  Candidate candidateAt(size_t column) const;
  size_t candidateColumns(double stamp) const;
  int minTerms() const;

  Config config_;
  bool localisation_;
  PlaceDatabase database_;
  SequenceMatcher matcher_;
  FrameMetric metric_;
  FrameDescriptor last_query_;
  uint64_t next_query_id_ = 0;
};

}  // namespace openable
