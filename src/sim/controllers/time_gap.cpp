// The longitudinal parts the car-following built-ins share: the scenario's following
// parameters, the time-gap law with its switchable parts, and the deceleration needed to
// keep a margin to a braking leader.

#include <algorithm>
#include <cmath>
#include <limits>

#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

/// Minimum over t >= 0 of the gap when the follower brakes with `decel` and the
/// leader accelerates with `leader_accel` (both stop at 0, never reverse).
double minimumGap(double gap, double speed, double decel, double leader_speed, double leader_accel) {
  auto travel = [](double v, double a, double t) {
    if (a < 0.0) {
      const double stop = v / -a;
      if (t >= stop) return v * stop + 0.5 * a * stop * stop;
    }
    return v * t + 0.5 * a * t * t;
  };
  auto gap_at = [&](double t) { return gap + travel(leader_speed, leader_accel, t) - travel(speed, -decel, t); };
  // The gap is piecewise quadratic; its minimum is at t = 0, at a stop time, at the
  // instant both speeds are equal, or (if the follower never stops) at infinity.
  double result = gap;
  const double follower_stop = decel > 0.0 ? speed / decel : std::numeric_limits<double>::infinity();
  const double leader_stop = leader_accel < 0.0 ? leader_speed / -leader_accel : std::numeric_limits<double>::infinity();
  for (double t : {follower_stop, leader_stop}) {
    if (std::isfinite(t)) result = std::min(result, gap_at(t));
  }
  const double relative_accel = leader_accel + decel;  // d/dt (v_leader - v_follower)
  if (relative_accel > 0.0) {
    const double t_equal = (speed - leader_speed) / relative_accel;
    if (t_equal > 0.0 && t_equal < std::min(follower_stop, leader_stop)) result = std::min(result, gap_at(t_equal));
  }
  if (!std::isfinite(follower_stop) && speed > leader_speed && leader_accel <= 0.0) {
    result = -std::numeric_limits<double>::infinity();
  }
  return result;
}

}  // namespace

double requiredDeceleration(double gap, double speed, double leader_speed, double leader_accel, double margin,
                            double max_decel) {
  if (minimumGap(gap, speed, 0.0, leader_speed, leader_accel) >= margin) return 0.0;
  if (minimumGap(gap, speed, max_decel, leader_speed, leader_accel) < margin) {
    return std::numeric_limits<double>::infinity();
  }
  double lo = 0.0;
  double hi = max_decel;
  for (int i = 0; i < 40; ++i) {  // bisection: the minimum gap grows with the deceleration
    const double mid = 0.5 * (lo + hi);
    if (minimumGap(gap, speed, mid, leader_speed, leader_accel) >= margin) hi = mid;
    else lo = mid;
  }
  return hi;
}

void FollowingParameters::read(const ControllerParams& params, bool with_time_gap) {
  if (with_time_gap) timeGap = params.get("time_gap", timeGap, 0.1, 10.0);
  standstillGap = params.get("standstill_gap", standstillGap, 0.0, 50.0);
  maxAccel = params.get("max_accel", maxAccel, 0.1, 20.0);
  maxDecel = params.get("max_decel", maxDecel, 0.1, 20.0);
  configuredSetSpeed_ = params.find("set_speed", 0.0, 100.0);
  setSpeed_ = configuredSetSpeed_;
}

double FollowingParameters::setSpeed(const Observation& observation) {
  if (observation.commandedSetSpeed) return *observation.commandedSetSpeed;
  if (!setSpeed_) setSpeed_ = std::max(observation.ego.speed, 0.1);
  return *setSpeed_;
}

double FollowingParameters::clamp(double accel) const { return std::clamp(accel, -maxDecel, maxAccel); }

void TimeGapLongitudinal::init(const ControllerParams& params, const FollowingParameters& defaults) {
  following_ = defaults;
  following_.read(params, !timeGapOf_);
  kGap_ = params.get("k_gap", kGap_, 0.0, 10.0);
  kSpeed_ = params.get("k_speed", kSpeed_, 0.0, 10.0);
  kCruise_ = params.get("k_cruise", kCruise_, 0.0, 10.0);
  emergencyMargin_ = params.get("emergency_margin", emergencyMargin_, 0.0, 50.0);
  emergencyTrigger_ = params.get("emergency_trigger", emergencyTrigger_, 0.0, 100.0);
  auto part = [&](const char* name, bool fallback) {
    return params.get(name, fallback ? 1.0 : 0.0, 0.0, 1.0) >= 0.5;  // 0 = off, 1 = on
  };
  parts_.relativeSpeedTerm = part("relative_speed_term", parts_.relativeSpeedTerm);
  parts_.cruiseCap = part("cruise_cap", parts_.cruiseCap);
  parts_.emergencyBrake = part("emergency_brake", parts_.emergencyBrake);
}

double TimeGapLongitudinal::accel(const Observation& observation, const std::optional<Observation::Leader>& lead) {
  const double speed = observation.ego.speed;
  const double cruise = kCruise_ * (following_.setSpeed(observation) - speed);
  if (!lead) return following_.clamp(cruise);
  const auto& leader = *lead;
  const double time_gap = timeGapOf_ ? timeGapOf_(speed) : following_.timeGap;
  const double desired_gap = std::max(following_.standstillGap, time_gap * speed);
  double command = kGap_ * (leader.gap - desired_gap);
  if (parts_.relativeSpeedTerm) command += kSpeed_ * (leader.speed - speed);
  if (parts_.cruiseCap) command = std::min(command, cruise);
  if (parts_.emergencyBrake) {
    // Only braking of the leader is extrapolated: a measured acceleration > 0 may be noise.
    const double required = requiredDeceleration(leader.gap, speed, leader.speed, std::min(leader.accel, 0.0),
                                                 emergencyMargin_, following_.maxDecel);
    if (required > emergencyTrigger_) command = std::min(command, -1.1 * required);
  }
  return following_.clamp(command);
}

void LeaderChoice::init(const ControllerParams& params) {
  fromObjects_ = params.get("leader_from_objects", 0.0, 0.0, 1.0) >= 0.5;
}

std::optional<Observation::Leader> LeaderChoice::leader(const Observation& observation) const {
  if (!fromObjects_) return observation.leader;
  const ObservedObject* nearest = nearestInPath(observation.objects);
  if (nearest == nullptr) return std::nullopt;
  return leaderOf(*nearest);
}

}  // namespace vsd::sim
