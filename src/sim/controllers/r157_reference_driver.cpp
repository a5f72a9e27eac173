// `r157_reference_driver`: the "competent and careful human driver" UN Regulation No. 157
// (ALKS) uses to separate preventable from unpreventable traffic disturbances - Annex 4,
// Appendix 3 of the original version (E/ECE/TRANS/505/Rev.3/Add.156), Annex 3 of the
// 01 series. Every number below is a parameter whose default is the regulation's value;
// docs/controllers.md cites the paragraph of each.
//
// The model (Table 1 "Performance model factors for vehicles", Figures 1 and 2):
//   risk perception point  - lane change (cut-in, cut-out): the other vehicle's centre
//                            deviates more than 0.375 m from the centre of its lane;
//                            deceleration: the leading vehicle decelerates harder than
//                            5 m/s^2 (the "deceleration ratio of the preceding vehicle");
//   risk evaluation time   - 0.4 s after the risk perception point;
//   reaction               - 0.75 s from the end of perception until the deceleration starts;
//   braking                - the deceleration rises to 0.774 g in 0.6 s (road friction 1.0),
//                            to 0.85 g in 0.6 s once the cut-in vehicle fully wraps the Ego.
// What the regulation leaves open, and how it is settled here (each a parameter):
//   - whether an evaluated risk is critical: the time to collision with the road user at
//     the end of the evaluation is below `critical_ttc` (2 s, the value of the JRC and
//     esmini implementations); a leader braking beyond the threshold is always critical;
//   - a road user already in the Ego's path that gets closer than `critical_ttc` (a stopped
//     vehicle coming into range, a leader whose braking stayed below the threshold) is a
//     risk perceived at that instant ("following distance of the ego vehicle" in Table 1);
//   - the braking ends once the Ego no longer closes in on the road user and that one no
//     longer brakes; the driver then drives normally again;
//   - normal driving: lane keeping by pure pursuit and a time-gap follower with comfortable
//     limits (time_gap 2 s, max_decel 3 m/s^2); while a risk is evaluated it ignores the road
//     user concerned - the driver has not yet responded to it - and during the reaction the
//     driver neither accelerates nor brakes (`release_decel`, 0: "until starting deceleration").
// Perception instants between two observations are interpolated from the lateral speed,
// and the braking profile is integrated over each step, so the model's timing does not
// depend on the simulation step (a 0.2 s step would otherwise delay every reaction).

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

constexpr double kGravity = 9.81;  ///< m/s^2, as the regulation's "g" is used by the JRC and esmini implementations

enum class RiskKind { CutIn, CutOut, Deceleration, Closing };

/// A risk perception point: which road user, what kind, when (s, simulation time).
struct Risk {
  int id = 0;
  RiskKind kind = RiskKind::Closing;
  double time = 0.0;
  double gap = 0.0;  ///< m, to order simultaneous risks (nearest first)
};

/// What the driver remembers about a road user it has seen.
struct Track {
  int startLane = 0;         ///< relative lane at first sight
  double deviation = 0.0;    ///< m, last deviation from the centre of that lane towards or away from the Ego's
  bool laneChangeDone = false;  ///< its lane change has been perceived and evaluated once
  std::optional<double> crossedAt;  ///< s, when the deviation passed the wandering threshold in the last step
};

class R157ReferenceDriver final : public EgoController {
 public:
  R157ReferenceDriver() : normal_(TimeGapLongitudinal::Parts{true, true, false}) {}

  void init(const ControllerParams& params) override {
    wanderingThreshold_ = params.get("wandering_threshold", wanderingThreshold_, 0.0, 2.0);
    decelerationThreshold_ = params.get("deceleration_threshold", decelerationThreshold_, 0.1, 20.0);
    evaluationTime_ = params.get("risk_evaluation_time", evaluationTime_, 0.0, 5.0);
    reactionTime_ = params.get("reaction_time", reactionTime_, 0.0, 5.0);
    brakeDecel_ = params.get("brake_decel", brakeDecel_, 0.1, 20.0);
    wrapDecel_ = params.get("full_wrap_decel", wrapDecel_, 0.1, 20.0);
    riseTime_ = params.get("brake_rise_time", riseTime_, 0.01, 5.0);
    criticalTtc_ = params.get("critical_ttc", criticalTtc_, 0.0, 20.0);
    releaseDecel_ = params.get("release_decel", releaseDecel_, 0.0, 20.0);
    FollowingParameters normal;
    normal.timeGap = 2.0;
    normal.maxDecel = 3.0;
    normal_.init(params, normal);
    lateral_.init(params);
    params.rejectUnknown("r157_reference_driver");
  }

  void reset() override {
    normal_.reset();
    tracks_.clear();
    phase_ = Phase::Watching;
    decel_ = 0.0;
  }

  bool observesObjects() const override { return true; }
  bool followsSetSpeed() const override { return true; }

  Command step(const Observation& observation, double dt) override {
    const double t = observation.time;
    const double lane_width = observation.lane ? observation.lane->width : 0.0;
    updateTracks(observation.objects, lane_width, t, dt);
    if (phase_ == Phase::Watching) watch(observation);
    if (phase_ == Phase::Evaluating && t >= evaluatedAt() - 1e-9) evaluate(observation);
    if (phase_ == Phase::Braking && riskResolved(observation)) {
      phase_ = Phase::Watching;
      decel_ = 0.0;
    }
    return {longitudinal(observation, dt), lateral_.curvature(observation)};
  }

 private:
  enum class Phase { Watching, Evaluating, Reacting, Braking };

  double evaluatedAt() const { return risk_.time + evaluationTime_; }
  double brakeOnset() const { return evaluatedAt() + reactionTime_; }

  /// m a road user's centre has moved from the centre of the lane it started in, in the
  /// direction that matters: towards the Ego's lane for a neighbour (cut-in), away from the
  /// Ego's lane centre for a road user in it (cut-out). Lanes are `lane_width` wide.
  static double laneDeviation(const ObservedObject& object, int start_lane, double lane_width) {
    if (start_lane == 0) return std::abs(object.relation.objectOffset);
    return start_lane * (start_lane * lane_width - object.relation.objectOffset);
  }

  void updateTracks(const std::vector<ObservedObject>& objects, double lane_width, double t, double dt) {
    std::map<int, Track> seen;
    for (const auto& object : objects) {
      auto it = tracks_.find(object.id);
      Track track = it != tracks_.end() ? it->second : Track{object.relation.relativeLane, 0.0, false, std::nullopt};
      const double deviation = laneDeviation(object, track.startLane, lane_width);
      // When the deviation crossed the threshold between the last observation and this one,
      // the crossing instant is interpolated; a road user first seen beyond it is perceived now.
      track.crossedAt = std::nullopt;
      if (it != tracks_.end() && track.deviation <= wanderingThreshold_ && deviation > wanderingThreshold_) {
        const double fraction = (wanderingThreshold_ - track.deviation) / (deviation - track.deviation);
        track.crossedAt = t - dt + fraction * dt;
      } else if (it == tracks_.end() && deviation > wanderingThreshold_) {
        track.crossedAt = t;
      }
      track.deviation = deviation;
      seen.emplace(object.id, track);
    }
    tracks_ = std::move(seen);
  }

  /// The earliest-perceived, then nearest, risk perception point of this step, if any.
  void watch(const Observation& observation) {
    std::optional<Risk> risk;
    auto consider = [&](const Risk& candidate) {
      if (!risk || candidate.time < risk->time - 1e-9 || (candidate.time < risk->time + 1e-9 && candidate.gap < risk->gap)) {
        risk = candidate;
      }
    };
    const ObservedObject* leader = nearestInPath(observation.objects);
    for (const auto& object : observation.objects) {
      if (object.relation.longitudinalDistance <= 0.0) continue;  // behind the Ego's centre
      const Track& track = tracks_.at(object.id);
      const double gap = object.relation.longitudinalGap;
      if (!track.laneChangeDone && track.crossedAt) {
        const double towards = track.startLane * object.lateralSpeed();  // < 0: towards the Ego's lane centre
        if (std::abs(track.startLane) == 1 && towards < 0.0) consider({object.id, RiskKind::CutIn, *track.crossedAt, gap});
        if (track.startLane == 0 && &object == leader && object.relation.objectOffset * object.lateralSpeed() > 0.0) {
          consider({object.id, RiskKind::CutOut, *track.crossedAt, gap});
        }
      }
      if (&object != leader) continue;
      if (object.state.accel < -decelerationThreshold_) consider({object.id, RiskKind::Deceleration, observation.time, gap});
      if (timeToCollision(observation, object, 0.0) < criticalTtc_) consider({object.id, RiskKind::Closing, observation.time, gap});
    }
    if (!risk) return;
    risk_ = *risk;
    focus_ = risk_.id;
    phase_ = Phase::Evaluating;
  }

  /// s until the gap closes at the current speeds, the gap taken `late` s earlier (inf if not closing).
  double timeToCollision(const Observation& observation, const ObservedObject& object, double late) const {
    const double closing = observation.ego.speed - object.longitudinalSpeed();
    if (closing <= 0.0) return std::numeric_limits<double>::infinity();
    return (object.relation.longitudinalGap + closing * late) / closing;
  }

  void evaluate(const Observation& observation) {
    auto& track = tracks_[risk_.id];
    if (risk_.kind == RiskKind::CutIn || risk_.kind == RiskKind::CutOut) track.laneChangeDone = true;
    const ObservedObject* target = evaluationTarget(observation);
    const double late = observation.time - evaluatedAt();
    const bool critical = target != nullptr && target->relation.longitudinalDistance > 0.0 &&
                          (risk_.kind == RiskKind::Deceleration || timeToCollision(observation, *target, late) < criticalTtc_);
    if (!critical) {
      phase_ = Phase::Watching;
      return;
    }
    focus_ = target->id;
    phase_ = Phase::Reacting;
  }

  /// The road user whose risk is evaluated: the one perceived, or for a cut-out the one it reveals.
  const ObservedObject* evaluationTarget(const Observation& observation) const {
    const ObservedObject* perceived = find(observation, risk_.id);
    if (risk_.kind != RiskKind::CutOut) return perceived;
    const ObservedObject* revealed = nullptr;
    for (const auto& object : observation.objects) {
      if (object.id == risk_.id || !object.relation.inPath) continue;
      if (revealed == nullptr || object.relation.longitudinalGap < revealed->relation.longitudinalGap) revealed = &object;
    }
    return revealed;
  }

  static const ObservedObject* find(const Observation& observation, int id) {
    for (const auto& object : observation.objects) {
      if (object.id == id) return &object;
    }
    return nullptr;
  }

  bool riskResolved(const Observation& observation) const {
    const ObservedObject* object = find(observation, focus_);
    if (object == nullptr || object->relation.longitudinalDistance <= 0.0) return true;
    constexpr double kNotBraking = -0.5;  // m/s^2: a road user decelerating less than this no longer brakes
    return observation.ego.speed <= object->longitudinalSpeed() && object->state.accel >= kNotBraking;
  }

  bool fullWrap(const Observation& observation) const {
    const ObservedObject* object = find(observation, focus_);
    if (object == nullptr) return false;
    return object->relation.lateralGap <= -std::min(observation.egoWidth, object->width) + 1e-9;
  }

  /// Normal driving, ignoring the road user whose risk is under evaluation or reaction.
  double normalAccel(const Observation& observation) {
    std::optional<Observation::Leader> leader;
    const ObservedObject* nearest = nullptr;
    for (const auto& object : observation.objects) {
      if (!object.relation.inPath || (phase_ != Phase::Watching && object.id == focus_)) continue;
      if (nearest == nullptr || object.relation.longitudinalGap < nearest->relation.longitudinalGap) nearest = &object;
    }
    if (nearest != nullptr) leader = leaderOf(*nearest);
    return normal_.accel(observation, leader);
  }

  /// The step's command: normal driving until the brake onset, then the braking profile.
  double longitudinal(const Observation& observation, double dt) {
    const double t = observation.time;
    if (phase_ == Phase::Watching || phase_ == Phase::Evaluating) return normalAccel(observation);
    double normal_part = 0.0;
    double from = t;
    if (phase_ == Phase::Reacting) {
      if (t + dt <= brakeOnset()) return -releaseDecel_;
      normal_part = -releaseDecel_ * (brakeOnset() - t);
      from = brakeOnset();
      phase_ = Phase::Braking;
    }
    const double cap = fullWrap(observation) ? wrapDecel_ * kGravity : brakeDecel_ * kGravity;
    const double jerk = cap / riseTime_;
    const double braking = rampIntegral(from, t + dt, cap, jerk);
    return (normal_part - braking) / dt;
  }

  /// Integral over [from, to] of the braking deceleration rising from decel_ at `jerk` up to
  /// `cap` (a lower cap takes effect at once); advances decel_ to its value at `to`.
  double rampIntegral(double from, double to, double cap, double jerk) {
    const double duration = std::max(0.0, to - from);
    const double start = std::min(decel_, cap);
    const double rise = std::min(duration, (cap - start) / jerk);
    const double integral = start * rise + 0.5 * jerk * rise * rise + cap * (duration - rise);
    decel_ = start + jerk * rise;
    return integral;
  }

  // Table 1 of the regulation (defaults) - see the file's header.
  double wanderingThreshold_ = 0.375;    ///< m
  double decelerationThreshold_ = 5.0;   ///< m/s^2
  double evaluationTime_ = 0.4;          ///< s
  double reactionTime_ = 0.75;           ///< s
  double brakeDecel_ = 0.774;            ///< g
  double wrapDecel_ = 0.85;              ///< g
  double riseTime_ = 0.6;                ///< s
  double criticalTtc_ = 2.0;             ///< s
  double releaseDecel_ = 0.0;            ///< m/s^2 while reacting (0: the regulation's "until starting deceleration")

  TimeGapLongitudinal normal_;
  PurePursuitLateral lateral_;
  std::map<int, Track> tracks_;
  Phase phase_ = Phase::Watching;
  Risk risk_;
  int focus_ = 0;
  double decel_ = 0.0;  ///< m/s^2, braking deceleration reached
};

}  // namespace

void registerR157ReferenceDriver(ControllerRegistry& registry) {
  registry.add("r157_reference_driver",
               "UN R157's competent and careful human driver (Annex 4 Appendix 3 / 01 series Annex 3): risk perception "
               "at 0.375 m lateral deviation or 5 m/s^2 leader braking, 0.4 s evaluation, 0.75 s reaction, 0.774 g in "
               "0.6 s",
               [] { return std::make_unique<R157ReferenceDriver>(); });
}

}  // namespace vsd::sim
