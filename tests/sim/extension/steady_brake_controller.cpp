// A test-only Ego controller: a constant deceleration, no steering.
#include "steady_brake_controller.hpp"

#include <memory>

namespace vsd::test {

namespace {

class SteadyBrake final : public sim::EgoController {
 public:
  void init(const sim::ControllerParams& params) override {
    decel_ = params.get("decel", decel_, 0.0, 9.0);
    params.rejectUnknown("steady_brake");
  }
  void reset() override {}
  sim::Command step(const sim::Observation& /*observation*/, double /*dt*/) override { return {-decel_, 0.0}; }

 private:
  double decel_ = 1.0;  ///< m/s^2
};

}  // namespace

void registerSteadyBrake(sim::ControllerRegistry& registry) {
  registry.add("steady_brake", "constant deceleration `decel` (m/s^2), no steering (test-only)",
               [] { return std::make_unique<SteadyBrake>(); });
}

}  // namespace vsd::test
