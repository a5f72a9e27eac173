#pragma once
// Scripted (non-Ego) vehicles of generated scenarios, such as the paper's Co.
//
// The paper: "Ego and Co use a lane keeping controller; the resulting vehicle
// orientations are varied randomly with U(-2.9 deg, 2.9 deg)". A scripted vehicle
// therefore drives like the Ego's kinematic model, with
//   longitudinal: its scripted speed (profile + speed noise) at every instant, exactly;
//   lateral:      pure-pursuit lane keeping on its lane's centre line (the Ego's default
//                 lateral controller), plus its per-step heading disturbance.
// Nothing it does depends on other vehicles, so its whole path is a pure function of the
// concrete scenario and the road geometry: the simulation places it with moveToXY along
// this path, and planned scenes (built before simulating) use the very same path.

#include <vector>

#include "vsd/core/trace.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::sim {

/// States at t_0 .. t_steps (scenario frame, centre of the vehicle; `step` s apart).
/// t_0: on its lane's centre line at its x, heading along the lane, its initial speed.
/// Throws ConfigError if the vehicle starts outside its road.
std::vector<VehicleState> scriptedPath(const scenario::ConcreteVehicle& vehicle, const road::RoadGeometry& road,
                                       double step, int steps);

}  // namespace vsd::sim
