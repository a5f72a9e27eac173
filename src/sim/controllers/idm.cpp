// `idm`: the Intelligent Driver Model (Treiber et al. 2000) with pure-pursuit lane keeping;
// max_accel is IDM's a, comfort_decel its b, exponent its delta, set_speed its v0. The lead
// is SUMO's leader unless `leader_from_objects: 1` (LeaderChoice).

#include <algorithm>
#include <cmath>
#include <limits>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

class IdmController final : public EgoController {
 public:
  IdmController() {
    following_.timeGap = 1.5;
    following_.maxAccel = 1.5;
  }

  void init(const ControllerParams& params) override {
    following_.read(params);
    comfortDecel_ = params.get("comfort_decel", comfortDecel_, 0.1, 20.0);
    exponent_ = params.get("exponent", exponent_, 1.0, 10.0);
    lateral_.init(params);
    leader_.init(params);
    params.rejectUnknown("idm");
  }

  void reset() override { following_.reset(); }

  bool observesObjects() const override { return leader_.fromObjects(); }
  bool followsSetSpeed() const override { return true; }

  Command step(const Observation& observation, double /*dt*/) override {
    const double speed = observation.ego.speed;
    const double set_speed = following_.setSpeed(observation);
    // A set speed of 0 (a commanded stop): IDM's free-road term grows without bound while
    // moving (full braking, clamped) and is 1 at standstill (stays there), where 0/0 would be NaN.
    const double free_term = set_speed > 0.0   ? std::pow(speed / set_speed, exponent_)
                             : speed > 0.0     ? std::numeric_limits<double>::infinity()
                                               : 1.0;
    double interaction = 0.0;
    if (const auto lead = leader_.leader(observation)) {
      const auto& leader = *lead;
      const double approach = speed - leader.speed;
      const double dynamic_gap = speed * approach / (2.0 * std::sqrt(following_.maxAccel * comfortDecel_));
      const double desired_gap = following_.standstillGap + std::max(0.0, speed * following_.timeGap + dynamic_gap);
      const double gap = std::max(leader.gap, 0.1);
      interaction = (desired_gap / gap) * (desired_gap / gap);
    }
    return {following_.clamp(following_.maxAccel * (1.0 - free_term - interaction)), lateral_.curvature(observation)};
  }

 private:
  FollowingParameters following_;
  double comfortDecel_ = 2.0;  ///< m/s^2
  double exponent_ = 4.0;
  PurePursuitLateral lateral_;
  LeaderChoice leader_;
};

}  // namespace

void registerIdm(ControllerRegistry& registry) {
  registry.add("idm", "Intelligent Driver Model + pure-pursuit lane keeping",
               [] { return std::make_unique<IdmController>(); });
}

}  // namespace vsd::sim
