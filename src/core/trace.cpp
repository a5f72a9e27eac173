#include "vsd/core/trace.hpp"

namespace vsd {

void fillAccelerationFromSpeed(VehicleTrack& track, double step) {
  auto& states = track.states;
  for (std::size_t k = 1; k < states.size(); ++k) {
    states[k].accel = (states[k].speed - states[k - 1].speed) / step;
  }
  if (states.size() > 1) states[0].accel = states[1].accel;
}

}  // namespace vsd
