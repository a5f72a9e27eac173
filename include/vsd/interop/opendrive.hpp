#pragma once
// OpenDRIVE 1.6 for the roads of generated scenarios, and back.
//
// Export: one <road> whose reference line is the road centre vsd-sumo gives
// SUMO — the straight lead-in, the lane points of the scenario region (cubic +
// centre noise), the straight lead-out — written as one <line> geometry per
// segment. SUMO's lanes are straight between the lane points, so lines carry
// exactly the simulated lanes (a smooth paramPoly3 through the noisy points
// would bend between them and move lane centres by centimetres).
//   Lanes: vsd-sumo lane 0 (rightmost) is OpenDRIVE lane -N, lane N-1 is -1; all
//   are `driving` lanes of the realised width; a constant <laneOffset> of N·w/2
//   centres them on the reference line (SUMO's spreadType="center").
//   Coordinates: the scenario frame (m); headings in rad.
//
// Import (readOpenDrive) accepts that subset plus what simple hand-written files
// use: <arc> geometries, <roadMark>s, <link>, <userData>, a road <type> with a
// speed. Anything else is refused with one line naming the element and its line.

#include <filesystem>
#include <optional>
#include <string>

#include "vsd/road/road_geometry.hpp"

namespace vsd::interop {

/// OpenDRIVE lane id of vsd-sumo lane `lane` (0 = rightmost) on a road with `lanes` lanes: -(lanes - lane).
int openDriveLaneId(int lane, int lanes);
/// vsd-sumo lane of an OpenDRIVE right-hand lane id (-1 .. -lanes); nullopt outside that range.
std::optional<int> laneFromOpenDrive(int lane_id, int lanes);

/// The road as OpenDRIVE 1.6 text. `name` goes into the header. Throws ConfigError
/// for a road with fewer than 2 points or a zero-length segment.
std::string openDriveText(const road::RoadGeometry& road, const std::string& name);
/// Same, written atomically to `file`.
void writeOpenDrive(const road::RoadGeometry& road, const std::string& name, const std::filesystem::path& file);

/// A road read from OpenDRIVE: the reference line as a polyline (arcs sampled
/// every <= 0.5 m), lanes, width, speed limit (default: the scenario default when the
/// file has none). The whole road is the region (regionBegin = 0, regionEnd = centre.size()).
struct OpenDriveRoad {
  road::RoadGeometry geometry;
  std::string id;  ///< the road's id attribute
};
/// Throws ConfigError ("file:line: ...") for malformed files and anything outside
/// the supported subset (several roads, left lanes, varying widths, spirals, ...).
OpenDriveRoad readOpenDrive(const std::filesystem::path& file);

/// Position on a road in reference-line coordinates (OpenDRIVE s/t).
struct RoadCoordinate {
  double s = 0.0;  ///< m along the reference line
  double t = 0.0;  ///< m, lateral, > 0 left of the reference line
};
/// The reference-line coordinate of a point (its perpendicular foot on the centre polyline).
RoadCoordinate toRoadCoordinate(const road::RoadGeometry& road, const Vec2& point);
/// The point at (s, t): the reference point at s moved t along the left normal of
/// the geometry holding s (OpenDRIVE's definition for line geometries).
Vec2 fromRoadCoordinate(const road::RoadGeometry& road, const RoadCoordinate& coordinate);

}  // namespace vsd::interop
