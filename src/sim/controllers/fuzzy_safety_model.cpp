// `fsm`: the Fuzzy Safety Model (Mattas et al. 2020, "Fuzzy Surrogate Safety Metrics for
// real-time assessment of rear-end collision risk", AAP 148:105794), as Mattas et al. 2022
// ("Driver models for the definition of safety requirements of automated vehicles in
// international regulations. Application to motorway driving conditions", AAP 174:106743)
// parameterise it to compare it with UN R157's reference driver, and as the 01 series of
// UN R157 states its formulas (Annex 3). Defaults: the authors' implementation, JRC-FSM
// (github.com/ec-jrc/JRC-FSM, utility/vehicle.py); docs/controllers.md lists each.
//
// A road user is relevant when it is in the Ego's path, or when it moves towards the path
// and would reach it laterally before the Ego would have passed it longitudinally:
//   lateral gap / lateral speed < (bumper gap + L_Ego + L_other) / (v_Ego - v_other) + 0.1 s.
// For each relevant road user two fuzzy surrogate safety metrics are computed on the
// bumper gap d (speeds u_Ego, u_other along the lane; tau the reaction time):
//   PFS (proactive):  d_safe   = u_Ego tau + u_Ego^2 / (2 b_comf) - u_other^2 / (2 b_other) + d1
//                     d_unsafe = u_Ego tau + u_Ego^2 / (2 b_max)  - u_other^2 / (2 b_other)
//                     PFS = 1 if d - d1 < d_unsafe, 0 if d - d1 > d_safe, linear between;
//   CFS (critical):   the Ego's acceleration a' = max(a_Ego, -b_comf) is held for tau, then
//                     d_safe / d_unsafe are the distances needed to match the other's speed
//                     braking at b_comf / b_max; CFS = 1 below d_unsafe, 0 above d_safe.
// When either is positive the driver - after the reaction time tau for that road user -
// brakes with b = CFS (b_max - b_comf) + b_comf if CFS > 0, else PFS b_comf, the braking
// rising at most at `jerk` and never beyond `max_decel`. Otherwise it cruises towards its
// set speed (`max_accel`) and keeps its lane (pure pursuit).

#include <algorithm>
#include <cmath>
#include <limits>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

constexpr double kGravity = 9.81;  ///< m/s^2 (JRC-FSM's g)

struct FsmParameters {
  double reactionTime = 0.75;     ///< s, tau
  double comfortDecel = 4.0;      ///< m/s^2, b_comf (JRC-FSM FSM_br_min)
  double maxDecel = 6.0;          ///< m/s^2, b_max (FSM_br_max)
  double otherDecel = 7.0;        ///< m/s^2, b_other: how hard the other road user may brake (FSM_bl)
  double margin = 2.0;            ///< m, d1 (FSM_margin_dist = FSM_margin_safe_dist)
  double brakeLimit = 0.774 * kGravity;  ///< m/s^2, the driver's hardest braking (FSM_max_deceleration)
  double jerk = 12.65;            ///< m/s^3, how fast the braking rises (0.774 g in 0.6 s, CC_min_jerk)
};

/// Linear membership between d_safe (0) and d_unsafe (1).
double membership(double d, double d_safe, double d_unsafe) {
  if (d > d_safe) return 0.0;
  if (d < d_unsafe) return 1.0;
  return (d - d_safe) / (d_unsafe - d_safe);
}

double proactiveFuzzySafety(double gap, double u_ego, double u_other, const FsmParameters& p) {
  const double d = gap - p.margin;
  const double common = u_ego * p.reactionTime - u_other * u_other / (2.0 * p.otherDecel);
  const double d_safe = common + u_ego * u_ego / (2.0 * p.comfortDecel) + p.margin;
  const double d_unsafe = common + u_ego * u_ego / (2.0 * p.maxDecel);
  return membership(d, d_safe, d_unsafe);
}

double criticalFuzzySafety(double gap, double u_ego, double u_other, double a_ego, const FsmParameters& p) {
  if (u_ego <= u_other) return 0.0;
  const double a = std::max(a_ego, -p.comfortDecel);  // very hard braking is not extrapolated
  const double u_next = u_ego + p.reactionTime * a;
  if (u_next < u_other) {  // the Ego's own braking matches the speeds within tau
    const double d_safe = (u_ego - u_other) * (u_ego - u_other) / std::abs(2.0 * a_ego);
    return gap < d_safe ? 1.0 : 0.0;
  }
  const double during = (u_ego + 0.5 * a * p.reactionTime - u_other) * p.reactionTime;
  const double after = (u_next - u_other) * (u_next - u_other);
  return membership(gap, during + after / (2.0 * p.comfortDecel), during + after / (2.0 * p.maxDecel));
}

class FuzzySafetyModel final : public EgoController {
 public:
  void init(const ControllerParams& params) override {
    p_.reactionTime = params.get("reaction_time", p_.reactionTime, 0.0, 5.0);
    p_.comfortDecel = params.get("comfort_decel", p_.comfortDecel, 0.1, 20.0);
    p_.maxDecel = params.get("max_decel", p_.maxDecel, p_.comfortDecel, 20.0);
    p_.otherDecel = params.get("other_decel", p_.otherDecel, 0.1, 20.0);
    p_.margin = params.get("margin", p_.margin, 0.0, 20.0);
    p_.brakeLimit = params.get("brake_limit", p_.brakeLimit, 0.1, 20.0);
    p_.jerk = params.get("jerk", p_.jerk, 0.1, 1000.0);
    kCruise_ = params.get("k_cruise", kCruise_, 0.0, 10.0);
    maxAccel_ = params.get("max_accel", maxAccel_, 0.0, 20.0);
    configuredSetSpeed_ = params.find("set_speed", 0.0, 100.0);
    lateral_.init(params);
    params.rejectUnknown("fsm");
  }

  void reset() override {
    setSpeed_ = configuredSetSpeed_;
    focus_ = 0;
    reactionLeft_ = 0.0;
    decel_ = 0.0;
  }

  bool observesObjects() const override { return true; }
  bool followsSetSpeed() const override { return true; }

  Command step(const Observation& observation, double dt) override {
    if (observation.commandedSetSpeed) setSpeed_ = *observation.commandedSetSpeed;
    if (!setSpeed_) setSpeed_ = std::max(observation.ego.speed, 0.1);
    return {longitudinal(observation, dt), lateral_.curvature(observation)};
  }

 private:
  /// Formula 2 of the 01 series' Annex 3: the road user reaches the Ego's path before the
  /// Ego has passed it.
  bool relevant(const Observation& observation, const ObservedObject& object) const {
    if (object.relation.longitudinalDistance <= 0.0) return false;
    if (object.relation.inPath) return true;
    const double approach = object.relation.lateralDistance > 0.0 ? -object.lateralSpeed() : object.lateralSpeed();
    if (approach <= 0.0) return false;
    const double closing = observation.ego.speed - object.longitudinalSpeed();
    if (closing <= 0.0) return false;
    const double lateral_time = object.relation.lateralGap / approach;
    const double passing_time =
        (object.relation.longitudinalGap + observation.egoLength + object.length) / closing;
    return lateral_time < passing_time + 0.1;
  }

  double longitudinal(const Observation& observation, double dt) {
    const double u_ego = observation.ego.speed;
    double worst = 0.0;
    double target = 0.0;
    int focus = 0;
    for (const auto& object : observation.objects) {
      if (!relevant(observation, object)) continue;
      const double gap = object.relation.longitudinalGap;
      const double u_other = object.longitudinalSpeed();
      const double cfs = criticalFuzzySafety(gap, u_ego, u_other, observation.ego.accel, p_);
      const double pfs = proactiveFuzzySafety(gap, u_ego, u_other, p_);
      const double braking = cfs > 0.0 ? cfs * (p_.maxDecel - p_.comfortDecel) + p_.comfortDecel : pfs * p_.comfortDecel;
      if (cfs + pfs > 0.0 && braking >= target) {
        target = braking;
        worst = std::max(cfs, pfs);
        focus = object.id;
      }
    }
    if (worst <= 0.0) {  // safe: cruise
      decel_ = 0.0;
      return std::clamp(kCruise_ * (*setSpeed_ - u_ego), -p_.comfortDecel, maxAccel_);
    }
    if (focus != focus_) {  // a new road user to respond to: the reaction time passes first
      focus_ = focus;
      reactionLeft_ = p_.reactionTime;
    }
    const double waiting = std::min(reactionLeft_, dt);
    reactionLeft_ -= waiting;
    if (waiting >= dt) return 0.0;
    decel_ = std::min({decel_ + p_.jerk * (dt - waiting), p_.brakeLimit, target});
    return -decel_ * (dt - waiting) / dt;
  }

  FsmParameters p_;
  double kCruise_ = 0.5;  ///< 1/s
  double maxAccel_ = 1.0;  ///< m/s^2 (JRC-FSM max_a_CF)
  std::optional<double> configuredSetSpeed_;
  std::optional<double> setSpeed_;
  PurePursuitLateral lateral_;
  int focus_ = 0;
  double reactionLeft_ = 0.0;  ///< s
  double decel_ = 0.0;         ///< m/s^2
};

}  // namespace

void registerFuzzySafetyModel(ControllerRegistry& registry) {
  registry.add("fsm",
               "Fuzzy Safety Model (Mattas et al. 2020/2022, UN R157 01 series Annex 3): proactive and critical fuzzy "
               "safety metrics, 0.75 s reaction, braking between 4 and 6 m/s^2",
               [] { return std::make_unique<FuzzySafetyModel>(); });
}

}  // namespace vsd::sim
