#pragma once
// Where another road user is relative to the Ego's lane and the path the Ego sweeps along
// it. One definition serves what the Ego's controller observes (the object list built in
// `sim`) and what metrics score on traces, simulated or predicted (in-path time to
// collision and headway, lateral clearance to side vehicles): both call relateToPath, so
// a cut-in counts as "in path" at the same instant for the controller and for the metric.
//
// The reference line is the centre line of the Ego's lane. The Ego's path is that line
// shifted to the Ego's own lateral offset: a lane-keeping Ego sweeps a corridor of its own
// width along it. Positions are projected onto the reference line - s along it, d across
// it (> 0 left of the direction of travel); beyond either end the end segment is extended.
// A footprint's extents along and across the line follow from its heading relative to
// the line there (a pedestrian crossing the road is wider along s than across it).
//
// Units: m, rad. Scenario frame (or any frame shared by the line and the footprints).

#include <cstdint>

#include "vsd/core/geometry.hpp"

namespace vsd {

struct PathRelation {
  double longitudinalDistance = 0.0;  ///< m, s_object - s_Ego (centre to centre along the line), > 0 ahead
  /// m, bumper to bumper along the line: |s_object - s_Ego| minus the Ego's and the object's
  /// half extents along it; < 0 when their s ranges overlap (side by side).
  double longitudinalGap = 0.0;
  double lateralDistance = 0.0;  ///< m, d_object - d_Ego (centre to centre across the line), > 0 left of the Ego
  /// m, |d_object - d_Ego| minus both half extents across the line; < 0: the object reaches
  /// into the corridor the Ego sweeps along its lane.
  double lateralGap = 0.0;
  double objectOffset = 0.0;  ///< m, d_object: the object's centre from the reference line, > 0 left
  /// The lane of the object's centre relative to the Ego's lane, for lanes of `lane_width`:
  /// 0 = the Ego's lane (|d_object| <= lane_width / 2), +1 = next lane to the left, -1 right, ...
  int relativeLane = 0;
  double relativeHeading = 0.0;  ///< rad, the object's heading minus the line's direction at its foot point
  /// Ahead (longitudinalDistance > 0) and reaching into the Ego's corridor (lateralGap < 0).
  bool inPath = false;
};

/// Projection of a point onto a line whose end segments are extended beyond its ends:
/// arcLength < 0 before the start and > length() after the end (the line has >= 2 points).
PolylineProjection projectExtended(const MeasuredPolyline& line, const Vec2& point);

/// Where `object` is relative to the Ego's lane (centre line `reference_line`, lanes
/// `lane_width` wide, > 0) and the Ego's path along it. A footprint of length and width 0 is a point.
PathRelation relateToPath(const MeasuredPolyline& reference_line, double lane_width, const Footprint& ego,
                          const Footprint& object);

/// relateToPath with the projections (projectExtended) of both centres onto the reference
/// line already at hand: for callers that relate one Ego to several objects, or need a foot
/// point again. The same result, bit for bit.
PathRelation relateFeet(const PolylineProjection& ego_foot, const PolylineProjection& object_foot, double lane_width,
                        const Footprint& ego, const Footprint& object);

}  // namespace vsd
