#pragma once

#include <cstdint>
#include <vector>

#include "openable/map/session_map.h"

/// The frame numbers openable_offline writes (matrix columns, the query and match of loop_closures.csv):
/// the files of this run, counted as decoded. A continued map's sessions come first, by their ids, and the
/// stream's files follow from the map's next id, so the outputs read as one stream (the map, then the run)
/// and evaluate like one.
class FrameNumbers
{
public:
  /// `first_id`: the id the stream's first stored frame gets (the continued map's nextId(), else 0).
  explicit FrameNumbers(uint64_t first_id) : first_id_(first_id) {}

  /// The frame stored next (in the stream's session, or the reference map) came from `file`.
  void stored(long file)
  {
    file_of_.push_back(file);
  }
  /// The number of a stream file (the query column of the outputs).
  long query(long file) const
  {
    return static_cast<long>(first_id_) + file;
  }
  /// The number of the stored frame at `position` of `session`. `own` is the session whose frames came
  /// from this run's files (the stream's, or the reference traversal's); other sessions keep their ids.
  long stored(const openable::SessionMap& map, uint32_t session, size_t position, uint32_t own) const
  {
    const uint64_t id = map.frames(session).firstId() + position;
    if (session != own)
      return static_cast<long>(id);
    return query(file_of_.at(static_cast<size_t>(id - first_id_)));
  }
  /// A row of distances by map order (MapMatcher::lastRow) into a row by frame number, `width` wide.
  void toNumbers(const openable::SessionMap& map, uint32_t own, const std::vector<float>& by_map, size_t width,
                 std::vector<float>& out) const
  {
    out.assign(width, std::nanf(""));
    size_t entry = 0;
    for (uint32_t s = 0; s < map.sessionCount(); ++s)
      for (size_t p = 0; p < map.frames(s).size() && entry < by_map.size(); ++p, ++entry)
      {
        const long column = stored(map, s, p, own);
        if (column >= 0 && static_cast<size_t>(column) < width)
          out[static_cast<size_t>(column)] = by_map[entry];
      }
  }

private:
  uint64_t first_id_;
  std::vector<long> file_of_;  ///< (id - first_id_) -> file
};
