#pragma once
// What a run recorded, in the scenario frame. Shared by `sim` (which records
// traces), `metrics` (which evaluates simulated and predicted traces alike) and
// `vector` (which describes scenes), so it lives in `core`.

#include <cstdint>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"

namespace vsd {

/// State of one vehicle at one instant. Reference point: the centre of the
/// vehicle's bounding box (SUMO's front-bumper position is converted at the
/// `sim` boundary).
struct VehicleState {
  double x = 0.0;        ///< m, scenario frame
  double y = 0.0;        ///< m, scenario frame
  double heading = 0.0;  ///< rad, 0 = +x, counter-clockwise, (-pi, pi]
  double speed = 0.0;    ///< m/s, >= 0
  double accel = 0.0;    ///< m/s^2, longitudinal: (v_k - v_{k-1}) / dt; at k = 0 the first such value

  Vec2 position() const { return {x, y}; }
};

enum class VehicleRole : std::uint8_t { Ego = 0, Other = 1 };

/// One vehicle over the whole recording: states[k] holds t_k = k * step.
struct VehicleTrack {
  std::string id;
  VehicleRole role = VehicleRole::Other;
  double length = 5.0;  ///< m
  double width = 1.8;   ///< m
  std::vector<VehicleState> states;
  std::vector<std::uint8_t> valid;  ///< 1 where the vehicle existed at t_k (same size as states)

  bool validAt(std::size_t k) const { return k < valid.size() && valid[k] != 0; }
};

/// All vehicles of one concrete scenario (or one map window). vehicles[0] is the Ego.
struct Trace {
  double step = 0.2;  ///< s between recorded instants
  std::vector<VehicleTrack> vehicles;

  std::size_t instants() const { return vehicles.empty() ? 0 : vehicles.front().states.size(); }
  const VehicleTrack& ego() const { return vehicles.front(); }
};

/// Fills `accel` from consecutive speeds: a_k = (v_k - v_{k-1}) / dt for k >= 1,
/// a_0 = a_1. Used for every source (SUMO, kinematic model, predictions) so that
/// accelerations are comparable.
void fillAccelerationFromSpeed(VehicleTrack& track, double step);

}  // namespace vsd
