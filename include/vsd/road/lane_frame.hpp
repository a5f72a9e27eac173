#pragma once
// Positions in a road's lane frame: s along the road's centre line, d across it (m, > 0
// left). Road users that move across lanes (lane changes, lateral offsets, pedestrians
// crossing) move in this frame exactly: their d follows the commanded lateral profile, no
// controller lag smears it.
//
// The frame matches the lane centre lines the generator builds (RoadGeometry::laneCentre,
// the lines SUMO gets): point(s, d) for a fixed d traces the centre line offset by d with
// the mitre rule of offsetPolyline, so d = laneOffset(lane) is exactly that lane's centre
// line, and a point moves continuously in both s and d (no jump at the polyline's vertices).
// Within a segment of the centre line, point(s, d) interpolates linearly between the
// offset vertices at the same fraction of the segment.

#include <vector>

#include "vsd/core/geometry.hpp"

namespace vsd::road {

class LaneFrame {
 public:
  LaneFrame() = default;
  /// `centre`: at least 2 points.
  explicit LaneFrame(const Polyline& centre);

  /// The point at (s, d); beyond either end the end segment is extended.
  Vec2 point(double s, double d) const;
  /// Velocity (m/s) of a point moving along the road at `speed_along` m/s (measured on its
  /// own offset line) and across it at `lateral_rate` m/s (dd/dt), at (s, d).
  Vec2 velocity(double s, double d, double speed_along, double lateral_rate) const;
  /// ds/dt of a point moving `speed_along` m/s along its offset line at (s, d).
  double sRate(double s, double d, double speed_along) const;
  /// Direction (rad) of the offset line at (s, d).
  double heading(double s, double d) const;
  /// s and d of a point: its projection onto the centre line (ends extended).
  std::pair<double, double> coordinates(const Vec2& point) const;
  double length() const { return centre_.length(); }

 private:
  struct Segment {
    std::size_t index = 0;
    double fraction = 0.0;  ///< may lie outside [0, 1] beyond the ends
  };
  Segment segmentAt(double s) const;
  /// d(point)/ds within the segment (not normalised).
  Vec2 alongDerivative(std::size_t segment, double d) const;

  MeasuredPolyline centre_;
  std::vector<double> cumulative_;  ///< m, arc length at each vertex
  std::vector<Vec2> mitre_;  ///< per vertex: the offset of a unit left offset (offsetPolyline(centre, 1) - centre)
};

}  // namespace vsd::road
