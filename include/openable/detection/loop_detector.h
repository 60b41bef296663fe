#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "openable/config.h"
#include "openable/detection/map_matcher.h"
#include "openable/map/session_map.h"

namespace openable
{
/// What a detector does with a saved map.
enum class MapMode
{
  Localise,  ///< match against the map only; nothing is stored
  Continue,  ///< a new session: match against the map's sessions and the new session's past, store
};

/// Adds frames, matches them (MapMatcher) and, unless localising, stores them. Three uses:
/// - loop closure (first constructor): each frame is matched against the stream's own past, except the
///   last `exclusion_window` frames and those stamped less than `exclusion_seconds` before it, then stored
///   in the map's one session (bounded by max_history);
/// - continue (a saved map, MapMode::Continue): the stream is a new session of the map; each frame is
///   matched against every earlier session and the new session's own past, then stored there;
/// - localisation (a saved map, MapMode::Localise): each frame is matched against the map, nothing is stored.
///
/// The normalised distance is the mean per-frame distance of the sequence divided by the largest possible
/// frame distance (all bits different, or unit vectors opposite): it is causal, comparable between frames
/// and sessions, and lies in [0, 1]. The offline tool can also render the paper's global Eq. 5.
class LoopDetector
{
public:
  explicit LoopDetector(const Config& config, SessionInfo session = SessionInfo{"session 0", "", 0.0});
  /// Localisation against one stored traversal.
  LoopDetector(const Config& config, PlaceDatabase reference_map);
  /// A saved map, localised against or continued as the new session `session`. Throws Error when the map's
  /// layout differs from the configuration's, or the new session's name is already in the map.
  LoopDetector(const Config& config, SessionMap map, MapMode mode,
               SessionInfo session = SessionInfo{"session 0", "", 0.0});
  /// The same, from a configuration validated already (OnlineDetector's): not validated again.
  explicit LoopDetector(const ValidConfig& config, SessionInfo session = SessionInfo{"session 0", "", 0.0});
  LoopDetector(const ValidConfig& config, PlaceDatabase reference_map);
  LoopDetector(const ValidConfig& config, SessionMap map, MapMode mode,
               SessionInfo session = SessionInfo{"session 0", "", 0.0});

  bool localisationMode() const
  {
    return own_session_ < 0;
  }
  const Config& config() const
  {
    return config_;
  }
  /// Every session: the loaded ones and the one this detector stores its frames in.
  const SessionMap& map() const
  {
    return map_;
  }
  /// The session this detector stores frames in (-1 when localising).
  int ownSession() const
  {
    return own_session_;
  }
  int sequenceLength() const
  {
    return matcher_.sequenceLength();
  }

  /// Matches a frame, then (unless localising) stores it. info.id and info.session are set by the detector.
  /// `shifted`: the frame's shifted views (MapMatcher::match), matched but never stored.
  Detection process(const FrameDescriptor& descriptor, FrameInfo info = FrameInfo(),
                    const FrameDescriptor& shifted = FrameDescriptor());

  /// The last frame's normalised distance to every stored frame, sessions one after another in map order,
  /// by position; NaN where no comparison was made (exclusion window, the frame itself).
  void lastRow(std::vector<float>& out) const;

  /// Changes what can change without touching the descriptors: threshold, sequence_length (restarts
  /// sequences), min_sequence_length, exclusion_window, top_k, min_uniqueness, uniqueness_window, bidirectional,
  /// color_map. Throws Error when the new config is invalid or changes a descriptor key.
  void updateMatching(const Config& config);
  /// Forgets the stream: its query sequences and, unless localising, the frames it stored (loaded
  /// sessions stay).
  void reset();
  /// Whether the stream is looking for a loop: no loop closure was published at the last frame (the decision's
  /// outcome, MapMatcher::setSearching).
  void setSearching(bool searching)
  {
    matcher_.setSearching(searching);
  }

private:
  Config config_;
  SessionMap map_;
  int own_session_;
  MapMatcher matcher_;
  uint64_t next_query_id_ = 0;
};

}  // namespace openable
