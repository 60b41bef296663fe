#pragma once

#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "openable/geo_position.h"
#include "openable/evaluation/loop_list.h"

namespace openable
{
/// Geographic positions by frame from a CSV with the header `frame,stamp,latitude,longitude,altitude`
/// (e.g. converted from GPS or KITTI's OXTS). Throws Error for a missing file, another header, a malformed
/// line (with its number), a latitude outside [-90, 90], a longitude outside [-180, 180] or a frame given
/// twice.
std::map<int, GeoPosition> loadGeoPositions(const std::string& path);

/// One line per frame: `frame,stamp,x,y,z,loop_partner,loop_agrees`. `stamps` may be empty (stamp left
/// empty) or hold one per position. loop_partner is the earlier frame of the first loop this frame closes
/// as the query (empty when none); loop_agrees is 1 when the ground truth has that loop, 0 when not.
/// Throws Error when `stamps` has another size than `positions`.
std::string trajectoryCsv(const std::vector<cv::Vec3d>& positions, const std::vector<double>& stamps,
                          const std::vector<LoopPair>& loops);

/// A KML 2.2 document Google Earth opens: the path as one LineString Placemark through the frames in
/// order, and a Folder with one Placemark per loop (a Point on the query frame and a LineString to the
/// matched frame), styled green when the ground truth agrees and red when not. Loops naming a frame
/// without position are left out and counted in `skipped` (when given). Throws Error for no positions.
std::string trajectoryKml(const std::map<int, GeoPosition>& positions, const std::vector<LoopPair>& loops,
                          const std::string& name, size_t* skipped = nullptr);

/// `text` with &, <, >, " and ' as XML entities.
std::string xmlEscape(const std::string& text);

}  // namespace openable
