#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "openable/map/place_database.h"

namespace openable
{
/// What MapMatcher asks of the matcher of one session: for each query frame, a row of normalised sequence
/// distances to the session's places, kept online. Two implementations: SequenceMatcher (sequences at the
/// first pass's pace, the paper's diagonal sums) and PaceMatcher (sequences at any pace in a range).
class RowMatcher
{
public:
  virtual ~RowMatcher() = default;

  /// Adds the next query frame and computes its row against reference positions [0, candidates).
  /// The reference may have grown or lost its oldest frames since the last call.
  virtual void match(const uint64_t* query, const PlaceDatabase& reference, size_t candidates) = 0;
  /// The same for a query also described shifted sideways (Config::lateral_shift): `shifted` holds `views`
  /// descriptors of the reference's layout, one after another, and a place's frame distance is the smallest of the
  /// query's and theirs. A matcher that does not compare shifted views (SequenceMatcher: its sums drop each frame's
  /// distance again L frames later, from the stored centre) matches the centre alone.
  virtual void matchShifted(const uint64_t* query, const uint64_t* shifted, size_t views,
                            const PlaceDatabase& reference, size_t candidates)
  {
    (void)shifted;
    (void)views;
    match(query, reference, candidates);
  }
  /// The current row covers reference ids [firstId(), firstId() + columns()).
  virtual uint64_t firstId() const = 0;
  virtual size_t columns() const = 0;
  /// Normalised distance of the sequence ending in `column`: 0 = identical, 1 = every bit different; NaN when
  /// the column holds fewer than `min_terms` frames of evidence. `direction` (optional): +1 same, -1 reverse.
  virtual float normalized(size_t column, int* direction = nullptr, int min_terms = 1) const = 0;
  /// Places of the reference per query frame along the sequence ending in `column`.
  virtual float pace(size_t column) const
  {
    (void)column;
    return 1.0f;
  }
  /// The column where the revisit whose best sequence ends in `column` most likely is now: `column` itself, unless
  /// the matcher can place the end of a sequence between the paces it follows (PaceMatcher).
  virtual size_t refinedColumn(size_t column) const
  {
    return column;
  }
  /// The standard deviation of the last query's frame distances over the row's columns (normalised as
  /// normalized() is), or NaN where the matcher does not keep it (SequenceMatcher): how far apart places
  /// that are not the query usually are, the unit of Detection::relief.
  virtual float rowSpread() const
  {
    return std::nanf("");
  }
  /// Frames of evidence behind the column's sequence in `direction` (at most the sequence length).
  virtual uint16_t terms(size_t column, int direction) const = 0;
  /// The best distinct places of the row: repeatedly the column with the smallest normalized() (the lowest
  /// on ties) more than `window` columns from every column already taken, until `count` are taken or none is
  /// left. Returns the number of columns with a distance.
  virtual size_t smallestDistinct(size_t count, size_t window, int min_terms, std::vector<size_t>& columns) const = 0;

  /// Restarts every sequence (the history of query frames is kept).
  virtual void setSequenceLength(int sequence_length) = 0;
  virtual void setBidirectional(bool bidirectional) = 0;
  /// Whether the stream is looking for a loop (no loop closure published at its last stored frame): from the next
  /// frame, PaceMatcher judges each place by its paths near the first pass's pace first (PaceOptions::prior).
  virtual void setSearching(bool searching)
  {
    (void)searching;
  }
  /// Forgets every query frame and every sequence.
  virtual void reset() = 0;
};

}  // namespace openable
