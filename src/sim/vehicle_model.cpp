#include "vsd/sim/vehicle_model.hpp"

#include <algorithm>
#include <cmath>

namespace vsd::sim {

VehicleState advanceKinematic(const VehicleState& state, const Command& command, double dt, double heading_noise,
                              const VehicleLimits& limits) {
  const double accel = std::clamp(command.accel, -limits.maxDecel, limits.maxAccel);
  double next_speed = state.speed + accel * dt;
  double distance = 0.0;
  if (next_speed >= 0.0) {
    distance = 0.5 * (state.speed + next_speed) * dt;
  } else {
    // Stops within the step: distance to standstill is v^2 / (2 |a|).
    distance = accel < 0.0 ? state.speed * state.speed / (-2.0 * accel) : 0.0;
    next_speed = 0.0;
  }
  const double curvature = std::clamp(command.curvature, -limits.maxCurvature, limits.maxCurvature);
  const double turn = curvature * distance;
  const double mid_heading = state.heading + 0.5 * turn;

  VehicleState next;
  next.x = state.x + distance * std::cos(mid_heading);
  next.y = state.y + distance * std::sin(mid_heading);
  // The disturbance models the wobble of a moving vehicle: a standing one does not turn.
  next.heading = wrapAngle(state.heading + turn + (distance > 0.0 ? heading_noise : 0.0));
  next.speed = next_speed;
  next.accel = (next_speed - state.speed) / dt;
  return next;
}

}  // namespace vsd::sim
