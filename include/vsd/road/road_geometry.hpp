#pragma once
// Road geometry of one concrete scenario, in its scenario frame (m).

#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::road {

struct RoadGeometry {
  /// Road centre over the whole edge SUMO gets: straight lead-in, the noisy
  /// lane points of the scenario region, straight lead-out.
  Polyline centre;
  std::size_t regionBegin = 0;  ///< index in `centre` of the first scenario-region point
  std::size_t regionEnd = 0;    ///< one past the last scenario-region point
  int lanes = 1;
  double laneWidth = 3.5;   ///< m, every lane
  double speedLimit = 50.0; ///< m/s

  /// Centre line of lane `lane` (0 = rightmost) over the whole edge.
  Polyline laneCentre(int lane) const;
  /// Lateral offset (m, left positive) of lane `lane`'s centre from the road centre.
  double laneOffset(int lane) const;
  /// Axis-aligned bounds of the road including its width: {min corner, max corner}.
  std::pair<Vec2, Vec2> bounds() const;
};

/// Evaluates the centre expression at the lane points x_min + (x_max - x_min) / (points - 1) * i,
/// adds the drawn centre noise and appends straight extensions along the end
/// tangents of the noise-free centre line. Throws ConfigError if the centre
/// expression is not finite at a lane point.
RoadGeometry buildRoadGeometry(const scenario::ConcreteScenario& concrete);

/// Where a vehicle starts: the point on its lane's centre line whose x equals `x`,
/// with the lane's direction there.
struct StartPose {
  Vec2 position;
  double heading = 0.0;  ///< rad
};
/// Throws ConfigError if x lies outside the road.
StartPose startPoseOnLane(const RoadGeometry& road, int lane, double x, const std::string& vehicle_id);

}  // namespace vsd::road
