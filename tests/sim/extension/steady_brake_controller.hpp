#pragma once
// An Ego controller written by a test, as a newcomer would write one (docs/design.md
// "Adding a surrogate, a decoder, a controller, a map importer").
#include "vsd/sim/controller.hpp"

namespace vsd::test {

/// Registers "steady_brake": brakes at the parameter `decel` (m/s^2, 0 .. 9) from the start
/// and steers straight ahead.
void registerSteadyBrake(sim::ControllerRegistry& registry);

}  // namespace vsd::test
