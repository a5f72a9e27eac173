#pragma once
// What a run recorded, in the scenario frame. Shared by `sim` (which records
// traces), `metrics` (which evaluates simulated and predicted traces alike) and
// `vector` (which describes scenes), so it lives in `core`.

#include <cstdint>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/road_user.hpp"

namespace vsd {

/// Bounds of every time base (scenario, export flags, dataset attributes, model
/// description), checked wherever one enters: SUMO counts milliseconds, and at most
/// kMaxWindowSteps steps per horizon (and per history) keep every per-sample array,
/// trace and tensor bounded.
inline constexpr double kMinStep = 0.001;     ///< s
inline constexpr double kMaxStep = 10.0;      ///< s
inline constexpr int kMaxWindowSteps = 1000;  ///< steps

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
  double length = 0.0;  ///< m, bounding box; no default: from the scenario, the map or the dataset
  double width = 0.0;   ///< m
  RoadUserType type = RoadUserType::Car;  ///< what kind of road user (core/road_user.hpp)
  std::vector<VehicleState> states;
  std::vector<std::uint8_t> valid;  ///< 1 where the vehicle existed at t_k (same size as states)

  bool validAt(std::size_t k) const { return k < valid.size() && valid[k] != 0; }
};

/// All vehicles of one concrete scenario (or one map window). vehicles[0] is the Ego.
struct Trace {
  double step = 0.0;  ///< s between recorded instants; no default: from the scenario or the dataset
  std::vector<VehicleTrack> vehicles;

  std::size_t instants() const { return vehicles.empty() ? 0 : vehicles.front().states.size(); }
  const VehicleTrack& ego() const { return vehicles.front(); }
};

/// Fills `accel` from consecutive speeds: a_k = (v_k - v_{k-1}) / dt for k >= 1,
/// a_0 = a_1. Used for every source (SUMO, kinematic model, predictions) so that
/// accelerations are comparable.
void fillAccelerationFromSpeed(VehicleTrack& track, double step);

/// A track from positions alone (e.g. a predicted trajectory), positions[0] at t = 0
/// where the speed and heading are known (the Ego's initial vector). Speeds come from
/// step lengths: u_j = |p_j - p_{j-1}| / dt is the speed at the step's midpoint
/// (t_j - dt/2) - exact for the simulator's trapezoidal integration and second-order
/// accurate for any smooth motion - so no smoothing window blurs a sudden brake at t = 0:
///   accel at instant j >= 1: (u_j - u_{j-1}) / (t of u_j - t of u_{j-1}), with u_0 = the
///                            initial speed at t = 0 (so accel_1 covers [0, dt/2]);
///   speed at instant k:      (u_k + u_{k+1}) / 2, the last one extrapolated with accel_F;
///   heading at instant k:    direction of p_{k+1} - p_{k-1} (one-sided at the end).
/// On simulated positions, a_min from this track is within a few cm/s^2 of the
/// simulation's (README "Metrics from predicted trajectories").
VehicleTrack trackFromPositions(const Polyline& positions, double step, double initial_speed, double initial_heading);

}  // namespace vsd
