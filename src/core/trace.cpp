#include "vsd/core/trace.hpp"

#include <algorithm>
#include <cmath>

namespace vsd {

void fillAccelerationFromSpeed(VehicleTrack& track, double step) {
  auto& states = track.states;
  for (std::size_t k = 1; k < states.size(); ++k) {
    states[k].accel = (states[k].speed - states[k - 1].speed) / step;
  }
  if (states.size() > 1) states[0].accel = states[1].accel;
}

VehicleTrack trackFromPositions(const Polyline& positions, double step, double initial_speed, double initial_heading) {
  const std::size_t n = positions.size();
  VehicleTrack track;
  track.states.resize(n);
  track.valid.assign(n, 1);
  if (n == 0) return track;
  // u[j]: speed at t = 0 (j = 0) and at the midpoint of step j (j >= 1).
  std::vector<double> u(n, initial_speed);
  for (std::size_t j = 1; j < n; ++j) u[j] = (positions[j] - positions[j - 1]).norm() / step;
  for (std::size_t k = 0; k < n; ++k) {
    auto& state = track.states[k];
    state.x = positions[k].x();
    state.y = positions[k].y();
    if (k == 0) {
      state.speed = initial_speed;
      state.heading = initial_heading;
      continue;
    }
    state.accel = (u[k] - u[k - 1]) / (k == 1 ? 0.5 * step : step);
    state.speed = k + 1 < n ? 0.5 * (u[k] + u[k + 1]) : std::max(0.0, u[k] + 0.5 * step * state.accel);
    const Vec2 chord = positions[std::min(k + 1, n - 1)] - positions[k - 1];
    state.heading = chord.norm() > 1e-9 ? std::atan2(chord.y(), chord.x()) : track.states[k - 1].heading;
  }
  track.states[0].accel = n > 1 ? track.states[1].accel : 0.0;
  return track;
}

}  // namespace vsd
