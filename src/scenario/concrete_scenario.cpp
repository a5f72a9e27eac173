#include "vsd/scenario/concrete_scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/core/geometry.hpp"
#include "vsd/core/random.hpp"

namespace vsd::scenario {

namespace {

double evaluateFinite(const Expression& expression, const std::vector<double>& values, const std::string& where,
                      const std::string& what) {
  const double value = expression.evaluate(values);
  if (!std::isfinite(value)) {
    throw ConfigError(fmt::format("{}: {} '{}' evaluates to {} (expected a finite number)", where, what,
                                  expression.text(), value));
  }
  return value;
}

double sampleDistribution(const Distribution& distribution, Rng& rng, const std::vector<double>& values) {
  double draw = 0.0;
  switch (distribution.kind) {
    case Distribution::Kind::Constant:
      draw = evaluateFinite(distribution.value, values, distribution.where, "value");
      break;
    case Distribution::Kind::Choice:
      draw = distribution.choices[static_cast<std::size_t>(rng.below(distribution.choices.size()))];
      break;
    case Distribution::Kind::Uniform: {
      const double lo = evaluateFinite(distribution.min, values, distribution.where, "min");
      const double hi = evaluateFinite(distribution.max, values, distribution.where, "max");
      if (lo > hi) {
        throw ConfigError(fmt::format("{}: min '{}' = {} > max '{}' = {} (expected min <= max)", distribution.where,
                                      distribution.min.text(), lo, distribution.max.text(), hi));
      }
      draw = rng.uniform(lo, hi);
      break;
    }
    case Distribution::Kind::Normal: {
      const double mean = evaluateFinite(distribution.mean, values, distribution.where, "mean");
      const double stddev = evaluateFinite(distribution.stddev, values, distribution.where, "std");
      if (stddev < 0.0) {
        throw ConfigError(fmt::format("{}: std '{}' = {} (expected >= 0)", distribution.where,
                                      distribution.stddev.text(), stddev));
      }
      draw = rng.normal(mean, stddev);
      if (distribution.hasBounds) {
        const double lo = evaluateFinite(distribution.min, values, distribution.where, "min");
        const double hi = evaluateFinite(distribution.max, values, distribution.where, "max");
        if (lo > hi) {
          throw ConfigError(fmt::format("{}: min {} > max {} (expected min <= max)", distribution.where, lo, hi));
        }
        // Truncation by resampling; bounded so that a far-away window cannot hang a run.
        int attempts = 0;
        while ((draw < lo || draw > hi) && ++attempts < 10000) draw = rng.normal(mean, stddev);
        if (draw < lo || draw > hi) {
          throw ConfigError(fmt::format("{}: normal({}, {}) almost never falls into [{}, {}]", distribution.where, mean,
                                        stddev, lo, hi));
        }
      }
      break;
    }
  }
  return draw * distribution.unitScale;
}

/// A lane index from an expression: a whole number of the road (relative ones from `base`).
int evaluateLane(const Expression& expression, const std::vector<double>& inputs, int base, int lanes,
                 const std::string& where, const std::string& field, std::uint64_t sample) {
  const double value = evaluateFinite(expression, inputs, where, field);
  const double lane = base + value;
  if (value != std::round(value) || lane < 0 || lane >= lanes) {
    throw ConfigError(fmt::format("{}.{}: got '{}' = {} in sample {}{}, expected a lane the road has (0 .. {})", where,
                                  field, expression.text(), formatValue(value), sample,
                                  base == 0 ? "" : fmt::format(" (lane {} from lane {})", lane, base), lanes - 1));
  }
  return static_cast<int>(lane);
}

ConcreteVehicle placeVehicle(const VehicleSpec& spec, const std::vector<double>& inputs, int ego_lane, int lanes,
                             std::uint64_t sample) {
  ConcreteVehicle vehicle;
  vehicle.id = spec.id;
  vehicle.type = spec.type;
  vehicle.length = spec.length;
  vehicle.width = spec.width;
  if (spec.typeCode) {
    const double code = evaluateFinite(*spec.typeCode, inputs, spec.where, "type");
    if (code != std::round(code) || code < 0 || code >= static_cast<double>(roadUserKinds().size())) {
      throw ConfigError(fmt::format("{}.type: got '{}' = {} in sample {}, expected the code of a road-user type "
                                    "(an input whose choices name types: {})",
                                    spec.where, spec.typeCode->text(), formatValue(code), sample, roadUserTypeList()));
    }
    vehicle.type = static_cast<RoadUserType>(static_cast<int>(code));
    if (!spec.lengthGiven) vehicle.length = roadUserKind(vehicle.type).length;
    if (!spec.widthGiven) vehicle.width = roadUserKind(vehicle.type).width;
  }
  vehicle.referencePoint = spec.referencePoint;
  if (std::abs(vehicle.referencePoint) > 0.5 * vehicle.length) {
    throw ConfigError(fmt::format("{}.reference_point: got {} m in sample {}, expected within half its length "
                                  "({} m) of its centre",
                                  spec.where, formatValue(vehicle.referencePoint), sample,
                                  formatValue(0.5 * vehicle.length)));
  }
  vehicle.lane = spec.lane;
  if (spec.laneExpression) {
    vehicle.lane = evaluateLane(*spec.laneExpression, inputs, spec.laneRelativeToEgo ? ego_lane : 0, lanes, spec.where,
                                spec.laneRelativeToEgo ? "relative_lane" : "lane", sample);
  }
  vehicle.along = spec.along;
  if (spec.along == VehicleSpec::Along::X) vehicle.x = evaluateFinite(spec.x, inputs, spec.where, "x");
  else vehicle.alongValue = evaluateFinite(spec.alongValue, inputs, spec.where, "s, ds or gap");
  vehicle.offset = evaluateFinite(spec.offset, inputs, spec.where, "offset");
  vehicle.heading = evaluateFinite(spec.headingDeg, inputs, spec.where, "heading_deg") * kPi / 180.0;
  vehicle.againstRoad = spec.againstRoad;
  vehicle.mayStartOverlapping = spec.mayStartOverlapping;
  if (vehicle.againstRoad) {
    // A drawn type is known per sample only (a fixed one is checked at load).
    if (!roadUserKind(vehicle.type).drivesInLanes) {
      throw ConfigError(fmt::format("{}.direction: against with type {} in sample {}, expected a vehicle (pedestrians "
                                    "and objects face by heading_deg)",
                                    spec.where, roadUserKind(vehicle.type).name, sample));
    }
    vehicle.heading = kPi;
  }
  vehicle.purePursuit = spec.keepsLaneByPurePursuit();
  return vehicle;
}

/// A speed that must be a finite number >= 0 m/s.
void checkSpeed(double speed, const std::string& where, const std::string& field, const std::string& text,
                std::uint64_t sample) {
  if (!(speed >= 0.0) || !std::isfinite(speed)) {
    throw ConfigError(fmt::format("{}.{}: got '{}' = {} m/s in sample {}, expected a finite speed >= 0 m/s", where,
                                  field, text, formatValue(speed), sample));
  }
}

/// The others' initial speeds: a speed profile (the paper's Co), or a speed absolute or
/// relative to the Ego's, constant until a speed action; plus speed noise at every instant.
void sampleSpeeds(const VehicleSpec& spec, const ConcreteScenario& concrete, Rng& vehicle_rng, ConcreteVehicle& other) {
  const auto& inputs = concrete.inputs;
  const double step = concrete.step();
  const int steps = concrete.steps();
  std::vector<std::pair<double, double>> phases;
  double initial = 0.0;
  if (spec.hasSpeedProfile) {
    for (std::size_t p = 0; p < spec.speedProfile.phases.size(); ++p) {
      const auto& phase = spec.speedProfile.phases[p];
      const double duration = evaluateFinite(phase.duration, inputs, spec.where, "phase duration");
      if (duration < 0.0) {
        throw ConfigError(fmt::format("{}: speed_profile.phases[{}].duration '{}' = {} (expected >= 0 s)", spec.where, p,
                                      phase.duration.text(), duration));
      }
      phases.emplace_back(duration, evaluateFinite(phase.accel, inputs, spec.where, "phase accel"));
    }
    initial = evaluateFinite(spec.speedProfile.initial, inputs, spec.where, "initial speed");
  } else {
    initial = spec.speed.evaluate(inputs) + (spec.speedRelativeToEgo ? concrete.ego.speed : 0.0);
    checkSpeed(initial, spec.where, spec.speedRelativeToEgo ? "relative_speed" : "speed", spec.speed.text(),
               concrete.index);
  }
  other.scriptedSpeed.resize(static_cast<std::size_t>(steps) + 1);
  other.speedNoise.resize(static_cast<std::size_t>(steps) + 1);
  for (int k = 0; k <= steps; ++k) {
    const double nominal = spec.hasSpeedProfile ? scriptedSpeedAt(initial, phases, k * step) : initial;
    const double noise = sampleDistribution(spec.speedNoise, vehicle_rng, inputs);
    other.scriptedSpeed[static_cast<std::size_t>(k)] = std::max(0.0, nominal + noise);
    other.speedNoise[static_cast<std::size_t>(k)] = noise;
  }
  other.speed = other.scriptedSpeed.front();
}

/// The stepper moves road users along the road at their speed: one facing off it (heading_deg)
/// must stand, or it would slide sideways to its heading and turn along the road at once. It
/// may cross (a cross action walks it at its own speed); speed actions may only hold it at 0.
void checkStandsWhileFacingOff(const ConcreteVehicle& other, const VehicleSpec& spec, const std::vector<double>& inputs,
                               std::uint64_t sample) {
  const double off_deg = std::remainder(other.heading, 2.0 * kPi) * 180.0 / kPi;
  if (other.againstRoad || std::abs(off_deg) < 1e-6) return;
  const auto moving = std::find_if(other.scriptedSpeed.begin(), other.scriptedSpeed.end(),
                                   [](double speed) { return speed > 0.0; });
  if (moving != other.scriptedSpeed.end()) {
    throw ConfigError(fmt::format("{}.speed: got {} m/s in sample {} for a {} facing {} deg off the road: road users "
                                  "move along the road, so one facing off it stands (speed 0; a cross action walks "
                                  "it across)",
                                  spec.where, formatValue(*moving), sample, roadUserKind(other.type).name,
                                  formatValue(off_deg)));
  }
  for (const ActionSpec& action : spec.actions) {
    if (action.kind != ActionSpec::Kind::Speed) continue;
    const bool holds_still =
        action.speedTarget == ActionSpec::SpeedTarget::Absolute && action.target.evaluate(inputs) == 0.0;
    if (!holds_still) {
      throw ConfigError(fmt::format("{}: a speed action for a {} facing {} deg off the road in sample {}: road users "
                                    "move along the road, so one facing off it stands (a cross action walks it across)",
                                    action.where, roadUserKind(other.type).name, formatValue(off_deg), sample));
    }
  }
}

/// Each lane's width: road.lane_width plus its noise (one draw for every lane), or road.lane_widths.
std::vector<double> realisedLaneWidths(const LogicalScenario& spec, const std::vector<double>& inputs, Rng& road_rng) {
  const std::string where = spec.sourceFile.string() + ": road.lane_width";
  std::vector<double> widths;
  if (spec.road.laneWidths.empty()) {
    const double width = evaluateFinite(spec.road.laneWidth, inputs, where, "lane_width") +
                         sampleDistribution(spec.road.laneWidthNoise, road_rng, inputs);
    widths.assign(static_cast<std::size_t>(spec.road.lanes), width);
  } else {
    for (const auto& width : spec.road.laneWidths) {
      widths.push_back(evaluateFinite(width, inputs, where + "s", "lane_widths"));
    }
  }
  for (const double width : widths) {
    if (!(width > 0.5 && width <= 50.0)) {
      throw ConfigError(fmt::format("{}{}: realised lane width {} m (expected 0.5 .. 50 m)", where,
                                    spec.road.laneWidths.empty() ? "" : "s", width));
    }
  }
  return widths;
}

/// A pedestrian stands, and crosses to, places on the road's lanes or shoulders.
/// `offset` m from lane `lane`'s centre lies on the lanes or shoulders; `what` says what lies
/// beyond them otherwise.
void checkOnPavedGround(const ConcreteScenario& concrete, int lane, double offset, const std::string& where,
                        const std::string& field, const std::string& what) {
  const auto& road = concrete.logical->road;
  const double half = halfRoadWidth(concrete.laneWidths);
  const double d = laneCentreOffset(lane, concrete.laneWidths) + offset;
  if (d < -(half + road.shoulderRight) - 1e-9 || d > half + road.shoulderLeft + 1e-9) {
    const bool right = d < 0.0;
    throw ConfigError(fmt::format(
        "{}.{}: got {} m from lane {}'s centre in sample {}, {:.2f} m beyond the road's {} edge where road.shoulders.{} "
        "is {} m: {} (expected a place on the lanes or shoulders)",
        where, field, formatValue(offset), lane, concrete.index, std::abs(d) - half, right ? "right" : "left",
        right ? "right" : "left", formatValue(right ? road.shoulderRight : road.shoulderLeft), what));
  }
}

constexpr const char* kNoPlaceToCross = "a pedestrian on a road without a place to cross";
constexpr const char* kOffTheRoad = "a road user off the road";

/// Index of action `id` in ConcreteScenario::actions (road user by road user, in file order).
int actionIndex(const LogicalScenario& logical, const std::string& id) {
  int index = 0;
  for (const auto& other : logical.others) {
    for (const auto& action : other.actions) {
      if (action.id == id) return index;
      ++index;
    }
  }
  for (const auto& action : logical.ego.actions) {
    if (action.id == id) return index;
    ++index;
  }
  return -1;
}

/// Index of road user `id`: -1 for the Ego, else into `others`.
int roadUserIndex(const LogicalScenario& logical, const std::string& id) {
  for (std::size_t o = 0; o < logical.others.size(); ++o) {
    if (logical.others[o].id == id) return static_cast<int>(o);
  }
  return -1;
}

/// A place relative to a road user (PositionSpec::from): ds, and lanes + offset or dd.
ConcretePlace evaluateRelativePlace(const PositionSpec& position, const std::string& where, const std::string& field,
                                    const LogicalScenario& logical, const ConcreteScenario& concrete) {
  ConcretePlace place;
  place.relative = true;
  place.from = roadUserIndex(logical, position.from);
  place.acrossFromCentre = position.acrossFromCentre;
  place.inPlane = position.inPlane;
  place.frameAxes = position.frameAxes;
  if (position.inPlane) {
    place.x = evaluateFinite(position.x, concrete.inputs, where, field + ".dx");
    place.y = evaluateFinite(position.y, concrete.inputs, where, field + ".dy");
    return place;
  }
  place.s = evaluateFinite(position.s, concrete.inputs, where, field + ".ds");
  place.offset = evaluateFinite(position.offset, concrete.inputs, where,
                                field + (position.acrossFromCentre ? ".dd" : ".offset"));
  if (position.acrossFromCentre) return place;
  const double lanes = evaluateFinite(position.lane, concrete.inputs, where, field + ".lanes");
  place.lane = static_cast<int>(std::lround(lanes));
  if (std::abs(lanes - place.lane) > 1e-9) {
    throw ConfigError(fmt::format("{}.{}.lanes: got {} in sample {}, expected a whole number of lanes", where, field,
                                  formatValue(lanes), concrete.index));
  }
  return place;
}

/// A place of `field` (e.g. "position" of a trigger, "teleport" of an action) at `where`, a
/// fixed one's lane checked against the road.
ConcretePlace evaluatePlace(const PositionSpec& position, const std::string& where, const std::string& field,
                            const LogicalScenario& logical, const ConcreteScenario& concrete) {
  if (!position.from.empty()) return evaluateRelativePlace(position, where, field, logical, concrete);
  ConcretePlace place;
  place.inFrame = position.inFrame;
  if (position.inFrame) {
    place.x = evaluateFinite(position.x, concrete.inputs, where, field + ".x");
    place.y = evaluateFinite(position.y, concrete.inputs, where, field + ".y");
    return place;
  }
  place.s = evaluateFinite(position.s, concrete.inputs, where, field + ".s");
  place.offset = evaluateFinite(position.offset, concrete.inputs, where, field + ".offset");
  const double lane = evaluateFinite(position.lane, concrete.inputs, where, field + ".lane");
  place.lane = static_cast<int>(std::lround(lane));
  if (std::abs(lane - place.lane) > 1e-9 || place.lane < 0 || place.lane >= logical.road.lanes) {
    throw ConfigError(fmt::format("{}.{}.lane: got {} in sample {}, expected a lane the road has (0 .. {})", where,
                                  field, formatValue(lane), concrete.index, logical.road.lanes - 1));
  }
  return place;
}

/// `owner`: the acting road user (index into `others`), whose quantities a condition without `of` measures.
ConcreteTrigger evaluateTrigger(const TriggerSpec& spec, int owner, const LogicalScenario& logical,
                                const ConcreteScenario& concrete) {
  ConcreteTrigger trigger;
  trigger.kind = spec.kind;
  trigger.bound = spec.bound;
  const bool composite = spec.kind == TriggerSpec::Kind::All || spec.kind == TriggerSpec::Kind::Any;
  if (spec.kind != TriggerSpec::Kind::After && !composite) {
    trigger.value = evaluateFinite(spec.value, concrete.inputs, spec.where, "value");
  }
  trigger.delay = evaluateFinite(spec.delay, concrete.inputs, spec.where, "delay");
  if ((trigger.value < 0.0 && !spec.signedValue()) || trigger.delay < 0.0) {
    throw ConfigError(fmt::format("{}: got value {} and delay {} s in sample {}, expected both >= 0", spec.where,
                                  formatValue(trigger.value), formatValue(trigger.delay), concrete.index));
  }
  trigger.reference = roadUserIndex(logical, spec.reference);
  trigger.subject = spec.subject.empty() ? owner : roadUserIndex(logical, spec.subject);
  trigger.directed = spec.kind == TriggerSpec::Kind::Headway && !spec.subject.empty();
  trigger.betweenReferencePoints = spec.betweenReferencePoints;
  trigger.measure = spec.measure;
  trigger.fromBody = spec.fromBody;
  trigger.fromReferencePoint = spec.fromReferencePoint;
  trigger.rising = spec.rising;
  trigger.falling = spec.falling;
  if (spec.kind == TriggerSpec::Kind::After) trigger.action = actionIndex(logical, spec.action);
  trigger.lastRun = spec.lastRun;
  if (spec.kind == TriggerSpec::Kind::Distance) {
    trigger.place = evaluatePlace(spec.position, spec.where, "position", logical, concrete);
  }
  for (const auto& member : spec.members) trigger.members.push_back(evaluateTrigger(member, owner, logical, concrete));
  return trigger;
}

ConcreteAction evaluateAction(const ActionSpec& spec, int owner, const LogicalScenario& logical,
                              const ConcreteScenario& concrete) {
  ConcreteAction action;
  action.id = spec.id;
  action.owner = owner;
  action.kind = spec.kind;
  action.trigger = evaluateTrigger(spec.trigger, owner, logical, concrete);
  action.shape = spec.shape;
  action.speedTarget = spec.speedTarget;
  action.speedReference = roadUserIndex(logical, spec.speedReference);
  action.continuous = spec.continuous;
  action.target = evaluateFinite(spec.target, concrete.inputs, spec.where, "target");
  action.targetLaneOffset = evaluateFinite(spec.targetLaneOffset, concrete.inputs, spec.where, "lane_change.offset");
  if (spec.kind == ActionSpec::Kind::Teleport) {
    action.place = evaluatePlace(spec.place, spec.where, "teleport", logical, concrete);
  }
  for (const auto& id : spec.ends) action.ends.push_back(actionIndex(logical, id));
  action.relativeToEgoLane = spec.relativeToEgoLane;
  action.toRoadLane = spec.toRoadLane;
  action.domains = spec.domains;
  action.pace = spec.pace;
  action.paceValue = evaluateFinite(spec.paceValue, concrete.inputs, spec.where, "pace");
  action.repeat = spec.repeat;
  action.where = spec.where;
  const bool duration = spec.pace == ActionSpec::Pace::Duration;
  const bool distance = spec.pace == ActionSpec::Pace::Distance;
  if (duration ? action.paceValue < 0.0 : !(action.paceValue > 0.0)) {
    throw ConfigError(fmt::format("{}: got a {} of {} in sample {}, expected {}", spec.where,
                                  duration ? "duration" : distance ? "distance" : "rate",
                                  formatValue(action.paceValue), concrete.index,
                                  duration ? "a duration >= 0 s" : distance ? "a distance > 0 m" : "a rate > 0"));
  }
  if (spec.kind == ActionSpec::Kind::Speed && spec.speedTarget == ActionSpec::SpeedTarget::Absolute) {
    checkSpeed(action.target, spec.where, "speed.target", spec.target.text(), concrete.index);
  }
  if (spec.kind == ActionSpec::Kind::SetSpeed) {
    checkSpeed(action.target, spec.where, "set_speed.target", spec.target.text(), concrete.index);
  }
  for (const auto& [name, expression] : spec.controller.params) {
    action.controllerParams.emplace_back(
        name, evaluateFinite(expression, concrete.inputs, spec.controller.where, "parameter " + name));
  }
  if (spec.kind == ActionSpec::Kind::Speed && spec.speedTarget == ActionSpec::SpeedTarget::Factor &&
      !(action.target >= 0.0)) {
    throw ConfigError(fmt::format("{}.speed.relative_factor: got {} in sample {}, expected a factor >= 0", spec.where,
                                  formatValue(action.target), concrete.index));
  }
  return action;
}

/// Lane changes, crossings and teleports of one road user, followed in file order, stay on the
/// road. After a teleport relative to a road user its lane is known only when it lands (the
/// simulation checks what depends on it then).
void checkLateralTargets(const ConcreteScenario& concrete, std::size_t first_action, const ConcreteVehicle& user) {
  const int lanes = concrete.logical->road.lanes;
  int lane = user.lane;
  bool lane_known = true;
  for (std::size_t a = first_action; a < concrete.actions.size(); ++a) {
    const auto& action = concrete.actions[a];
    if (action.kind == ActionSpec::Kind::Cross && lane_known) {
      checkOnPavedGround(concrete, lane, action.target, action.where, "cross.to_offset", kNoPlaceToCross);
    }
    if (action.kind == ActionSpec::Kind::Teleport) {
      if (action.place.relative) {
        lane_known = false;
        continue;
      }
      checkOnPavedGround(concrete, action.place.lane, action.place.offset, action.where, "teleport.offset",
                         kOffTheRoad);
      lane = action.place.lane;
      lane_known = true;
    }
    if (action.kind != ActionSpec::Kind::LaneChange) continue;
    const bool known = lane_known || action.toRoadLane || action.relativeToEgoLane;
    if (!known) {  // a number of lanes from where it landed: a whole one (the rest when it starts)
      if (action.target != std::round(action.target)) {
        throw ConfigError(fmt::format("{}.lane_change: got {} lanes in sample {}, expected a whole number",
                                      action.where, formatValue(action.target), concrete.index));
      }
      continue;
    }
    const int from = action.relativeToEgoLane ? concrete.ego.lane : lane;
    const double target = laneChangeTarget(action, lane, concrete.ego.lane);
    if (action.target != std::round(action.target) || target < 0 || target >= lanes) {
      const std::string what = action.toRoadLane
                                   ? fmt::format("lane {}", formatValue(action.target))
                                   : fmt::format("{} lanes from lane {}", formatValue(action.target), from);
      throw ConfigError(fmt::format("{}.lane_change: got {} in sample {}, that is lane {}; expected a lane the road "
                                    "has (0 .. {})",
                                    action.where, what, concrete.index, formatValue(target), lanes - 1));
    }
    lane = static_cast<int>(target);
    lane_known = true;
    checkOnPavedGround(concrete, lane, action.targetLaneOffset, action.where, "lane_change.offset", kOffTheRoad);
  }
}

}  // namespace

double laneChangeTarget(const ConcreteAction& action, int own_lane, int ego_lane) {
  if (action.toRoadLane) return action.target;
  return (action.relativeToEgoLane ? ego_lane : own_lane) + action.target;
}

double laneCentreOffset(int lane, int lanes, double lane_width) {
  // Lanes are spread symmetrically around the road centre; lane 0 is rightmost.
  return (static_cast<double>(lane) - 0.5 * static_cast<double>(lanes - 1)) * lane_width;
}

bool oneLaneWidth(const std::vector<double>& lane_widths) {
  return std::all_of(lane_widths.begin(), lane_widths.end(), [&](double w) { return w == lane_widths.front(); });
}

double laneCentreOffset(int lane, const std::vector<double>& lane_widths) {
  const int lanes = static_cast<int>(lane_widths.size());
  if (oneLaneWidth(lane_widths)) return laneCentreOffset(lane, lanes, lane_widths.front());
  double right_edge = -halfRoadWidth(lane_widths);
  for (int i = 0; i < lane; ++i) right_edge += lane_widths[static_cast<std::size_t>(i)];
  return right_edge + 0.5 * lane_widths[static_cast<std::size_t>(lane)];
}

double halfRoadWidth(const std::vector<double>& lane_widths) {
  if (lane_widths.empty()) return 0.0;
  if (oneLaneWidth(lane_widths)) return 0.5 * lane_widths.front() * static_cast<double>(lane_widths.size());
  double total = 0.0;
  for (const double width : lane_widths) total += width;
  return 0.5 * total;
}

int laneAtOffset(double offset, const std::vector<double>& lane_widths) {
  double left_edge = -halfRoadWidth(lane_widths);
  for (std::size_t lane = 0; lane + 1 < lane_widths.size(); ++lane) {
    left_edge += lane_widths[lane];
    if (offset < left_edge) return static_cast<int>(lane);
  }
  return static_cast<int>(lane_widths.size()) - 1;
}

std::string ConcreteScenario::where() const {
  return fmt::format("{}: sample {}", logical->sourceFile.string(), index);
}

double scriptedSpeedAt(double initial, const std::vector<std::pair<double, double>>& duration_accel_phases, double t) {
  double speed = initial;
  double phase_start = 0.0;
  for (const auto& [duration, accel] : duration_accel_phases) {
    if (t <= phase_start) break;
    const double active = std::min(t, phase_start + duration) - phase_start;
    // Braking ends at standstill (vehicles do not reverse); a later phase may start again.
    speed = std::max(0.0, speed + accel * active);
    phase_start += duration;
  }
  return std::max(speed, 0.0);
}

ConcreteScenario sampleConcreteScenario(const std::shared_ptr<const LogicalScenario>& logical, std::uint64_t seed,
                                        std::uint64_t index) {
  const LogicalScenario& spec = *logical;
  ConcreteScenario concrete;
  concrete.logical = logical;
  concrete.seed = seed;
  concrete.index = index;

  Rng input_rng = Rng::derive(seed, index, RandomStream::Inputs);
  concrete.inputs.assign(spec.inputs.size(), 0.0);
  for (std::size_t i = 0; i < spec.inputs.size(); ++i) {
    concrete.inputs[i] = sampleDistribution(spec.inputs[i].distribution, input_rng, concrete.inputs);
  }
  const auto& inputs = concrete.inputs;

  Rng road_rng = Rng::derive(seed, index, RandomStream::RoadNoise);
  concrete.centreNoise.resize(static_cast<std::size_t>(spec.road.points));
  for (auto& noise : concrete.centreNoise) noise = sampleDistribution(spec.road.centreNoise, road_rng, inputs);
  concrete.laneWidths = realisedLaneWidths(spec, inputs, road_rng);

  const int steps = spec.steps();
  Rng vehicle_rng = Rng::derive(seed, index, RandomStream::VehicleNoise);
  concrete.ego = placeVehicle(spec.ego, inputs, 0, spec.road.lanes, index);
  concrete.ego.speed = spec.ego.speed.evaluate(inputs);
  checkSpeed(concrete.ego.speed, spec.ego.where, "speed", spec.ego.speed.text(), index);
  concrete.ego.headingNoise.resize(static_cast<std::size_t>(steps));
  for (auto& noise : concrete.ego.headingNoise) noise = sampleDistribution(spec.ego.headingNoise, vehicle_rng, inputs);
  // The others' heading noise has its own stream: adding it leaves every other draw as it was.
  Rng heading_rng = Rng::derive(seed, index, RandomStream::OtherHeadingNoise);

  for (const auto& other_spec : spec.others) {
    ConcreteVehicle other = placeVehicle(other_spec, inputs, concrete.ego.lane, spec.road.lanes, index);
    for (std::size_t o = 0; o < concrete.others.size(); ++o) {
      if (spec.others[o].id == other_spec.alongFrom) other.alongFrom = static_cast<int>(o);
    }
    sampleSpeeds(other_spec, concrete, vehicle_rng, other);
    checkStandsWhileFacingOff(other, other_spec, inputs, index);
    other.headingNoise.resize(static_cast<std::size_t>(steps));
    for (auto& noise : other.headingNoise) noise = sampleDistribution(other_spec.headingNoise, heading_rng, inputs);
    if (other.type == RoadUserType::Pedestrian) {
      checkOnPavedGround(concrete, other.lane, other.offset, other_spec.where, "offset", kNoPlaceToCross);
    }
    concrete.others.push_back(std::move(other));
  }
  for (std::size_t o = 0; o < spec.others.size(); ++o) {
    const std::size_t first_action = concrete.actions.size();
    for (const auto& action : spec.others[o].actions) {
      concrete.actions.push_back(evaluateAction(action, static_cast<int>(o), spec, concrete));
    }
    checkLateralTargets(concrete, first_action, concrete.others[o]);
  }
  // The Ego's actions come last (actionIndex counts them so).
  const std::size_t first_ego_action = concrete.actions.size();
  for (const auto& action : spec.ego.actions) concrete.actions.push_back(evaluateAction(action, -1, spec, concrete));
  checkLateralTargets(concrete, first_ego_action, concrete.ego);
  for (const auto& [name, expression] : spec.ego.controller.params) {
    concrete.controllerParams.emplace_back(
        name, evaluateFinite(expression, inputs, spec.ego.controller.where, "parameter " + name));
  }
  concrete.controllerActiveFrom = evaluateFinite(spec.ego.controller.activeFrom, inputs, spec.ego.controller.where,
                                                 "active_from");
  if (concrete.controllerActiveFrom < 0.0) {
    throw ConfigError(fmt::format("{}: active_from: got {} s in sample {}, expected a time >= 0 s",
                                  spec.ego.controller.where, formatValue(concrete.controllerActiveFrom), index));
  }
  return concrete;
}

}  // namespace vsd::scenario
