#pragma once
// 2-D geometry in SI units (m, rad). Headings are mathematical: 0 rad points
// along +x, counter-clockwise positive, wrapped to (-pi, pi].
//
// SUMO's convention (degrees, 0 = north, clockwise) appears only in the
// conversion helpers at the bottom, which the `sim` boundary uses.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace vsd {

using Vec2 = Eigen::Vector2d;
using Polyline = std::vector<Vec2>;

constexpr double kPi = 3.14159265358979323846;

/// Wraps an angle to (-pi, pi].
double wrapAngle(double angle_rad);
/// Unit vector of a heading.
Vec2 headingVector(double heading_rad);
/// Heading of a direction vector (atan2).
double headingOf(const Vec2& direction);

/// Where a point lies relative to a polyline.
struct PolylineProjection {
  double arcLength = 0.0;      ///< m along the polyline to the foot point (clamped to [0, length])
  double lateralOffset = 0.0;  ///< m, signed: > 0 left of the direction of travel
  double heading = 0.0;        ///< rad, direction of the segment holding the foot point
  std::size_t segment = 0;     ///< index of that segment (points segment, segment + 1)
  Vec2 foot = Vec2::Zero();    ///< closest point on the polyline
};

/// A polyline with cumulative arc lengths, for repeated queries (at least 2 points).
class MeasuredPolyline {
 public:
  MeasuredPolyline() = default;
  explicit MeasuredPolyline(Polyline points);

  const Polyline& points() const { return points_; }
  double length() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }
  bool empty() const { return points_.size() < 2; }

  /// Closest point on the polyline: the first segment (lowest index) at the least distance.
  /// Blocks of segments whose bounding box is provably farther than the nearest segment found
  /// so far are skipped; the result is bit for bit that of a scan over every segment.
  PolylineProjection project(const Vec2& point) const;
  /// Point at arc length s; beyond either end the end segment is extended linearly.
  Vec2 pointAt(double arc_length) const;
  /// Direction at arc length s (of the segment holding it, end segments beyond the ends).
  double headingAt(double arc_length) const;

 private:
  /// Axis-aligned bounding box of the segments [first, first + kBlock) (their end points).
  struct Block {
    double minX, minY, maxX, maxY;
  };
  static constexpr std::size_t kBlock = 8;

  std::size_t segmentAt(double arc_length) const;
  /// project() over every segment in order.
  PolylineProjection projectScan(const Vec2& point) const;
  /// project() with blocks skipped by their bounding boxes.
  PolylineProjection projectIndexed(const Vec2& point) const;
  /// The projection on segment `segment` at `fraction` along it, `distance_sq` from `point`.
  PolylineProjection projectionOn(const Vec2& point, std::size_t segment, double fraction, double distance_sq,
                                  std::size_t heading_segment) const;

  Polyline points_;
  std::vector<double> cumulative_;
  std::vector<Block> blocks_;  ///< empty: project() scans every segment
  double scale_ = 0.0;         ///< largest |coordinate| of the points
};

/// Sum of segment lengths.
double polylineLength(const Polyline& points);

/// The polyline moved sideways by `left_offset` m (negative: right). Each vertex moves
/// along the bisector of its adjacent segment normals, scaled so that both segments stay
/// exactly `left_offset` away (mitre), with the scale capped to avoid spikes at sharp turns.
Polyline offsetPolyline(const Polyline& points, double left_offset);

/// A lane as a road network describes it: centre line and width.
struct LaneGeometry {
  std::string id;
  Polyline centre;     ///< m
  double width = 0.0;  ///< m
};

/// First point on the polyline whose x equals `x` (linear interpolation), if any.
std::optional<Vec2> pointAtX(const Polyline& points, double x);

/// The part of the polyline with x in [x_min, x_max], with interpolated end points.
/// Meant for polylines that advance in x (roads of the scenario frame).
Polyline clipToXRange(const Polyline& points, double x_min, double x_max);

/// A vehicle's footprint: a rectangle around its centre, `length` along its heading.
struct Footprint {
  Vec2 centre = Vec2::Zero();  ///< m
  double heading = 0.0;        ///< rad
  double length = 0.0;         ///< m, > 0
  double width = 0.0;          ///< m, > 0
};

/// Signed clearance between two footprints (m): the shortest distance between the
/// rectangles when they are apart, 0 when they touch, and minus the penetration
/// depth (the shortest translation that separates them) when they overlap. Two cars
/// side by side in neighbouring lanes are ~1.7 m apart, not overlapping.
double footprintGap(const Footprint& a, const Footprint& b);

// --- SUMO conventions (only for the sim boundary) --------------------------------------

/// SUMO angle (deg, 0 = north, clockwise) -> heading (rad, 0 = +x, counter-clockwise).
double headingFromSumoAngle(double sumo_angle_deg);
/// Heading (rad) -> SUMO angle in [0, 360) deg.
double sumoAngleFromHeading(double heading_rad);

}  // namespace vsd
