#include "vsd/sim/scripted_vehicle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <string>

#include "vsd/core/error.hpp"
#include "vsd/core/path_relation.hpp"
#include "vsd/sim/builtin_controllers.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/vehicle_model.hpp"

namespace vsd::sim {

namespace {

using scenario::ActionSpec;
using scenario::ConcreteAction;
using scenario::TransitionShape;
using scenario::TriggerSpec;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A transition of a speed or a lateral offset from `from` to `to` over [start, start + duration].
struct Transition {
  double start = 0.0;
  double duration = 0.0;
  double from = 0.0;
  double to = 0.0;
  TransitionShape shape = TransitionShape::Linear;

  double end() const { return start + duration; }
  double at(double t) const {
    if (t >= end()) return to;
    if (t <= start) return from;
    const double tau = (t - start) / duration;
    const double share = shape == TransitionShape::Smooth  ? 0.5 * (1.0 - std::cos(kPi * tau))
                         : shape == TransitionShape::Cubic ? tau * tau * (3.0 - 2.0 * tau)
                                                           : tau;
    return from + (to - from) * share;
  }
  double rate(double t) const {
    if (t < start || t >= end() || duration <= 0.0) return 0.0;
    const double tau = (t - start) / duration;
    const double mean = (to - from) / duration;
    if (shape == TransitionShape::Smooth) return mean * 0.5 * kPi * std::sin(kPi * tau);
    return shape == TransitionShape::Cubic ? mean * 6.0 * tau * (1.0 - tau) : mean;
  }
};

/// The duration of a transition from `from` to `to` (m/s or m) at an action's pace.
double durationOf(const ConcreteAction& action, double from, double to) {
  const double magnitude = std::abs(to - from);
  // A smooth (half-cosine) profile peaks at pi/2 times its mean rate, a cubic one at 1.5 times.
  const double peak_factor = action.shape == TransitionShape::Smooth  ? 0.5 * kPi
                             : action.shape == TransitionShape::Cubic ? 1.5
                                                                      : 1.0;
  switch (action.pace) {
    case ActionSpec::Pace::Duration: return action.shape == TransitionShape::Step ? 0.0 : action.paceValue;
    case ActionSpec::Pace::Rate:
    case ActionSpec::Pace::LateralSpeed: return peak_factor * magnitude / action.paceValue;
    // Peak accelerations: pi^2 / 2 (smooth) and 6 (cubic) times the change over the duration
    // squared; a linear change has none (its speed jumps) and is paced as a cubic one, as esmini does.
    case ActionSpec::Pace::LateralAccel:
      return action.shape == TransitionShape::Smooth ? kPi * std::sqrt(magnitude / (2.0 * action.paceValue))
                                                     : std::sqrt(6.0 * magnitude / action.paceValue);
    // A speed change over a distance: linear, smooth and cubic profiles average (from + to) / 2,
    // so they cover the distance in 2 d / (from + to) (as esmini converts it; speeds are >= 0).
    // No change ends at once, as in esmini.
    case ActionSpec::Pace::Distance:
      return magnitude > 1e-9 && from + to > 0.0 ? 2.0 * action.paceValue / (from + to) : 0.0;
  }
  return 0.0;
}

/// The duration of a lateral transition at an action's pace; a lane change over a distance
/// covers it at `speed` (m/s along the road, the road user's when it starts), so it lasts
/// distance / speed (esmini follows the distance travelled: the same while the speed holds).
double lateralDuration(const ConcreteAction& action, const Transition& transition, double speed,
                       const std::string& sample) {
  if (action.pace != ActionSpec::Pace::Distance) return durationOf(action, transition.from, transition.to);
  if (!(speed > 1e-9)) {
    throw ConfigError(fmt::format("{}: {}.lane_change.distance: at t = {:.1f} s it stands and covers no distance "
                                  "(expected a road user that moves when its lane change over a distance starts)",
                                  sample, action.where, transition.start));
  }
  return action.paceValue / speed;
}

/// One scripted road user as the stepper moves it.
struct Mover {
  const scenario::ConcreteVehicle* spec = nullptr;
  VehicleState state;
  // Pure pursuit: its lane's centre line.
  MeasuredPolyline lane;
  // Exact: its place in the lane frame and its current lane.
  double s = 0.0;
  double d = 0.0;
  int laneIndex = 0;
  std::optional<Transition> speed;    ///< the latest speed action (none: the scripted speed)
  std::optional<Transition> lateral;  ///< the latest lateral action (none: stays at d)
  /// The latest speed and lateral actions that started (index into ConcreteScenario::actions): a
  /// later one, or a teleport, ends them where it starts.
  std::optional<std::size_t> speedAction;
  std::optional<std::size_t> lateralAction;
  double speedAlong = 0.0;            ///< m/s, longitudinal speed at the current instant
  /// The latest speed action if it is continuous (it tracks another road user's speed): its index.
  std::optional<std::size_t> tracking;
  double trackedSpeed = 0.0;  ///< m/s, what the tracking action asks for over the current step

  /// Nominal (noise-free) longitudinal speed at t.
  double nominalSpeed(double t, double step) const {
    if (tracking) return trackedSpeed;
    if (speed) return speed->at(t);
    // Before any speed action: the scripted speed without its noise, between instants linearly.
    const auto& scripted = spec->scriptedSpeed;
    const double position = std::clamp(t / step, 0.0, static_cast<double>(scripted.size() - 1));
    const auto k = std::min(static_cast<std::size_t>(position), scripted.size() - 2);
    const double f = position - static_cast<double>(k);
    const double a = scripted[k] - spec->speedNoise[k];
    const double b = scripted[k + 1] - spec->speedNoise[k + 1];
    return a + f * (b - a);
  }
  /// Longitudinal speed at instant k (noise included, never below 0).
  double speedAt(std::size_t k, double step) const {
    if (tracking) return std::max(0.0, trackedSpeed + spec->speedNoise[k]);
    if (!speed) return spec->scriptedSpeed[k];
    return std::max(0.0, speed->at(static_cast<double>(k) * step) + spec->speedNoise[k]);
  }
};

/// True if a trigger (or a member) needs the distances travelled or the road's end.
bool measuresProgress(const scenario::ConcreteTrigger& trigger) {
  if (trigger.kind == TriggerSpec::Kind::Travelled || trigger.kind == TriggerSpec::Kind::EndOfRoad) return true;
  return std::any_of(trigger.members.begin(), trigger.members.end(), measuresProgress);
}

/// `quantity` against a bound; to 1e-9, so that values computed at instants (e.g. 20 + 5 * 1.0
/// reached through 25 steps) meet a bound they reach exactly.
bool withinBound(double quantity, const scenario::ConcreteTrigger& trigger) {
  constexpr double kTolerance = 1e-9;
  return trigger.bound == TriggerSpec::Bound::AtLeast ? quantity >= trigger.value - kTolerance
                                                      : quantity <= trigger.value + kTolerance;
}

Footprint footprintOf(const VehicleState& state, double length, double width) {
  return {state.position(), state.heading, length, width};
}

/// A road user's reference point (VehicleSpec::referencePoint ahead of its centre), in the frame.
Vec2 referencePoint(const VehicleState& state, const scenario::ConcreteVehicle& spec) {
  return state.position() + spec.referencePoint * Vec2(std::cos(state.heading), std::sin(state.heading));
}

}  // namespace

EgoStandIn::EgoStandIn(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road)
    : lane_(road.laneCentre(concrete.ego.lane)), speed_(concrete.ego.speed) {
  const road::LaneFrame frame(road.centre);
  const auto start = road::roadUserStart(road, frame, concrete, concrete.ego, 0.0, 0.0);
  startArcLength_ = lane_.project(start.position).arcLength;
}

VehicleState EgoStandIn::at(double time) const {
  const double s = startArcLength_ + speed_ * time;
  const Vec2 position = lane_.pointAt(s);
  return {position.x(), position.y(), lane_.headingAt(s), speed_, 0.0};
}

struct ScriptedTraffic::Impl {
  const scenario::ConcreteScenario* concrete = nullptr;
  const road::RoadGeometry* road = nullptr;
  road::LaneFrame frame;
  MeasuredPolyline egoLane;  ///< the Ego's starting lane: the reference line of triggers
  VehicleState egoStart;
  std::size_t k = 0;
  double step = 0.0;
  std::vector<Mover> movers;
  std::vector<VehicleState> states;
  std::vector<ActionTiming> timings;
  std::vector<double> scheduled;  ///< per action: start time once its trigger fired (NaN before)
  std::vector<int> starts;        ///< per action: how many times it started (up to its repeat)
  std::vector<double> firstEnds;  ///< per action: the end of its first run once a second has started (NaN before)
  /// An edge condition's memory: whether it held when last checked, and its answer at instant `instant`.
  struct Edge {
    std::size_t instant = std::numeric_limits<std::size_t>::max();
    bool checked = false;
    bool held = false;
    bool fired = false;
  };
  mutable std::map<const scenario::ConcreteTrigger*, Edge> edges;
  /// The Ego's set_speed actions that started: (start time s, set speed m/s), in start order.
  std::vector<std::pair<double, double>> egoSetSpeeds;
  /// The Ego's controller actions that started: (start time s, action index), in start order.
  std::vector<std::pair<double, std::size_t>> egoControllers;
  /// The Ego's lane_change and lateral_offset actions that started: (start time s, the move of
  /// the lane its controller keeps, as offsets across the road in m), in start order.
  std::vector<std::pair<double, Transition>> egoLaterals;
  int egoLateralLane = 0;  ///< the road lane the latest of them moves to (valid once one started)
  std::optional<std::size_t> egoLateralAction;  ///< the latest of them (index into ConcreteScenario::actions)
  /// Where a teleport of the Ego that starts over the step ahead puts it at the current instant
  /// (none: no such teleport); its controller drives it on from there.
  std::optional<VehicleState> egoPlaced;
  PurePursuitLateral laneKeeping;  // the Ego's defaults: lookahead max(4 m, 0.4 s * v)
  // What travelled and end_of_road conditions measure, per road user (0: the Ego, 1 + o: others[o]);
  // tracked only if a trigger asks.
  bool tracksProgress = false;
  std::vector<double> travelled;     ///< m since t = 0 (sum of the straight steps between instants)
  std::vector<double> atRoadEndSince;  ///< s: first instant its front was at or beyond the region's end (NaN: never)
  VehicleState lastEgo;
  double regionStartS = 0.0;  ///< m along the centre line where the scenario region starts
  double regionEndS = 0.0;    ///< m along the centre line where it ends (the road's end for end_of_road)

  /// Pairs let start overlapping (VehicleSpec::mayStartOverlapping), in scenario order.
  std::vector<std::string> startOverlaps;

  void init();
  void checkOverlaps();
  double relationValue(const scenario::ConcreteTrigger& trigger, int owner, const VehicleState& ego) const;
  double distanceToPlace(const scenario::ConcreteTrigger& trigger, const VehicleState& ego) const;
  /// Road user `user`'s id: -1 the Ego, else others[user].
  std::string idOf(int user) const {
    return user < 0 ? std::string("ego") : concrete->others[static_cast<std::size_t>(user)].id;
  }
  /// Road user `user`'s state and description: -1 the Ego, else others[user].
  const VehicleState& stateOf(int user, const VehicleState& ego) const {
    return user < 0 ? ego : states[static_cast<std::size_t>(user)];
  }
  const scenario::ConcreteVehicle& specOf(int user) const {
    return user < 0 ? concrete->ego : concrete->others[static_cast<std::size_t>(user)];
  }
  void trackProgress(const VehicleState& ego);
  bool holds(const scenario::ConcreteTrigger& trigger, int owner, const VehicleState& ego) const;
  bool conditionHolds(const scenario::ConcreteTrigger& trigger, int owner, const VehicleState& ego) const;
  void rearmEnded();
  double awaitedEnd(const scenario::ConcreteTrigger& trigger) const;
  /// When a time or after trigger fires (s), its delay included; NaN before its action's end is known.
  double momentOf(const scenario::ConcreteTrigger& trigger) const {
    return (trigger.kind == TriggerSpec::Kind::Time ? trigger.value : awaitedEnd(trigger)) + trigger.delay;
  }
  /// Its edge conditions (rising, falling; and its members') as if never checked.
  void forgetEdges(const scenario::ConcreteTrigger& trigger) const;
  double fireTime(const scenario::ConcreteTrigger& trigger, int owner, const VehicleState& ego) const;
  void offer(std::size_t a, const VehicleState& ego);
  void fireTriggers(const VehicleState& ego);
  double speedTargetOf(const ConcreteAction& action, double from, const VehicleState& ego) const;
  void startSpeedAction(std::size_t a, Mover& mover, Transition transition, const VehicleState& ego);
  void track(const VehicleState& ego);
  void activate(std::size_t a, const VehicleState& ego);
  void activateEgoLateral(std::size_t a, const VehicleState& ego);
  /// Whether `d` (m left of the centre line) lies on the road's lanes or shoulders.
  bool onPavedGround(double d) const;
  /// Where a teleport lands: m along the frame, m left of the centre line, road lane.
  struct Landing {
    double s = 0.0;
    double d = 0.0;
    int lane = 0;
  };
  Landing landingOf(std::size_t a, const VehicleState& ego) const;
  /// The heading (rad, relative to the road's direction) road user `owner` (-1: the Ego) lands
  /// with if teleported now: moving, along its lane in its direction; standing, the one it has.
  double landingFacing(int owner, const VehicleState& ego) const;
  Landing placeNow(const scenario::ConcretePlace& place, const VehicleState& ego, double since) const;
  /// Where a place relative to a road user in the plane lies in the frame, that one where it is
  /// `since` s after the current instant (moved on along its heading at its speed).
  Vec2 planePoint(const scenario::ConcretePlace& place, const VehicleState& ego, double since) const;
  /// Refuses a relative place on a lane the road does not have; `field` names the place.
  [[noreturn]] void refuseLane(const Landing& landing, const scenario::ConcretePlace& place,
                               const std::string& field) const;
  void teleport(std::size_t a, const VehicleState& ego);
  void teleportEgo(std::size_t a, const VehicleState& ego);
  /// The road lane the Ego at `ego` is in.
  int egoLaneOf(const VehicleState& ego) const;
  /// The road lane a lane change of `owner` (-1: the Ego), now in lane `own_lane`, goes to.
  int laneChangeTarget(const ConcreteAction& action, int own_lane, const VehicleState& ego, double t0) const;
  void scheduleWaiters(std::size_t a, const VehicleState& ego);
  /// Ends action `a` (if any) at `t` if it is under way then: a later action replaced it.
  void endIfUnderWay(const std::optional<std::size_t>& a, double t, const VehicleState& ego);
  /// Whether action `a` (if any) is a lane change under way at `t`: ended there, its road user is
  /// in the lane it has got to (as esmini finds a road user's lane from where it is).
  bool laneChangeUnderWay(const std::optional<std::size_t>& a, double t) const {
    return a && concrete->actions[*a].kind == ActionSpec::Kind::LaneChange && timings[*a].start <= t + 1e-9 &&
           timings[*a].end > t;
  }
  /// Ends `mover`'s speed action at `t`: it keeps the (noise-free) speed it has then.
  void holdSpeed(Mover& mover, double t, const VehicleState& ego);
  /// Ends action `a`'s ends (ActionSpec::ends) under way at its start: their road users keep the
  /// speed and the place across the road they have reached.
  void endListed(std::size_t a, const VehicleState& ego);
  void activateDue(const VehicleState& ego);
  VehicleState advancePurePursuit(Mover& mover);
  VehicleState advanceExact(Mover& mover);
};

void ScriptedTraffic::Impl::init() {
  frame = road::LaneFrame(road->centre);
  const auto ego = road::roadUserStart(*road, frame, *concrete, concrete->ego, 0.0, 0.0);
  egoStart = {ego.position.x(), ego.position.y(), ego.heading, concrete->ego.speed, 0.0};
  egoLane = MeasuredPolyline(road->laneCentre(concrete->ego.lane));
  step = concrete->step();
  for (const auto& other : concrete->others) {
    Mover mover;
    mover.spec = &other;
    const bool from_ego = other.alongFrom < 0;
    const double from_s = from_ego ? ego.s : movers[static_cast<std::size_t>(other.alongFrom)].s;
    const double from_length = from_ego ? concrete->ego.length : concrete->others[static_cast<std::size_t>(other.alongFrom)].length;
    const auto start = road::roadUserStart(*road, frame, *concrete, other, from_s, from_length);
    mover.state = {start.position.x(), start.position.y(), start.heading, other.scriptedSpeed.at(0), 0.0};
    mover.s = start.s;
    mover.d = start.d;
    mover.laneIndex = other.lane;
    mover.speedAlong = other.scriptedSpeed.at(0);
    if (other.purePursuit) mover.lane = MeasuredPolyline(road->laneCentre(other.lane));
    movers.push_back(std::move(mover));
    states.push_back(movers.back().state);
  }
  timings.assign(concrete->actions.size(), {kNaN, kNaN});
  scheduled.assign(concrete->actions.size(), kNaN);
  starts.assign(concrete->actions.size(), 0);
  firstEnds.assign(concrete->actions.size(), kNaN);
  for (std::size_t a = 0; a < concrete->actions.size(); ++a) {
    const auto& trigger = concrete->actions[a].trigger;
    if (trigger.kind == TriggerSpec::Kind::Time) scheduled[a] = trigger.value + trigger.delay;
    tracksProgress = tracksProgress || measuresProgress(trigger);
  }
  regionStartS = road->regionStart();
  regionEndS = regionStartS;
  for (std::size_t i = road->regionBegin + 1; i < road->regionEnd; ++i) {
    regionEndS += (road->centre[i] - road->centre[i - 1]).norm();
  }
  travelled.assign(movers.size() + 1, 0.0);
  atRoadEndSince.assign(movers.size() + 1, kNaN);
  lastEgo = egoStart;
  checkOverlaps();
}

void ScriptedTraffic::Impl::checkOverlaps() {
  std::vector<Footprint> footprints = {footprintOf(egoStart, concrete->ego.length, concrete->ego.width)};
  std::vector<const scenario::ConcreteVehicle*> users = {&concrete->ego};
  for (const auto& mover : movers) {
    footprints.push_back(footprintOf(mover.state, mover.spec->length, mover.spec->width));
    users.push_back(mover.spec);
  }
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    for (std::size_t j = i + 1; j < footprints.size(); ++j) {
      const double clearance = footprintGap(footprints[i], footprints[j]);
      if (clearance >= 0.0) continue;
      // Index 0 is the Ego: nothing may start inside it (its test would begin with a collision).
      if (i > 0 && (users[i]->mayStartOverlapping || users[j]->mayStartOverlapping)) {
        startOverlaps.push_back(fmt::format("'{}' starts overlapping '{}' (clearance {:.2f} m)", users[j]->id,
                                            users[i]->id, clearance));
        continue;
      }
      throw ConfigError(fmt::format("{}: road user '{}' starts overlapping '{}' (clearance {:.2f} m): expected road "
                                    "users apart at t = 0 (check their x/s/ds, lane and offset)",
                                    concrete->where(), users[j]->id, users[i]->id, clearance));
    }
  }
}

/// The value a gap, headway or ttc trigger of road user `owner` (-1: the Ego) compares (inf: never).
double ScriptedTraffic::Impl::relationValue(const scenario::ConcreteTrigger& trigger, int owner,
                                            const VehicleState& ego) const {
  const VehicleState& other = stateOf(trigger.reference, ego);
  const auto& other_spec = specOf(trigger.reference);
  const VehicleState& self = stateOf(owner, ego);
  const auto& self_spec = specOf(owner);
  using Measure = scenario::TriggerSpec::Measure;
  double signed_gap = 0.0;  // m, what a gap trigger compares (bumpers: < 0 side by side)
  bool self_ahead = false;
  if (trigger.betweenReferencePoints) {
    const PolylineProjection self_foot = projectExtended(egoLane, referencePoint(self, self_spec));
    const PolylineProjection other_foot = projectExtended(egoLane, referencePoint(other, other_spec));
    self_ahead = self_foot.arcLength > other_foot.arcLength;
    switch (trigger.measure) {
      case Measure::AlongLane: signed_gap = std::abs(self_foot.arcLength - other_foot.arcLength); break;
      case Measure::StraightLine:
        signed_gap = (referencePoint(other, other_spec) - referencePoint(self, self_spec)).norm();
        break;
      case Measure::Lateral: signed_gap = std::abs(self_foot.lateralOffset - other_foot.lateralOffset); break;
    }
  } else {
    const Footprint other_body = footprintOf(other, other_spec.length, other_spec.width);
    const Footprint self_body = footprintOf(self, self_spec.length, self_spec.width);
    const PathRelation relation =
        relateToPath(egoLane, road->laneWidthOf(concrete->ego.lane), other_body, self_body);
    self_ahead = relation.longitudinalDistance > 0.0;
    switch (trigger.measure) {
      case Measure::AlongLane: signed_gap = relation.longitudinalGap; break;
      // The shortest distance between the bodies (< 0 where they overlap).
      case Measure::StraightLine: signed_gap = footprintGap(self_body, other_body); break;
      // Between their sides across the Ego's lane (< 0 where they overlap sideways).
      case Measure::Lateral: signed_gap = relation.lateralGap; break;
    }
  }
  const double gap = std::max(signed_gap, 0.0);
  if (trigger.kind == TriggerSpec::Kind::Gap) return signed_gap;
  // Each one's speed along the line towards the other (> 0: it closes in; a road user driving
  // against the road closes in on one behind it in s, as oncoming traffic does).
  const auto along = [&](const VehicleState& state) {
    return state.speed * std::cos(state.heading - projectExtended(egoLane, state.position()).heading);
  };
  const double self_towards = self_ahead ? -along(self) : along(self);
  const double other_towards = self_ahead ? along(other) : -along(other);
  // Rear and front along the line (s); the front one heads for the rear one only where it
  // drives against the road, and only then is it the one whose headway is defined.
  const double rear_towards = self_ahead ? other_towards : self_towards;
  const double front_towards = self_ahead ? self_towards : other_towards;
  const bool front_against = self_ahead ? self_spec.againstRoad : other_spec.againstRoad;
  if (trigger.kind == TriggerSpec::Kind::Headway && trigger.directed) {
    // OpenSCENARIO's: the subject's to the other, undefined while the other is not ahead of it
    // (in the subject's direction of travel).
    const bool subject_in_front = (trigger.subject == owner) == self_ahead;
    const double towards = !subject_in_front ? rear_towards : front_against ? front_towards : 0.0;
    return towards > 0.1 ? gap / towards : kInf;
  }
  // The one that closes in (on a head-on approach both do: the faster one).
  const double follower = front_against ? std::max(rear_towards, front_towards) : rear_towards;
  if (trigger.kind == TriggerSpec::Kind::Headway) return follower > 0.1 ? gap / follower : kInf;
  const double closing = self_towards + other_towards;
  return closing > 1e-9 ? gap / closing : kInf;  // Ttc
}

/// A distance trigger's distance (m) from its subject's centre, or the nearest point of its body,
/// to its place: in a straight line, along the Ego's starting lane (arc lengths) or across it.
double ScriptedTraffic::Impl::distanceToPlace(const scenario::ConcreteTrigger& trigger, const VehicleState& ego) const {
  using Measure = scenario::TriggerSpec::Measure;
  const auto& spot = trigger.place;
  Vec2 place(spot.x, spot.y);
  if (spot.inPlane) {
    place = planePoint(spot, ego, 0.0);
  } else if (!spot.inFrame) {
    const Landing now = placeNow(spot, ego, 0.0);
    if (std::isnan(now.d)) {
      refuseLane(now, spot, fmt::format("the distance trigger of '{}': its position", idOf(trigger.subject)));
    }
    place = frame.point(now.s, now.d);
  }
  const VehicleState& subject = stateOf(trigger.subject, ego);
  const auto& spec = specOf(trigger.subject);
  const Vec2 origin = trigger.fromReferencePoint ? referencePoint(subject, spec) : subject.position();
  if (!trigger.fromBody && trigger.measure == Measure::StraightLine) return (origin - place).norm();
  // The place (and a centre or reference point) as a footprint of no extent: the gaps to it are
  // those from its point.
  const Footprint point{place, 0.0, 0.0, 0.0};
  const Footprint body = trigger.fromBody ? footprintOf(subject, spec.length, spec.width)
                                          : Footprint{origin, subject.heading, 0.0, 0.0};
  if (trigger.measure == Measure::StraightLine) return std::max(footprintGap(body, point), 0.0);
  const PathRelation relation = relateToPath(egoLane, road->laneWidthOf(concrete->ego.lane), point, body);
  return std::max(trigger.measure == Measure::AlongLane ? relation.longitudinalGap : relation.lateralGap, 0.0);
}

void ScriptedTraffic::Impl::trackProgress(const VehicleState& ego) {
  const double now = static_cast<double>(k) * step;
  travelled[0] += (ego.position() - lastEgo.position()).norm();
  lastEgo = ego;
  for (std::size_t u = 0; u < travelled.size(); ++u) {
    if (!std::isnan(atRoadEndSince[u])) continue;  // road users never reverse
    const VehicleState& state = u == 0 ? ego : states[u - 1];
    const scenario::ConcreteVehicle& spec = u == 0 ? concrete->ego : concrete->others[u - 1];
    const double s = frame.coordinates(state.position()).first;
    // Its front: ahead along the road, or behind where it drives against it (to the region's start).
    const bool at_end = spec.againstRoad ? s - 0.5 * spec.length <= regionStartS : s + 0.5 * spec.length >= regionEndS;
    if (at_end) atRoadEndSince[u] = now;
  }
}

/// Whether a trigger holds at the current instant (members of `all` and `any` alike): a rising
/// one only where its condition holds after a check at which it did not, a falling one where it
/// does not after a check at which it did. Asked again within the instant, it answers the same.
bool ScriptedTraffic::Impl::holds(const scenario::ConcreteTrigger& trigger, int owner,
                                  const VehicleState& ego) const {
  if (!trigger.rising && !trigger.falling) return conditionHolds(trigger, owner, ego);
  Edge& edge = edges[&trigger];
  if (edge.instant == k) return edge.fired;
  const bool held = conditionHolds(trigger, owner, ego);
  const bool changed = edge.checked && held != edge.held;
  edge.fired = changed && (held ? trigger.rising : trigger.falling);
  edge.checked = true;
  edge.held = held;
  edge.instant = k;
  return edge.fired;
}

/// Whether a condition holds at the current instant.
bool ScriptedTraffic::Impl::conditionHolds(const scenario::ConcreteTrigger& trigger, int owner,
                                           const VehicleState& ego) const {
  const double now = static_cast<double>(k) * step;
  const auto user = static_cast<std::size_t>(trigger.subject + 1);
  const auto member_holds = [&](const scenario::ConcreteTrigger& member) { return holds(member, owner, ego); };
  switch (trigger.kind) {
    // A moment's delay counts here for members of `all` (a later moment); at the top, fireTime adds it.
    case TriggerSpec::Kind::Time: return now + 1e-9 >= trigger.value + trigger.delay;
    case TriggerSpec::Kind::After: {
      const double end = awaitedEnd(trigger);
      return !std::isnan(end) && end + trigger.delay <= now + 1e-9;
    }
    case TriggerSpec::Kind::All: return std::all_of(trigger.members.begin(), trigger.members.end(), member_holds);
    case TriggerSpec::Kind::Any: return std::any_of(trigger.members.begin(), trigger.members.end(), member_holds);
    case TriggerSpec::Kind::Gap:
    case TriggerSpec::Kind::Headway:
    case TriggerSpec::Kind::Ttc: {
      // Exact, as these were before the *_at_least forms: a gap is no count reached through steps.
      // inf stands for undefined (the rear one stands; the two do not close in): it holds
      // neither bound, as an OpenSCENARIO condition on an undefined value is false.
      const double value = relationValue(trigger, owner, ego);
      return trigger.bound == TriggerSpec::Bound::AtMost ? value <= trigger.value
                                                         : std::isfinite(value) && value >= trigger.value;
    }
    case TriggerSpec::Kind::Speed: return withinBound(stateOf(trigger.subject, ego).speed, trigger);
    case TriggerSpec::Kind::RelativeSpeed:
      return withinBound(stateOf(trigger.subject, ego).speed - stateOf(trigger.reference, ego).speed, trigger);
    case TriggerSpec::Kind::Accel: return withinBound(stateOf(trigger.subject, ego).accel, trigger);
    case TriggerSpec::Kind::Travelled: return withinBound(travelled[user], trigger);
    case TriggerSpec::Kind::EndOfRoad:
      return !std::isnan(atRoadEndSince[user]) && withinBound(now - atRoadEndSince[user], trigger);
    case TriggerSpec::Kind::Distance: return withinBound(distanceToPlace(trigger, ego), trigger);
  }
  return false;
}

/// When a trigger fires as far as the current instant tells (NaN: not yet): a time or an
/// action's end exactly, `any` at its earliest member, any other at this instant; plus delays.
double ScriptedTraffic::Impl::fireTime(const scenario::ConcreteTrigger& trigger, int owner,
                                       const VehicleState& ego) const {
  if (trigger.kind == TriggerSpec::Kind::Time || trigger.kind == TriggerSpec::Kind::After) return momentOf(trigger);
  if (trigger.kind == TriggerSpec::Kind::Any) {
    double earliest = kNaN;
    for (const auto& member : trigger.members) {
      const double when = fireTime(member, owner, ego);
      if (!std::isnan(when) && !(when >= earliest)) earliest = when;
    }
    return earliest + trigger.delay;
  }
  return holds(trigger, owner, ego) ? static_cast<double>(k) * step + trigger.delay : kNaN;
}

/// Schedules action `a` at its trigger's fire time if that is earlier than what it has.
void ScriptedTraffic::Impl::offer(std::size_t a, const VehicleState& ego) {
  const auto& action = concrete->actions[a];
  const double when = fireTime(action.trigger, action.owner, ego);
  if (!std::isnan(when) && !(when >= scheduled[a])) scheduled[a] = when;
}

void ScriptedTraffic::Impl::fireTriggers(const VehicleState& ego) {
  for (std::size_t a = 0; a < concrete->actions.size(); ++a) {
    const auto kind = concrete->actions[a].trigger.kind;
    if (kind == TriggerSpec::Kind::After || kind == TriggerSpec::Kind::Time) continue;  // scheduled exactly
    if (!std::isnan(timings[a].start)) continue;  // started
    // Only an `any` can fire earlier than it already has (a member with a shorter delay).
    if (!std::isnan(scheduled[a]) && kind != TriggerSpec::Kind::Any) continue;
    offer(a, ego);
  }
}

/// The speed (m/s) a speed action of target kind `action.speedTarget` aims at, starting from `from`.
double ScriptedTraffic::Impl::speedTargetOf(const ConcreteAction& action, double from, const VehicleState& ego) const {
  double to = 0.0;
  switch (action.speedTarget) {
    case ActionSpec::SpeedTarget::Absolute: to = action.target; break;
    case ActionSpec::SpeedTarget::Relative: to = stateOf(action.speedReference, ego).speed + action.target; break;
    case ActionSpec::SpeedTarget::Factor: to = stateOf(action.speedReference, ego).speed * action.target; break;
    case ActionSpec::SpeedTarget::Delta: to = from + action.target; break;
  }
  return std::max(0.0, to);  // a relative target below 0 means: stop
}

/// Starts speed action `a` of `mover`: a transition to its target, or (continuous) tracking
/// the reference's speed, which ends a tracking action before it.
void ScriptedTraffic::Impl::startSpeedAction(std::size_t a, Mover& mover, Transition transition,
                                             const VehicleState& ego) {
  const auto& action = concrete->actions[a];
  transition.from = mover.nominalSpeed(transition.start, step);
  transition.to = speedTargetOf(action, transition.from, ego);
  transition.duration = durationOf(action, transition.from, transition.to);
  endIfUnderWay(mover.speedAction, transition.start, ego);  // replaced: it ends here
  mover.speed = transition;
  mover.speedAction = a;
  mover.tracking.reset();
  if (action.continuous) {
    mover.tracking = a;
    mover.trackedSpeed = transition.to;
  }
  // A continuous action runs until another speed action replaces it.
  timings[a] = {transition.start, action.continuous ? kInf : transition.end()};
  scheduleWaiters(a, ego);
}

/// Tracking actions take the speed their reference has at the current instant for the step
/// ahead (one step behind it, as every road user moves on what it sees at the instant).
void ScriptedTraffic::Impl::track(const VehicleState& ego) {
  for (Mover& mover : movers) {
    if (mover.tracking) mover.trackedSpeed = speedTargetOf(concrete->actions[*mover.tracking], 0.0, ego);
  }
}

/// Actions that may start again and have ended: their triggers are checked again from now on,
/// their edge conditions afresh (as esmini resets a trigger's conditions when it fires: the
/// first check after it never fires). Their start is cleared; their latest end stays in `timings`.
/// One started by a moment (a time, an action's end) that has come starts again now, as its
/// trigger still holds (as esmini restarts an Event whose start holds); its delay is not waited again.
void ScriptedTraffic::Impl::rearmEnded() {
  const double now = static_cast<double>(k) * step;
  for (std::size_t a = 0; a < timings.size(); ++a) {
    const bool ended = !std::isnan(timings[a].start) && timings[a].end <= now + 1e-9;
    if (!ended || starts[a] >= concrete->actions[a].repeat) continue;
    const auto& trigger = concrete->actions[a].trigger;
    timings[a].start = kNaN;
    scheduled[a] = kNaN;
    forgetEdges(trigger);
    if (trigger.kind == TriggerSpec::Kind::Time || trigger.kind == TriggerSpec::Kind::After) {
      const double moment = momentOf(trigger);
      if (!std::isnan(moment)) scheduled[a] = std::max(now, moment);
    }
  }
}

void ScriptedTraffic::Impl::forgetEdges(const scenario::ConcreteTrigger& trigger) const {
  if (trigger.rising || trigger.falling) edges[&trigger].checked = false;
  for (const auto& member : trigger.members) forgetEdges(member);
}

void ScriptedTraffic::Impl::activate(std::size_t a, const VehicleState& ego) {
  const auto& action = concrete->actions[a];
  const double t0 = scheduled[a];
  if (starts[a] == 1) firstEnds[a] = timings[a].end;  // an `after` keeps waiting for that one
  ++starts[a];
  endListed(a, ego);
  if (action.kind == ActionSpec::Kind::SetSpeed || action.kind == ActionSpec::Kind::Controller) {
    // The Ego's controller takes it (or the new controller drives) from t0 on; done at once.
    if (action.kind == ActionSpec::Kind::SetSpeed) egoSetSpeeds.emplace_back(t0, action.target);
    if (action.kind == ActionSpec::Kind::Controller) egoControllers.emplace_back(t0, a);
    timings[a] = {t0, t0};
    scheduleWaiters(a, ego);
    return;
  }
  if (action.kind == ActionSpec::Kind::Teleport) {
    if (action.owner < 0) teleportEgo(a, ego);
    else teleport(a, ego);
    return;
  }
  if (action.owner < 0) {
    activateEgoLateral(a, ego);
    return;
  }
  Mover& mover = movers[static_cast<std::size_t>(action.owner)];
  Transition transition;
  transition.start = t0;
  transition.shape = action.shape;
  if (action.kind == ActionSpec::Kind::Speed) {
    startSpeedAction(a, mover, transition, ego);
    return;
  }
  transition.from = mover.lateral ? mover.lateral->at(t0) : mover.d;
  if (laneChangeUnderWay(mover.lateralAction, t0)) mover.laneIndex = road->laneAt(transition.from);
  if (action.kind == ActionSpec::Kind::LaneChange) {
    const int target = laneChangeTarget(action, mover.laneIndex, ego, t0);
    mover.laneIndex = target;
    transition.to = road->laneOffset(target) + action.targetLaneOffset;
  } else {
    // Lateral offsets count from the current lane's centre, crossings from the starting lane's.
    transition.to = road->laneOffset(mover.laneIndex) + action.target;
  }
  // Checked before the run where its lane is known; after a relative teleport, here.
  if (action.kind != ActionSpec::Kind::LateralOffset && !onPavedGround(transition.to)) {
    const char* field = action.kind == ActionSpec::Kind::LaneChange ? "lane_change.offset" : "cross.to_offset";
    throw ConfigError(fmt::format("{}: {}.{}: at t = {:.1f} s it would end {:.2f} m left of the road's centre: "
                                  "expected a place on its lanes or shoulders",
                                  concrete->where(), action.where, field, t0, transition.to));
  }
  transition.duration = lateralDuration(action, transition, mover.speedAlong, concrete->where());
  endIfUnderWay(mover.lateralAction, t0, ego);
  mover.lateral = transition;
  mover.lateralAction = a;
  timings[a] = {t0, action.continuous ? kInf : transition.end()};  // a held offset ends where it is replaced
  scheduleWaiters(a, ego);
}

bool ScriptedTraffic::Impl::onPavedGround(double d) const {
  const auto& shape = concrete->logical->road;
  return d >= -(road->halfWidth() + shape.shoulderRight) - 1e-9 && d <= road->halfWidth() + shape.shoulderLeft + 1e-9;
}

/// Where teleport action `a` lands its road user when it starts: its place on the road, or relative
/// to a road user where that one is now (ds along the road from its centre; lanes from the lane
/// its centre is in, or dd across from its centre). On the road, or a ConfigError.
ScriptedTraffic::Impl::Landing ScriptedTraffic::Impl::landingOf(std::size_t a, const VehicleState& ego) const {
  const ConcreteAction& action = concrete->actions[a];
  Landing landing = placeNow(action.place, ego, scheduled[a] - static_cast<double>(k) * step);
  if (std::isnan(landing.d)) refuseLane(landing, action.place, action.where + ".teleport");
  if (action.place.inPlane) {
    // Its reference point lands there: its centre lies `reference_point` m behind it, along the
    // heading it lands with.
    const double facing = landingFacing(action.owner, ego);
    const double reference_point = specOf(action.owner).referencePoint;
    landing.s -= frame.sRate(landing.s, landing.d, reference_point * std::cos(facing));
    landing.d -= reference_point * std::sin(facing);
  }
  if (landing.s < 0.0 || landing.s > frame.length() || !onPavedGround(landing.d)) {
    throw ConfigError(fmt::format("{}: {}.teleport: it lands {:.1f} m along a road of {:.1f} m (lead-in and lead-out "
                                  "included), {:.2f} m left of its centre line: expected a place on its lanes or "
                                  "shoulders",
                                  concrete->where(), action.where, landing.s - regionStartS, frame.length(),
                                  landing.d));
  }
  return landing;
}

/// Where a place on the road lies: a fixed one, or one relative to a road user where that one
/// is `since` s after the current instant (moved on along the road at its speed: the next
/// instant's state is not known yet). A relative one on a lane the road does not have has that
/// lane and d NaN (the caller refuses it, refuseLane).
ScriptedTraffic::Impl::Landing ScriptedTraffic::Impl::placeNow(const scenario::ConcretePlace& place,
                                                               const VehicleState& ego, double since) const {
  if (!place.relative) return {regionStartS + place.s, road->laneOffset(place.lane) + place.offset, place.lane};
  if (place.inPlane) {
    const auto [s, d] = frame.coordinates(planePoint(place, ego, since));
    return {s, d, road->laneAt(d)};
  }
  const VehicleState& reference = stateOf(place.from, ego);
  const auto [s, d] = frame.coordinates(reference.position());
  const double speed_along = reference.speed * std::cos(reference.heading - frame.heading(s, d));
  Landing landing;
  landing.s = s + frame.sRate(s, d, speed_along) * since + place.s;
  // Lanes count from the lane its centre is in; beside the lanes (a shoulder), from the lane
  // that shoulder would be (esmini counts from the shoulder's lane id).
  const int own_lane = d < -road->halfWidth() ? -1 : d > road->halfWidth() ? road->lanes : road->laneAt(d);
  landing.lane = place.acrossFromCentre ? road->laneAt(d + place.offset) : own_lane + place.lane;
  if (landing.lane < 0 || landing.lane >= road->lanes) {
    landing.d = kNaN;
  } else {
    landing.d = place.acrossFromCentre ? d + place.offset : road->laneOffset(landing.lane) + place.offset;
  }
  return landing;
}

Vec2 ScriptedTraffic::Impl::planePoint(const scenario::ConcretePlace& place, const VehicleState& ego,
                                       double since) const {
  const VehicleState& reference = stateOf(place.from, ego);
  const Vec2 along = headingVector(reference.heading);
  const Vec2 left(-along.y(), along.x());
  const double ahead = reference.speed * since + specOf(place.from).referencePoint;  // of its centre, m
  const Vec2 offset = place.frameAxes ? Vec2(place.x, place.y) : Vec2(place.x * along + place.y * left);
  return reference.position() + ahead * along + offset;
}

void ScriptedTraffic::Impl::refuseLane(const Landing& landing, const scenario::ConcretePlace& place,
                                       const std::string& field) const {
  throw ConfigError(fmt::format("{}: {}.lanes: lane {} from the lane of '{}', expected a lane the road has (0 .. {})",
                                concrete->where(), field, landing.lane, idOf(place.from), road->lanes - 1));
}

/// A teleport: the road user lands on its place at the action's start t0 and drives on from
/// there in its direction (moving, it faces along its lane; standing, it keeps its heading to the
/// road). A speed or lateral action under way ends there: it keeps the speed it has, and stays
/// on its landing place across the road (as esmini ends the actions a teleport overrides). Its
/// state at the instant before t0 is put where the step from there (the mean of its speeds at
/// both instants) ends where it gets from its landing place by the next instant; the distance
/// it travels counts from there, not the jump.
void ScriptedTraffic::Impl::teleport(std::size_t a, const VehicleState& ego) {
  const auto& action = concrete->actions[a];
  const double t0 = scheduled[a];
  const auto o = static_cast<std::size_t>(action.owner);
  Mover& mover = movers[o];
  const Landing landing = landingOf(a, ego);
  const double facing = landingFacing(action.owner, ego);
  const double now = static_cast<double>(k) * step;
  const double speed_now = mover.speedAlong;
  const double speed_landing = speed_now + (mover.speedAt(k + 1, step) - speed_now) * (t0 - now) / step;
  holdSpeed(mover, t0, ego);
  endIfUnderWay(mover.lateralAction, t0, ego);
  mover.lateral.reset();
  const double speed_next = mover.speedAt(k + 1, step);
  const double after_landing = 0.5 * (speed_landing + speed_next) * (now + step - t0);  // m
  const double whole_step = 0.5 * (speed_now + speed_next) * step;                      // m
  const double direction = mover.spec->againstRoad ? -1.0 : 1.0;
  mover.d = landing.d;
  // sRate is linear in its speed: metres along its offset line to metres of s.
  mover.s = landing.s + direction * frame.sRate(landing.s, mover.d, after_landing - whole_step);
  mover.laneIndex = landing.lane;
  const Vec2 position = frame.point(mover.s, mover.d);
  mover.state.x = position.x();
  mover.state.y = position.y();
  mover.state.heading = wrapAngle(frame.heading(mover.s, mover.d) + facing);
  states[o] = mover.state;
  atRoadEndSince[o + 1] = kNaN;  // it may have left the road's end behind
  timings[a] = {t0, t0};
  scheduleWaiters(a, ego);
}

/// A teleport of the Ego: at the current instant it is put where it reaches its landing place at
/// the action's start t0 at its speed, facing along its lane (standing: keeping its heading to the
/// road), and its controller drives it on from there. The lane it keeps becomes the landing place
/// across the road (a lane change under way ends); the distance it travels counts from there.
void ScriptedTraffic::Impl::teleportEgo(std::size_t a, const VehicleState& ego) {
  const double t0 = scheduled[a];
  const Landing landing = landingOf(a, ego);
  const double facing = landingFacing(-1, ego);
  // m it drives from the current instant to t0, as m of s (sRate is linear in its speed)
  const double before = frame.sRate(landing.s, landing.d, ego.speed * (t0 - static_cast<double>(k) * step));
  const double s = landing.s - before;
  VehicleState placed = ego;
  const Vec2 position = frame.point(s, landing.d);
  placed.x = position.x();
  placed.y = position.y();
  placed.heading = wrapAngle(frame.heading(s, landing.d) + facing);
  egoPlaced = placed;
  // Its controller keeps the landing place from the current instant, where it is put.
  const double now = static_cast<double>(k) * step;
  egoLaterals.emplace_back(now, Transition{now, 0.0, landing.d, landing.d, TransitionShape::Step});
  egoLateralLane = landing.lane;
  endIfUnderWay(egoLateralAction, t0, ego);
  egoLateralAction.reset();
  lastEgo = placed;
  atRoadEndSince[0] = kNaN;  // it may have left the road's end behind
  timings[a] = {t0, t0};
  scheduleWaiters(a, ego);
}

double ScriptedTraffic::Impl::landingFacing(int owner, const VehicleState& ego) const {
  if (owner < 0) {
    if (ego.speed > 1e-9) return 0.0;
    const auto [s, d] = frame.coordinates(ego.position());
    return wrapAngle(ego.heading - frame.heading(s, d));
  }
  const Mover& mover = movers[static_cast<std::size_t>(owner)];
  if (mover.speedAlong > 1e-9) return mover.spec->againstRoad ? kPi : 0.0;
  return wrapAngle(mover.state.heading - frame.heading(mover.s, mover.d));  // its place in the lane frame
}

int ScriptedTraffic::Impl::egoLaneOf(const VehicleState& ego) const {
  return road->laneAt(road->laneOffset(concrete->ego.lane) + projectExtended(egoLane, ego.position()).lateralOffset);
}

int ScriptedTraffic::Impl::laneChangeTarget(const ConcreteAction& action, int own_lane, const VehicleState& ego,
                                            double t0) const {
  const auto target = static_cast<int>(std::lround(scenario::laneChangeTarget(action, own_lane, egoLaneOf(ego))));
  if (target < 0 || target >= road->lanes) {
    throw ConfigError(fmt::format("{}: {}.lane_change: at t = {:.1f} s that is lane {}, expected a lane the road has "
                                  "(0 .. {})",
                                  concrete->where(), action.where, t0, target, road->lanes - 1));
  }
  return target;
}

/// The Ego's lane_change and lateral_offset: the lane its controller keeps moves across the
/// road, from where the latest such move has put it (before the first: the centre of the lane
/// the Ego is in) to the target lane's centre or an offset from the current lane's, with the
/// action's shape and pace (a step jumps: the controller then gets there its own way).
void ScriptedTraffic::Impl::activateEgoLateral(std::size_t a, const VehicleState& ego) {
  const auto& action = concrete->actions[a];
  Transition transition;
  transition.start = scheduled[a];
  transition.shape = action.shape;
  if (egoLaterals.empty()) {
    egoLateralLane = egoLaneOf(ego);
    transition.from = road->laneOffset(egoLateralLane);
  } else {
    transition.from = egoLaterals.back().second.at(transition.start);
  }
  if (laneChangeUnderWay(egoLateralAction, transition.start)) egoLateralLane = road->laneAt(transition.from);
  if (action.kind == ActionSpec::Kind::LaneChange) {
    egoLateralLane = laneChangeTarget(action, egoLateralLane, ego, transition.start);
    transition.to = road->laneOffset(egoLateralLane) + action.targetLaneOffset;
  } else {
    transition.to = road->laneOffset(egoLateralLane) + action.target;
  }
  transition.duration =
      action.shape == TransitionShape::Step ? 0.0 : lateralDuration(action, transition, ego.speed, concrete->where());
  egoLaterals.emplace_back(transition.start, transition);
  endIfUnderWay(egoLateralAction, transition.start, ego);
  egoLateralAction = a;
  timings[a] = {transition.start, action.continuous ? kInf : transition.end()};
  scheduleWaiters(a, ego);
}

/// The end an `after` waits for (s): the end of its action's first run (a moment that stays
/// when the action runs again); with `last`, of its last run, once that has started. NaN before.
double ScriptedTraffic::Impl::awaitedEnd(const scenario::ConcreteTrigger& trigger) const {
  const auto a = static_cast<std::size_t>(trigger.action);
  if (trigger.lastRun) {
    // Its start is set after its count (activate): in between, its end is the run's before.
    const bool last_started = starts[a] == concrete->actions[a].repeat && !std::isnan(timings[a].start);
    return last_started ? timings[a].end : kNaN;
  }
  return starts[a] >= 2 ? firstEnds[a] : timings[a].end;
}

/// Once action `a` has started and its end is known (or has moved earlier: it was replaced): the
/// actions waiting for that end that have not started.
void ScriptedTraffic::Impl::scheduleWaiters(std::size_t a, const VehicleState& ego) {
  for (std::size_t b = 0; b < concrete->actions.size(); ++b) {
    const auto& trigger = concrete->actions[b].trigger;
    if (trigger.kind == TriggerSpec::Kind::After && trigger.action == static_cast<int>(a) &&
        std::isnan(timings[b].start)) {
      const double awaited = awaitedEnd(trigger);
      if (std::isfinite(awaited) && !(awaited + trigger.delay >= scheduled[b])) scheduled[b] = awaited + trigger.delay;
    } else if (trigger.kind == TriggerSpec::Kind::Any && std::isnan(timings[b].start)) {
      offer(b, ego);  // a member waiting for this action's end
    }
  }
}

void ScriptedTraffic::Impl::endIfUnderWay(const std::optional<std::size_t>& a, double t, const VehicleState& ego) {
  if (!a || !(timings[*a].start <= t + 1e-9) || !(timings[*a].end > t)) return;
  timings[*a].end = t;
  scheduleWaiters(*a, ego);
}

void ScriptedTraffic::Impl::holdSpeed(Mover& mover, double t, const VehicleState& ego) {
  if (!mover.speed && !mover.tracking) return;  // its scripted speed: no action to end
  const double held = mover.nominalSpeed(t, step);  // noise-free, as the action's speeds are
  mover.speed = Transition{t, 0.0, held, held, TransitionShape::Step};
  mover.tracking.reset();
  endIfUnderWay(mover.speedAction, t, ego);
}

void ScriptedTraffic::Impl::endListed(std::size_t a, const VehicleState& ego) {
  const double t = scheduled[a];
  for (const int listed : concrete->actions[a].ends) {
    const auto e = static_cast<std::size_t>(listed);
    if (!(timings[e].start <= t + 1e-9) || !(timings[e].end > t)) continue;  // not under way
    const int owner = concrete->actions[e].owner;
    if (owner < 0) {
      if (egoLateralAction != e) continue;  // the Ego's other actions end at once
      const double kept = egoLaterals.back().second.at(t);  // the lane its controller keeps stays there
      egoLaterals.emplace_back(t, Transition{t, 0.0, kept, kept, TransitionShape::Step});
      if (laneChangeUnderWay(egoLateralAction, t)) egoLateralLane = road->laneAt(kept);
      endIfUnderWay(egoLateralAction, t, ego);
      continue;
    }
    Mover& mover = movers[static_cast<std::size_t>(owner)];
    if (mover.speedAction == e) holdSpeed(mover, t, ego);
    if (mover.lateralAction == e && mover.lateral) {
      const double d = mover.lateral->at(t);
      if (laneChangeUnderWay(mover.lateralAction, t)) mover.laneIndex = road->laneAt(d);
      mover.lateral = Transition{t, 0.0, d, d, TransitionShape::Step};
      endIfUnderWay(mover.lateralAction, t, ego);
    }
  }
}

void ScriptedTraffic::Impl::activateDue(const VehicleState& ego) {
  const double next = static_cast<double>(k + 1) * step;
  // In order of their start (a chain of `after` triggers may start several in one step).
  for (;;) {
    std::size_t first = scheduled.size();
    for (std::size_t a = 0; a < scheduled.size(); ++a) {
      if (std::isnan(timings[a].start) && !std::isnan(scheduled[a]) && scheduled[a] <= next + 1e-9 &&
          (first == scheduled.size() || scheduled[a] < scheduled[first])) {
        first = a;
      }
    }
    if (first == scheduled.size()) return;
    // After a teleport of the Ego, the actions that start later in the step see it where it was put.
    activate(first, egoPlaced ? *egoPlaced : ego);
  }
}

VehicleState ScriptedTraffic::Impl::advancePurePursuit(Mover& mover) {
  // The script sets the speed at every instant; limits must not bend it. Curvature keeps
  // the Ego's bound, which lane keeping on the generated roads never reaches.
  VehicleLimits limits;
  limits.maxAccel = 1e6;
  limits.maxDecel = 1e6;
  Observation observation;
  observation.ego = mover.state;
  observation.lane = observeLane(mover.lane, mover.lane.project(mover.state.position()), mover.state,
                                  road->laneWidthOf(mover.laneIndex));
  Command command;
  command.accel = (mover.speedAt(k + 1, step) - mover.state.speed) / step;
  command.curvature = laneKeeping.curvature(observation);
  const auto& noise = mover.spec->headingNoise;
  const double disturbance = k < noise.size() ? noise[k] : 0.0;
  return advanceKinematic(mover.state, command, step, disturbance, limits);
}

VehicleState ScriptedTraffic::Impl::advanceExact(Mover& mover) {
  const double t1 = static_cast<double>(k + 1) * step;
  const double speed_along = mover.speedAt(k + 1, step);
  const double d1 = mover.lateral ? mover.lateral->at(t1) : mover.d;
  // s advances with the mean of the speeds at both instants (trapezoid, as the Ego's model),
  // measured along the line at the mean offset (on a bend, lanes differ in length).
  // Against the road (its heading pi off), s decreases; speeds are magnitudes either way.
  const double direction = mover.spec->againstRoad ? -1.0 : 1.0;
  mover.s += direction * frame.sRate(mover.s, 0.5 * (mover.d + d1), 0.5 * (mover.speedAlong + speed_along)) * step;
  mover.d = d1;
  mover.speedAlong = speed_along;
  const double lateral_rate = mover.lateral ? mover.lateral->rate(t1) : 0.0;
  const Vec2 velocity = frame.velocity(mover.s, mover.d, direction * speed_along, lateral_rate);
  const Vec2 position = frame.point(mover.s, mover.d);
  VehicleState next;
  next.x = position.x();
  next.y = position.y();
  next.speed = velocity.norm();
  // Standing still, it keeps the heading it had (a pedestrian that crossed faces across).
  next.heading = next.speed > 1e-9 ? headingOf(velocity) : mover.state.heading;
  next.accel = (next.speed - mover.state.speed) / step;
  return next;
}

ScriptedTraffic::ScriptedTraffic(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road)
    : impl_(std::make_unique<Impl>()) {
  impl_->concrete = &concrete;
  impl_->road = &road;
  impl_->init();
}

ScriptedTraffic::ScriptedTraffic(ScriptedTraffic&&) noexcept = default;
ScriptedTraffic& ScriptedTraffic::operator=(ScriptedTraffic&&) noexcept = default;
ScriptedTraffic::~ScriptedTraffic() = default;

const VehicleState& ScriptedTraffic::egoStart() const { return impl_->egoStart; }
std::size_t ScriptedTraffic::instant() const { return impl_->k; }
const std::vector<VehicleState>& ScriptedTraffic::states() const { return impl_->states; }
const std::vector<ScriptedTraffic::ActionTiming>& ScriptedTraffic::timings() const { return impl_->timings; }

const std::vector<std::string>& ScriptedTraffic::startOverlaps() const { return impl_->startOverlaps; }

namespace {
/// The value of the last started entry (start time, value) that has started by `time`: asked every
/// step, so searched from the end (a repeated action adds an entry each time it starts again).
template <typename Value>
std::optional<Value> lastStartedBy(const std::vector<std::pair<double, Value>>& started, double time) {
  for (auto it = started.rbegin(); it != started.rend(); ++it) {
    if (it->first <= time + 1e-9) return it->second;
  }
  return std::nullopt;
}
}  // namespace

std::vector<std::size_t> ScriptedTraffic::egoControllersStarted(double time, std::size_t first) const {
  std::vector<std::size_t> started;
  for (std::size_t i = first; i < impl_->egoControllers.size(); ++i) {
    if (impl_->egoControllers[i].first > time + 1e-9) break;
    started.push_back(impl_->egoControllers[i].second);
  }
  return started;
}

std::optional<double> ScriptedTraffic::egoSetSpeedAt(double time) const {
  return lastStartedBy(impl_->egoSetSpeeds, time);
}

const std::optional<VehicleState>& ScriptedTraffic::egoTeleported() const { return impl_->egoPlaced; }

std::optional<double> ScriptedTraffic::egoLaneOffsetAt(double time) const {
  const auto move = lastStartedBy(impl_->egoLaterals, time);
  if (!move) return std::nullopt;
  return move->at(time);
}

void ScriptedTraffic::step(const VehicleState& ego) {
  Impl& impl = *impl_;
  impl.egoPlaced.reset();
  if (impl.tracksProgress) impl.trackProgress(ego);
  impl.rearmEnded();
  impl.fireTriggers(ego);
  impl.track(ego);
  impl.activateDue(ego);
  for (std::size_t o = 0; o < impl.movers.size(); ++o) {
    Mover& mover = impl.movers[o];
    mover.state = mover.spec->purePursuit ? impl.advancePurePursuit(mover) : impl.advanceExact(mover);
    if (impl.tracksProgress) impl.travelled[o + 1] += (mover.state.position() - impl.states[o].position()).norm();
    impl.states[o] = mover.state;
  }
  ++impl.k;
}

bool ScriptedTraffic::pastRoadEnd(std::size_t other) const {
  const Mover& mover = impl_->movers.at(other);
  const double front = 0.5 * mover.spec->length;
  if (mover.spec->purePursuit) return mover.lane.project(mover.state.position()).arcLength + front >= mover.lane.length();
  // Against the road, its end is the road's start.
  if (mover.spec->againstRoad) return mover.s - front <= 0.0;
  return mover.s + front >= impl_->frame.length();
}

std::vector<std::vector<VehicleState>> plannedPaths(const scenario::ConcreteScenario& concrete,
                                                    const road::RoadGeometry& road) {
  ScriptedTraffic traffic(concrete, road);
  const EgoStandIn ego(concrete, road);
  const auto instants = static_cast<std::size_t>(concrete.steps()) + 1;
  std::vector<std::vector<VehicleState>> paths(concrete.others.size());
  for (auto& path : paths) path.reserve(instants);
  for (std::size_t k = 0; k < instants; ++k) {
    if (k > 0) traffic.step(ego.at(static_cast<double>(k - 1) * concrete.step()));
    for (std::size_t o = 0; o < paths.size(); ++o) paths[o].push_back(traffic.states()[o]);
  }
  for (auto& path : paths) {
    if (path.size() > 1) path[0].accel = path[1].accel;  // as fillAccelerationFromSpeed does for every track
  }
  return paths;
}

}  // namespace vsd::sim
