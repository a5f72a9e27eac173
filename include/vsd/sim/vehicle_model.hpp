#pragma once
// Kinematic vehicle model of the Ego: state (x, y, heading, speed) driven by a
// Command (longitudinal acceleration, path curvature).
//
// Over one step dt:
//   a  = clamp(command.accel, -max_decel, max_accel)
//   v' = max(0, v + a dt)                       (a vehicle does not reverse)
//   s  = distance travelled (trapezoid; exact stopping distance if it stops)
//   kappa = clamp(command.curvature, +-max_curvature)
//   position moves s along the heading at mid-step, heading' = heading + kappa s + noise
// where `noise` is the scenario's heading disturbance for this step (the paper's
// U(-2.9 deg, 2.9 deg) orientation variation), applied only if the vehicle moves in the step.

#include "vsd/core/trace.hpp"
#include "vsd/sim/controller.hpp"

namespace vsd::sim {

struct VehicleLimits {
  double maxAccel = 4.0;       ///< m/s^2
  double maxDecel = 9.0;       ///< m/s^2 (tyre limit)
  double maxCurvature = 0.25;  ///< 1/m (~4 m turning radius)
};

/// Advances `state` by `dt` seconds. `accel` of the result is (v' - v) / dt.
VehicleState advanceKinematic(const VehicleState& state, const Command& command, double dt, double heading_noise,
                              const VehicleLimits& limits = {});

}  // namespace vsd::sim
