#pragma once
// Road geometry of one concrete scenario, in its scenario frame (m).

#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/road/lane_frame.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::road {

struct RoadGeometry {
  /// Road centre over the whole edge SUMO gets: straight lead-in, the noisy
  /// lane points of the scenario region, straight lead-out.
  Polyline centre;
  std::size_t regionBegin = 0;  ///< index in `centre` of the first scenario-region point
  std::size_t regionEnd = 0;    ///< one past the last scenario-region point
  int lanes = 1;
  std::vector<double> laneWidths;  ///< m, lane 0 (rightmost) first; no default: from the concrete scenario
  double speedLimit = 50.0; ///< m/s

  /// Centre line of lane `lane` (0 = rightmost) over the whole edge.
  Polyline laneCentre(int lane) const;
  /// Lateral offset (m, left positive) of lane `lane`'s centre from the road centre.
  double laneOffset(int lane) const;
  /// m, lane `lane`'s width.
  double laneWidthOf(int lane) const;
  /// m from the road centre to either outer lane edge.
  double halfWidth() const;
  /// The lane whose span holds `offset` (m from the road centre, left positive); the outer
  /// lanes beyond the edges.
  int laneAt(double offset) const;
  /// Axis-aligned bounds of the road including its width: {min corner, max corner}.
  std::pair<Vec2, Vec2> bounds() const;
  /// m along `centre` from its first point to the scenario region's start (s = 0 there).
  double regionStart() const;
};

/// m: how far apart points of a curve of this curvature (1/m) may lie for the chords between
/// them to stay within `chord_error` m of it (a chord c of radius R lies c^2 / (8 R) from
/// it at most), and at most `longest` m. Arc roads: 1 cm and 10 m.
double chordSpacing(double curvature, double chord_error = 0.01, double longest = 10.0);

/// The x range of the scenario region: x_range for polynomial roads; for arc roads the x
/// of the region's start (0) and end (a pure function of the inputs: arcs have no noise).
std::pair<double, double> regionXRange(const scenario::LogicalScenario& logical, const std::vector<double>& inputs);

/// Polynomial roads: evaluates the centre expression at the lane points x_min + (x_max - x_min) / (points - 1) * i,
/// adds the drawn centre noise and appends straight extensions along the end
/// tangents of the noise-free centre line. Arc roads: points along the circle (or line)
/// from the origin heading +x, spaced at most 10 m and close enough that the polyline
/// stays within 1 cm of the circle, then the straight extensions. Throws ConfigError if
/// the centre expression is not finite at a lane point, or an arc's curvature or length
/// is out of range.
RoadGeometry buildRoadGeometry(const scenario::ConcreteScenario& concrete);

/// Where a vehicle starts: the point on its lane's centre line whose x equals `x`,
/// with the lane's direction there.
struct StartPose {
  Vec2 position;
  double heading = 0.0;  ///< rad
};
/// Throws ConfigError if x lies outside the road.
StartPose startPoseOnLane(const RoadGeometry& road, int lane, double x, const std::string& vehicle_id);

/// Where a road user of a concrete scenario starts: in the scenario frame and in the road's
/// lane frame (s from the centre line's first point, d = its lane's offset + its offset).
struct RoadUserStart {
  Vec2 position;
  double heading = 0.0;  ///< rad: its lane's direction plus its own relative heading
  double s = 0.0;        ///< m
  double d = 0.0;        ///< m, > 0 left
};
/// `from_s`, `from_length`: s and length of the road user `ds` and `gap` count from (the
/// Ego, or an earlier one; ignored for x or s positions). A vehicle placed by x with no
/// offset starts exactly where startPoseOnLane puts it (the paper's Co). Throws ConfigError
/// naming the road user and the sample if it lies outside its road.
RoadUserStart roadUserStart(const RoadGeometry& road, const LaneFrame& frame, const scenario::ConcreteScenario& concrete,
                            const scenario::ConcreteVehicle& vehicle, double from_s, double from_length);

}  // namespace vsd::road
