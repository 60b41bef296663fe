#pragma once

#include <cstdint>
#include <string>

namespace openable
{
/// Where a frame was on the Earth (WGS84 degrees, metres), e.g. from a GNSS fix.
struct GeoPosition
{
  double latitude = 0.0;
  double longitude = 0.0;
  double altitude = 0.0;
  double stamp = 0.0;  ///< seconds; the time of the fix (may differ a little from the frame's)
};

/// The header of the geographic positions CSV: `frame,stamp,latitude,longitude,altitude`.
std::string geoPositionsCsvHeader();
/// One line of that CSV (with its newline), with every measured digit kept; loadGeoPositions() reads it.
std::string geoPositionsCsvLine(uint64_t frame, const GeoPosition& position);

}  // namespace openable
