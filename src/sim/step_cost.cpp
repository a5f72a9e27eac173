#include <fmt/format.h>

#include <chrono>
#include <thread>

#include "vsd/sim/controller.hpp"

namespace vsd::sim {

namespace {

/// The wrapped controller's commands, each after `cost` more wall time.
class SteppingCostController final : public EgoController {
 public:
  SteppingCostController(std::unique_ptr<EgoController> inner, std::chrono::microseconds cost)
      : inner_(std::move(inner)), cost_(cost) {}
  void init(const ControllerParams& params) override { inner_->init(params); }
  void reset() override { inner_->reset(); }
  bool observesObjects() const override { return inner_->observesObjects(); }
  Command step(const Observation& observation, double dt) override {
    std::this_thread::sleep_for(cost_);
    return inner_->step(observation, dt);
  }

 private:
  std::unique_ptr<EgoController> inner_;
  std::chrono::microseconds cost_;
};

}  // namespace

std::unique_ptr<EgoController> withStepCost(std::unique_ptr<EgoController> controller, double seconds) {
  if (!(seconds > 0.0)) return controller;
  return std::make_unique<SteppingCostController>(
      std::move(controller), std::chrono::microseconds(static_cast<std::int64_t>(seconds * 1e6 + 0.5)));
}

}  // namespace vsd::sim
