#pragma once
// The parts the built-in Ego controllers are made of: lateral (lane keeping) and
// longitudinal (car following) classes that a controller combines. The controllers
// themselves live one per file in src/sim/controllers/; registry.cpp lists them all.

#include <functional>
#include <optional>

#include "vsd/sim/controller.hpp"

namespace vsd::sim {

/// Lane keeping by pure pursuit on the lane-centre preview:
/// lookahead L = max(min_lookahead, lookahead_time * v), curvature = 2 sin(alpha) / L,
/// alpha = bearing of the lane-centre point L ahead in the Ego frame.
/// With no lane in sight it drives straight (curvature 0).
class PurePursuitLateral {
 public:
  void init(const ControllerParams& params);
  double curvature(const Observation& observation) const;

 private:
  double lookaheadTime_ = 0.4;   ///< s
  double minLookahead_ = 4.0;    ///< m
};

/// Parameters every car-following controller here shares, read from the scenario:
/// time_gap [s], standstill_gap [m], max_accel / max_decel [m/s^2] (command limits) and
/// set_speed [m/s] (cruise speed; default: the Ego's speed at its first step).
struct FollowingParameters {
  double timeGap = 2.0;
  double standstillGap = 2.0;
  double maxAccel = 2.0;
  double maxDecel = 9.0;

  /// `with_time_gap` false: time_gap is not a parameter (a controller with its own time gap).
  void read(const ControllerParams& params, bool with_time_gap = true);
  /// Forgets the set speed taken from a previous scenario's first step.
  void reset() { setSpeed_ = configuredSetSpeed_; }
  /// The cruise speed: the scenario's commanded set speed once it has one, else set_speed,
  /// else the Ego's speed at its first step.
  double setSpeed(const Observation& observation);
  double clamp(double accel) const;

 private:
  std::optional<double> configuredSetSpeed_;
  std::optional<double> setSpeed_;
};

/// Time-gap car following, in parts that the scenario switches on and off (0/1 parameters):
///   time-gap P-term (always):  a = k_gap * (gap - max(standstill_gap, time_gap * v))
///   relative_speed_term:       + k_speed * (v_leader - v)
///   cruise_cap:                never more than the cruise command k_cruise * (set_speed - v)
///   emergency_brake:           b_req = the smallest constant deceleration that keeps
///                              `emergency_margin` to the leader (assumed to keep braking at
///                              its current rate until it stops); when b_req > emergency_trigger
///                              the command is at most -1.1 b_req
/// With no leader it cruises: k_cruise * (set_speed - v) (set_speed default: the initial speed).
/// The result is clamped to [-max_decel, max_accel].
class TimeGapLongitudinal {
 public:
  /// Which parts are on unless the scenario's parameters say otherwise.
  struct Parts {
    bool relativeSpeedTerm = true;
    bool cruiseCap = true;
    bool emergencyBrake = true;
  };
  explicit TimeGapLongitudinal(Parts defaults) : parts_(defaults) {}
  /// Reads the scenario's parameters; `defaults` are the following parameters it does not set.
  void init(const ControllerParams& params, const FollowingParameters& defaults = {});
  /// Takes the desired time gap (s) as a function of the Ego's speed (m/s) instead of the
  /// constant time_gap - UN R157's speed-dependent minimum for the `alks` controller.
  void useTimeGap(std::function<double(double)> time_gap_of_speed) { timeGapOf_ = std::move(time_gap_of_speed); }
  void reset() { following_.reset(); }
  /// The command with SUMO's leader (Observation::leader).
  double accel(const Observation& observation) { return accel(observation, observation.leader); }
  /// The command with `leader` as the lead (none: cruise).
  double accel(const Observation& observation, const std::optional<Observation::Leader>& leader);

 private:
  Parts parts_;
  FollowingParameters following_;
  std::function<double(double)> timeGapOf_;
  double kGap_ = 0.3;              ///< 1/s^2
  double kSpeed_ = 0.8;            ///< 1/s
  double kCruise_ = 0.5;           ///< 1/s
  double emergencyMargin_ = 1.0;   ///< m
  double emergencyTrigger_ = 2.0;  ///< m/s^2
};

/// Where a car follower takes its lead from - the scenario's 0/1 parameter
/// `leader_from_objects`: 0 (default) SUMO's leader (Observation::leader, what the paper's
/// controllers have always used: their outputs stay byte for byte the same), 1 the nearest
/// road user of the object list in the Ego's path, which sees a cut-in as it enters the path.
class LeaderChoice {
 public:
  void init(const ControllerParams& params);
  bool fromObjects() const { return fromObjects_; }
  std::optional<Observation::Leader> leader(const Observation& observation) const;

 private:
  bool fromObjects_ = false;
};

/// UN R157 paragraph 5.2.3.3: the minimum time gap (s) of an ALKS vehicle (M1/N1) at `speed`
/// (m/s) - 1.0 s at 7.2 km/h rising by 0.1 s per 10 km/h to 1.6 s at 60 km/h, linear in
/// between, 1.0 s below 7.2 km/h and 1.6 s above 60 km/h (the end of the original version's table).
double r157MinimumTimeGap(double speed);

/// Smallest constant deceleration (m/s^2, >= 0) of a follower at `speed` that keeps at
/// least `margin` m to a leader `gap` m ahead at `leader_speed` accelerating with
/// `leader_accel` (<= 0: braking until it stops). Returns +inf if even `max_decel`
/// cannot keep the margin.
double requiredDeceleration(double gap, double speed, double leader_speed, double leader_accel, double margin,
                            double max_decel);

}  // namespace vsd::sim
