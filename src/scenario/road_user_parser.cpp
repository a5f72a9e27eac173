// Parsing of `vehicles`: the Ego, the other road users, their actions and triggers
// (docs/scenario-language.md).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <regex>
#include <set>

#include "parsing.hpp"
#include "vsd/core/error.hpp"

namespace vsd::scenario::detail {

bool isIdentifier(const std::string& name) {
  static const std::regex pattern("[A-Za-z][A-Za-z0-9_]*");
  return std::regex_match(name, pattern);
}

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

/// Exactly one of `keys` is present in `node`: returns it ("" when none and !required).
std::string oneOf(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                  const std::vector<std::string>& keys, bool required) {
  std::string found;
  for (const auto& key : keys) {
    if (!node[key]) continue;
    if (!found.empty()) {
      reader.fail(node[key], field + "." + key, fmt::format("'{}' and '{}' exclude each other", found, key));
    }
    found = key;
  }
  if (found.empty() && required) {
    reader.fail(node, field, fmt::format("needs one of: {}", fmt::join(keys, ", ")));
  }
  return found;
}

Expression optionalExpression(const YamlReader& reader, const YAML::Node& node, const std::string& key,
                              const std::string& field, const std::vector<std::string>& inputs, double fallback) {
  return node[key] ? reader.expression(node[key], field + "." + key, inputs) : Expression::constant(fallback);
}

void parseType(const YamlReader& reader, const YAML::Node& node, const std::string& field,
               const std::vector<std::string>& inputs, VehicleSpec& vehicle) {
  if (node["type"]) {
    const std::string name = reader.scalar(node["type"], field + ".type");
    if (const auto type = findRoadUserType(name)) {
      vehicle.type = *type;
    } else {
      // An expression over inputs: the type drawn per concrete scenario (its code).
      const Expression code = reader.expression(node["type"], field + ".type", inputs);
      if (code.isConstant() || inputs.empty()) {
        throw ConfigError::field(reader.where(node["type"], field + ".type"), field + ".type", name,
                                 "one of " + roadUserTypeList() + ", or an input whose choices name types");
      }
      vehicle.typeCode = code;
    }
  }
  const RoadUserKind& kind = roadUserKind(vehicle.type);
  vehicle.lengthGiven = static_cast<bool>(node["length"]);
  vehicle.widthGiven = static_cast<bool>(node["width"]);
  vehicle.length = reader.number(node, "length", field + ".length", kind.length);
  vehicle.width = reader.number(node, "width", field + ".width", kind.width);
  if (!(vehicle.length > 0.0 && vehicle.length <= 100.0) || !(vehicle.width > 0.0 && vehicle.width <= 20.0)) {
    reader.fail(node, field, "expected a length in (0, 100] m and a width in (0, 20] m");
  }
  vehicle.referencePoint = reader.number(node, "reference_point", field + ".reference_point", 0.0);
  // Within half its length: checked per sample (a drawn type sets the length).
  if (!std::isfinite(vehicle.referencePoint)) {
    reader.fail(node["reference_point"], field + ".reference_point", "expected a finite number of m from its centre");
  }
}

/// x | s | ds, lane | relative_lane, offset, heading_deg.
void parsePlacement(const YamlReader& reader, const YAML::Node& node, const std::string& field, bool is_ego,
                    const std::vector<std::string>& inputs, const LogicalScenario& scenario, VehicleSpec& vehicle) {
  std::vector<std::string> along_keys = {"x", "s"};
  if (!is_ego) along_keys.insert(along_keys.end(), {"ds", "gap"});
  const std::string along = oneOf(reader, node, field, along_keys, true);
  if (along == "x") {
    vehicle.along = VehicleSpec::Along::X;
    vehicle.x = reader.expression(node["x"], field + ".x", inputs);
    if (scenario.road.shape != RoadSpec::Shape::Polynomial) {
      reader.fail(node["x"], field + ".x", "x places a road user on a polynomial road; arc and polyline roads take 's' or 'ds'");
    }
  } else {
    vehicle.along = along == "s"    ? VehicleSpec::Along::S
                    : along == "ds" ? VehicleSpec::Along::EgoRelative
                                    : VehicleSpec::Along::EgoGap;
    vehicle.alongValue = reader.expression(node[along], field + "." + along, inputs);
  }
  if (node["from"]) {
    if (along != "ds" && along != "gap") reader.fail(node["from"], field + ".from", "'from' goes with 'ds' or 'gap'");
    vehicle.alongFrom = reader.scalar(node["from"], field + ".from");
    const bool earlier = std::any_of(scenario.others.begin(), scenario.others.end(),
                                     [&](const VehicleSpec& other) { return other.id == vehicle.alongFrom; });
    if (vehicle.alongFrom != "ego" && !earlier) {
      std::vector<std::string> ids = {"ego"};
      for (const auto& other : scenario.others) ids.push_back(other.id);
      throw ConfigError::field(reader.where(node["from"], field + ".from"), field + ".from", vehicle.alongFrom,
                               fmt::format("a road user listed before this one: {}", fmt::join(ids, ", ")));
    }
  }
  const std::string lane_key = oneOf(reader, node, field, is_ego ? std::vector<std::string>{"lane"}
                                                                 : std::vector<std::string>{"lane", "relative_lane"},
                                     false);
  const bool constant_lane =
      lane_key == "lane" && reader.expression(node["lane"], field + ".lane", inputs).isConstant();
  if (constant_lane) {
    vehicle.lane = reader.integer(node, "lane", field + ".lane", 0, 0);
    if (vehicle.lane >= scenario.road.lanes) {
      throw ConfigError::field(reader.where(node["lane"], field + ".lane"), field + ".lane",
                               std::to_string(vehicle.lane),
                               fmt::format("a lane index below road.lanes = {}", scenario.road.lanes));
    }
  } else if (!lane_key.empty()) {
    vehicle.laneExpression = reader.expression(node[lane_key], field + "." + lane_key, inputs);
    vehicle.laneRelativeToEgo = lane_key == "relative_lane";
  }
  vehicle.offset = optionalExpression(reader, node, "offset", field, inputs, 0.0);
  if (node["heading_deg"]) {
    if (roadUserKind(vehicle.type).drivesInLanes) {
      reader.fail(node["heading_deg"], field + ".heading_deg",
                  "a vehicle heads along its lane; heading_deg is for pedestrians and stationary objects");
    }
    vehicle.headingDeg = reader.expression(node["heading_deg"], field + ".heading_deg", inputs);
  }
}

void requireNonNegative(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const Expression& value, bool strictly_positive, const std::string& unit);

/// `in_action`: a controller action's, which may name the domains it drives.
void parseController(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                     const std::vector<std::string>& inputs, ControllerSpec& controller, bool in_action = false) {
  controller.where = reader.where(node, field);
  std::set<std::string> keys = {"name", "library", "params", "active_from"};
  if (in_action) keys.insert("domains");
  reader.checkKeys(node, field, keys);
  if (node["active_from"]) {
    controller.activeFrom = reader.expression(node["active_from"], field + ".active_from", inputs);
    requireNonNegative(reader, node["active_from"], field + ".active_from", controller.activeFrom, false, "s");
  }
  if (!node["name"]) reader.fail(node, field, "missing 'name' (a built-in controller or one exported by 'library')");
  controller.name = reader.scalar(node["name"], field + ".name");
  if (node["library"]) controller.library = reader.scalar(node["library"], field + ".library");
  if (const auto params = node["params"]) {
    reader.requireMap(params, field + ".params");
    for (const auto& entry : params) {
      const auto key = entry.first.as<std::string>();
      controller.params.emplace_back(key, reader.expression(entry.second, field + ".params." + key, inputs));
    }
  }
}

/// `heading_noise_deg`: the paper's per-step orientation variation (degrees in the YAML).
void parseHeadingNoise(const YamlReader& reader, const YAML::Node& vehicle, const std::string& field,
                       const std::vector<std::string>& inputs, VehicleSpec& spec) {
  if (!vehicle["heading_noise_deg"]) return;
  spec.headingNoise = reader.distribution(vehicle["heading_noise_deg"], field + ".heading_noise_deg", inputs);
  spec.headingNoise.unitScale = kDegree;
  if (!spec.headingNoise.isZero() && !roadUserKind(spec.type).drivesInLanes) {
    reader.fail(vehicle["heading_noise_deg"], field + ".heading_noise_deg",
                fmt::format("a heading disturbance needs a vehicle that keeps a lane, not a {}",
                            roadUserKind(spec.type).name));
  }
}

/// `direction`: along (default) or against the road's direction (oncoming traffic, or an
/// overtaker on the other side's lane). After the type and the heading noise.
void parseDirection(const YamlReader& reader, const YAML::Node& item, const std::string& field, VehicleSpec& other) {
  const YAML::Node node = item["direction"];
  if (!node) return;
  const std::string direction = reader.scalar(node, field + ".direction");
  if (direction != "along" && direction != "against") {
    throw ConfigError::field(reader.where(node, field + ".direction"), field + ".direction", direction,
                             "along or against (the road's direction)");
  }
  other.againstRoad = direction == "against";
  if (!other.againstRoad) return;
  if (!other.typeCode && !roadUserKind(other.type).drivesInLanes) {
    reader.fail(node, field + ".direction",
                fmt::format("a {} does not drive in a lane: pedestrians and objects face by heading_deg",
                            roadUserKind(other.type).name));
  }
  if (other.keepsLaneByPurePursuit()) {
    reader.fail(node, field + ".direction",
                "a road user with heading_noise_deg keeps its lane by pure pursuit along the road; one driving "
                "against it moves in the lane frame (drop heading_noise_deg)");
  }
}

void parseSpeedProfile(const YamlReader& reader, const YAML::Node& profile, const std::string& field,
                       const std::vector<std::string>& inputs, VehicleSpec& other) {
  reader.checkKeys(profile, field, {"initial", "phases"});
  if (!profile["initial"]) reader.fail(profile, field, "missing 'initial' (m/s)");
  other.hasSpeedProfile = true;
  other.speedProfile.initial = reader.expression(profile["initial"], field + ".initial", inputs);
  const auto phases = profile["phases"];
  if (!phases) return;
  if (!phases.IsSequence()) reader.fail(phases, field + ".phases", "expected a list of phases");
  for (std::size_t p = 0; p < phases.size(); ++p) {
    const std::string phase_field = fmt::format("{}.phases[{}]", field, p);
    reader.checkKeys(phases[p], phase_field, {"duration", "accel"});
    if (!phases[p]["duration"] || !phases[p]["accel"]) {
      reader.fail(phases[p], phase_field, "needs 'duration' (s) and 'accel' (m/s^2)");
    }
    SpeedPhase phase;
    phase.duration = reader.expression(phases[p]["duration"], phase_field + ".duration", inputs);
    phase.accel = reader.expression(phases[p]["accel"], phase_field + ".accel", inputs);
    if (phase.duration.isConstant() && phase.duration.evaluate({}) < 0.0) {
      throw ConfigError::field(reader.where(phases[p]["duration"], phase_field + ".duration"),
                               phase_field + ".duration", phase.duration.text(), "a duration >= 0 s");
    }
    other.speedProfile.phases.push_back(std::move(phase));
  }
}

/// A constant that must be a finite number >= 0 (or > 0): checked where it is read.
void requireNonNegative(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const Expression& value, bool strictly_positive, const std::string& unit) {
  if (!value.isConstant()) return;
  const double v = value.evaluate({});
  if (!(strictly_positive ? v > 0.0 : v >= 0.0)) {
    throw ConfigError::field(reader.where(node, field), field, value.text(),
                             fmt::format("a number {} 0 {}", strictly_positive ? ">" : ">=", unit));
  }
}

/// A trigger's kinds: key, kind, bound, unit of its value (empty: the value may be negative).
struct TriggerKey {
  const char* key;
  TriggerSpec::Kind kind;
  TriggerSpec::Bound bound;
  const char* unit;
};
constexpr TriggerKey kTriggerKeys[] = {
    {"time", TriggerSpec::Kind::Time, TriggerSpec::Bound::AtLeast, "s"},
    {"gap", TriggerSpec::Kind::Gap, TriggerSpec::Bound::AtMost, "m"},
    {"headway", TriggerSpec::Kind::Headway, TriggerSpec::Bound::AtMost, "s"},
    {"ttc", TriggerSpec::Kind::Ttc, TriggerSpec::Bound::AtMost, "s"},
    {"gap_at_least", TriggerSpec::Kind::Gap, TriggerSpec::Bound::AtLeast, "m"},
    {"headway_at_least", TriggerSpec::Kind::Headway, TriggerSpec::Bound::AtLeast, "s"},
    {"ttc_at_least", TriggerSpec::Kind::Ttc, TriggerSpec::Bound::AtLeast, "s"},
    {"after", TriggerSpec::Kind::After, TriggerSpec::Bound::AtLeast, ""},
    {"speed_at_least", TriggerSpec::Kind::Speed, TriggerSpec::Bound::AtLeast, "m/s"},
    {"speed_at_most", TriggerSpec::Kind::Speed, TriggerSpec::Bound::AtMost, "m/s"},
    {"relative_speed_at_least", TriggerSpec::Kind::RelativeSpeed, TriggerSpec::Bound::AtLeast, ""},
    {"relative_speed_at_most", TriggerSpec::Kind::RelativeSpeed, TriggerSpec::Bound::AtMost, ""},
    {"accel_at_least", TriggerSpec::Kind::Accel, TriggerSpec::Bound::AtLeast, ""},
    {"accel_at_most", TriggerSpec::Kind::Accel, TriggerSpec::Bound::AtMost, ""},
    {"travelled", TriggerSpec::Kind::Travelled, TriggerSpec::Bound::AtLeast, "m"},
    {"distance_at_most", TriggerSpec::Kind::Distance, TriggerSpec::Bound::AtMost, "m"},
    {"distance_at_least", TriggerSpec::Kind::Distance, TriggerSpec::Bound::AtLeast, "m"},
    {"end_of_road", TriggerSpec::Kind::EndOfRoad, TriggerSpec::Bound::AtLeast, "s"},
    {"all", TriggerSpec::Kind::All, TriggerSpec::Bound::AtLeast, ""},
    {"any", TriggerSpec::Kind::Any, TriggerSpec::Bound::AtLeast, ""},
};

bool isRelation(TriggerSpec::Kind kind) {
  return kind == TriggerSpec::Kind::Gap || kind == TriggerSpec::Kind::Headway || kind == TriggerSpec::Kind::Ttc ||
         kind == TriggerSpec::Kind::RelativeSpeed;
}
bool hasSubject(TriggerSpec::Kind kind) {
  return kind != TriggerSpec::Kind::Time && kind != TriggerSpec::Kind::After && kind != TriggerSpec::Kind::All &&
         kind != TriggerSpec::Kind::Any && kind != TriggerSpec::Kind::Gap &&
         kind != TriggerSpec::Kind::Ttc;
}

/// `position: {s, lane[, offset]}` or `{x, y}`.
void parseRelativePlace(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const std::vector<std::string>& inputs, PositionSpec& place);

/// A distance trigger's place: `{s, lane[, offset]}`, `{x, y}`, or relative to a road user
/// (`{from, ds, lanes[, offset]}` or `{from, ds, dd}`: it moves with that road user).
void parsePosition(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                   const std::vector<std::string>& inputs, PositionSpec& position) {
  reader.requireMap(node, field);
  if (node["from"]) {
    reader.checkKeys(node, field, {"from", "ds", "lanes", "offset", "dd", "dx", "dy", "axes"});
    parseRelativePlace(reader, node, field, inputs, position);
    return;
  }
  reader.checkKeys(node, field, {"s", "lane", "offset", "x", "y"});
  position.inFrame = static_cast<bool>(node["x"]) || static_cast<bool>(node["y"]);
  const std::vector<std::string> keys = position.inFrame ? std::vector<std::string>{"x", "y"}
                                                         : std::vector<std::string>{"s", "lane"};
  for (const auto& key : keys) {
    if (!node[key]) reader.fail(node, field, "expected {s, lane[, offset]} along the road or {x, y} in the scenario frame");
  }
  if (position.inFrame && (node["s"] || node["lane"] || node["offset"])) {
    reader.fail(node, field, "expected {s, lane[, offset]} or {x, y}, not both");
  }
  if (position.inFrame) {
    position.x = reader.expression(node["x"], field + ".x", inputs);
    position.y = reader.expression(node["y"], field + ".y", inputs);
    return;
  }
  position.s = reader.expression(node["s"], field + ".s", inputs);
  position.lane = reader.expression(node["lane"], field + ".lane", inputs);
  position.offset = optionalExpression(reader, node, "offset", field, inputs, 0.0);
}

/// The value of `between` or `measure`, which go with gap, headway and ttc only: `first` (the
/// default) or `second`.
bool secondOf(const YamlReader& reader, const YAML::Node& node, const std::string& field, const TriggerSpec& trigger,
              const std::string& first, const std::string& second) {
  if (trigger.kind != TriggerSpec::Kind::Gap && trigger.kind != TriggerSpec::Kind::Headway &&
      trigger.kind != TriggerSpec::Kind::Ttc) {
    reader.fail(node, field, fmt::format("'{}' goes with gap, headway and ttc (and their _at_least forms)",
                                         field.substr(field.rfind('.') + 1)));
  }
  const std::string value = reader.scalar(node, field);
  if (value != first && value != second) {
    throw ConfigError::field(reader.where(node, field), field, value, first + " or " + second);
  }
  return value == second;
}

/// `measure` of a gap, headway, ttc or distance: along_lane, straight_line, or (gaps and
/// distances only) lateral.
void parseMeasure(const YamlReader& reader, const YAML::Node& node, const std::string& field, TriggerSpec& trigger) {
  const std::string value = reader.scalar(node, field);
  const bool distance = trigger.kind == TriggerSpec::Kind::Distance;
  if (value == "lateral") {
    if (trigger.kind != TriggerSpec::Kind::Gap && !distance) {
      reader.fail(node, field,
                  "'measure: lateral' goes with gap, gap_at_least and the distance triggers (across the lane)");
    }
    trigger.measure = TriggerSpec::Measure::Lateral;
    return;
  }
  if (value != "along_lane" && value != "straight_line") {
    throw ConfigError::field(reader.where(node, field), field, value, "along_lane, straight_line or lateral");
  }
  if (distance) {
    trigger.measure = value == "along_lane" ? TriggerSpec::Measure::AlongLane : TriggerSpec::Measure::StraightLine;
  } else if (secondOf(reader, node, field, trigger, "along_lane", "straight_line")) {
    trigger.measure = TriggerSpec::Measure::StraightLine;
  }
}

/// `from` of a distance trigger: centre (the default) or body (its nearest point).
void parseDistanceFrom(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                       TriggerSpec& trigger) {
  if (trigger.kind != TriggerSpec::Kind::Distance) {
    reader.fail(node, field, "'from' goes with distance_at_most and distance_at_least (and only there)");
  }
  const std::string value = reader.scalar(node, field);
  if (value != "centre" && value != "body" && value != "reference_point") {
    throw ConfigError::field(reader.where(node, field), field, value, "centre, body or reference_point");
  }
  trigger.fromBody = value == "body";
  trigger.fromReferencePoint = value == "reference_point";
}

bool isMoment(TriggerSpec::Kind kind) { return kind == TriggerSpec::Kind::Time || kind == TriggerSpec::Kind::After; }

/// Whether a trigger's condition can stop holding and hold again (no time or action end in it).
bool canHoldAgain(const TriggerSpec& trigger) {
  if (isMoment(trigger.kind)) return false;
  return std::all_of(trigger.members.begin(), trigger.members.end(), canHoldAgain);
}

/// Whether a repeated action can start again on this trigger: a moment at its top or inside
/// `all` still holds when a run ends (it starts again then); inside `any` it would give a start
/// that has passed.
bool restartsOn(const TriggerSpec& trigger) {
  if (trigger.kind == TriggerSpec::Kind::Any) return canHoldAgain(trigger);
  return std::all_of(trigger.members.begin(), trigger.members.end(), restartsOn);
}

/// true or false.
bool flag(const YamlReader& reader, const YAML::Node& node, const std::string& field) {
  const std::string value = reader.scalar(node, field);
  if (value != "true" && value != "false") {
    throw ConfigError::field(reader.where(node, field), field, value, "true or false");
  }
  return value == "true";
}

/// A trigger; `delay_allowed`: where a member's own start time counts (the trigger itself
/// and the members of its `any`), not inside `all` (whose members hold at one instant).
void parseTrigger(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                  const std::vector<std::string>& inputs, bool delay_allowed, TriggerSpec& trigger) {
  trigger.where = reader.where(node, field);
  reader.requireMap(node, field);
  std::set<std::string> allowed = {"to", "of", "between", "measure", "from", "position", "delay", "rising", "falling",
                                   "last"};
  std::vector<std::string> keys;
  for (const auto& entry : kTriggerKeys) {
    allowed.insert(entry.key);
    keys.emplace_back(entry.key);
  }
  reader.checkKeys(node, field, allowed);
  const std::string key = oneOf(reader, node, field, keys, true);
  const auto& entry = *std::find_if(std::begin(kTriggerKeys), std::end(kTriggerKeys),
                                    [&](const TriggerKey& candidate) { return key == candidate.key; });
  trigger.kind = entry.kind;
  trigger.bound = entry.bound;
  if (trigger.kind == TriggerSpec::Kind::All || trigger.kind == TriggerSpec::Kind::Any) {
    const YAML::Node list = node[key];
    if (!list.IsSequence() || list.size() == 0) reader.fail(list, field + "." + key, "expected a non-empty list of triggers");
    for (std::size_t m = 0; m < list.size(); ++m) {
      TriggerSpec member;
      parseTrigger(reader, list[m], fmt::format("{}.{}[{}]", field, key, m), inputs,
                   delay_allowed && trigger.kind == TriggerSpec::Kind::Any, member);
      trigger.members.push_back(std::move(member));
    }
  } else if (trigger.kind == TriggerSpec::Kind::After) {
    trigger.action = reader.scalar(node["after"], field + ".after");
    if (node["last"]) trigger.lastRun = flag(reader, node["last"], field + ".last");
  } else {
    trigger.value = reader.expression(node[key], field + "." + key, inputs);
    if (*entry.unit) requireNonNegative(reader, node[key], field + "." + key, trigger.value, false, entry.unit);
  }
  if (node["last"] && trigger.kind != TriggerSpec::Kind::After) {
    reader.fail(node["last"], field + ".last", "'last' goes with 'after' (the end of that action's last run)");
  }
  if (node["to"]) {
    if (!isRelation(trigger.kind)) {
      reader.fail(node["to"], field + ".to", "'to' names the other road user of a gap, headway, ttc or relative_speed condition");
    }
    trigger.reference = reader.scalar(node["to"], field + ".to");
  }
  if (node["of"]) {
    if (!hasSubject(trigger.kind)) {
      reader.fail(node["of"], field + ".of",
                  "'of' names whose speed, acceleration, distance, road end or headway a condition measures");
    }
    trigger.subject = reader.scalar(node["of"], field + ".of");
  }
  // Which points of the two a gap, headway or ttc measures between, and how.
  if (node["between"]) {
    trigger.betweenReferencePoints =
        secondOf(reader, node["between"], field + ".between", trigger, "bumpers", "reference_points");
  }
  // A distance to a place is a straight one unless the trigger says otherwise.
  if (trigger.kind == TriggerSpec::Kind::Distance) trigger.measure = TriggerSpec::Measure::StraightLine;
  if (node["measure"]) parseMeasure(reader, node["measure"], field + ".measure", trigger);
  if (node["from"]) parseDistanceFrom(reader, node["from"], field + ".from", trigger);
  if ((trigger.kind == TriggerSpec::Kind::Distance) != static_cast<bool>(node["position"])) {
    reader.fail(node, field, "'position' goes with distance_at_most and distance_at_least (and only there)");
  }
  if (node["position"]) parsePosition(reader, node["position"], field + ".position", inputs, trigger.position);
  if (node["delay"] && !delay_allowed && !isMoment(trigger.kind)) {
    reader.fail(node["delay"], field + ".delay",
                "a delay on a condition inside 'all' (its members hold at one instant; a time or after may have one, "
                "a later moment): put it on the 'all'");
  }
  trigger.delay = optionalExpression(reader, node, "delay", field, inputs, 0.0);
  if (node["delay"]) requireNonNegative(reader, node["delay"], field + ".delay", trigger.delay, false, "s");
  for (const char* edge : {"rising", "falling"}) {
    if (!node[edge]) continue;
    (std::string(edge) == "rising" ? trigger.rising : trigger.falling) = flag(reader, node[edge], field + "." + edge);
    if (!canHoldAgain(trigger) || trigger.kind == TriggerSpec::Kind::All || trigger.kind == TriggerSpec::Kind::Any) {
      reader.fail(node[edge], field + "." + edge,
                  fmt::format("'{}' goes with a condition (not time, after, all or any; put it on their members)",
                              edge));
    }
  }
}

TransitionShape parseShape(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                           TransitionShape fallback, bool step_allowed) {
  if (!node["shape"]) return fallback;
  const std::string name = reader.scalar(node["shape"], field + ".shape");
  if (name == "linear") return TransitionShape::Linear;
  if (name == "smooth") return TransitionShape::Smooth;
  if (name == "cubic") return TransitionShape::Cubic;
  if (name == "step" && step_allowed) return TransitionShape::Step;
  throw ConfigError::field(reader.where(node["shape"], field + ".shape"), field + ".shape", name,
                           step_allowed ? "one of step, linear, smooth, cubic" : "one of linear, smooth, cubic");
}

/// The pace keys of `node` (exactly one of `keys`, each mapped to a Pace).
void parsePace(const YamlReader& reader, const YAML::Node& node, const std::string& field,
               const std::vector<std::pair<std::string, ActionSpec::Pace>>& keys,
               const std::vector<std::string>& inputs, ActionSpec& action) {
  std::vector<std::string> names;
  for (const auto& [key, pace] : keys) names.push_back(key);
  const std::string key = oneOf(reader, node, field, names, true);
  for (const auto& [name, pace] : keys) {
    if (name == key) action.pace = pace;
  }
  action.paceValue = reader.expression(node[key], field + "." + key, inputs);
  requireNonNegative(reader, node[key], field + "." + key, action.paceValue, action.pace != ActionSpec::Pace::Duration,
                     key == "duration" ? "s" : key == "distance" ? "m" : "");
}

/// `to` and `continuous` of a speed action relative to another road user's speed.
void parseSpeedReference(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                         const std::string& target, ActionSpec& action) {
  const bool relative = target == "relative_target" || target == "relative_factor";
  for (const char* key : {"to", "continuous"}) {
    if (node[key] && !relative) {
      reader.fail(node[key], field + "." + key, "goes with relative_target and relative_factor (and only there)");
    }
  }
  if (node["to"]) action.speedReference = reader.scalar(node["to"], field + ".to");
  if (node["continuous"]) action.continuous = flag(reader, node["continuous"], field + ".continuous");
}

void parseSpeedAction(const YamlReader& reader, const YAML::Node& node, const std::string& field, bool stop,
                      const std::vector<std::string>& inputs, ActionSpec& action) {
  action.kind = ActionSpec::Kind::Speed;
  if (stop) {
    reader.checkKeys(node, field, {"decel", "duration", "distance", "shape"});
    action.target = Expression::constant(0.0);
    parsePace(reader, node, field,
              {{"decel", ActionSpec::Pace::Rate},
               {"duration", ActionSpec::Pace::Duration},
               {"distance", ActionSpec::Pace::Distance}},
              inputs, action);
  } else {
    reader.checkKeys(node, field, {"target", "relative_target", "relative_factor", "to", "continuous", "delta", "shape",
                                   "rate", "duration", "distance"});
    const std::string target =
        oneOf(reader, node, field, {"target", "relative_target", "relative_factor", "delta"}, true);
    action.speedTarget = target == "target"            ? ActionSpec::SpeedTarget::Absolute
                         : target == "relative_target" ? ActionSpec::SpeedTarget::Relative
                         : target == "relative_factor" ? ActionSpec::SpeedTarget::Factor
                                                       : ActionSpec::SpeedTarget::Delta;
    action.target = reader.expression(node[target], field + "." + target, inputs);
    if (target == "target" || target == "relative_factor") {
      requireNonNegative(reader, node[target], field + "." + target, action.target, false,
                         target == "target" ? "m/s" : "");
    }
    parseSpeedReference(reader, node, field, target, action);
  }
  action.shape = parseShape(reader, node, field, TransitionShape::Linear, true);
  if (action.continuous && action.shape != TransitionShape::Step) {
    reader.fail(node, field + ".continuous", "a continuous target follows the other's speed at once: shape step");
  }
  if (action.shape == TransitionShape::Step) {
    for (const char* key : {"rate", "decel", "duration", "distance"}) {
      if (node[key]) {
        reader.fail(node[key], field + "." + key, "a step changes the speed at once: no rate, duration or distance");
      }
    }
    action.pace = ActionSpec::Pace::Duration;
    action.paceValue = Expression::constant(0.0);
  } else if (!stop) {
    parsePace(reader, node, field,
              {{"rate", ActionSpec::Pace::Rate},
               {"duration", ActionSpec::Pace::Duration},
               {"distance", ActionSpec::Pace::Distance}},
              inputs, action);
  }
}

/// `of_ego`: the Ego's lateral actions move the lane its controller keeps (a step is a jump of
/// that lane, which the controller then follows), and count from its own lane only.
void parseLateralAction(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const std::string& kind, const std::vector<std::string>& inputs, bool of_ego,
                        ActionSpec& action) {
  if (kind == "cross") {
    reader.checkKeys(node, field, {"speed", "to_offset"});
    action.kind = ActionSpec::Kind::Cross;
    if (!node["to_offset"]) reader.fail(node, field, "missing 'to_offset' (m from its lane's centre, > 0 left)");
    action.target = reader.expression(node["to_offset"], field + ".to_offset", inputs);
    action.shape = TransitionShape::Linear;
    parsePace(reader, node, field, {{"speed", ActionSpec::Pace::LateralSpeed}}, inputs, action);
    return;
  }
  std::vector<std::pair<std::string, ActionSpec::Pace>> paces = {{"lateral_speed", ActionSpec::Pace::LateralSpeed},
                                                                 {"duration", ActionSpec::Pace::Duration}};
  if (kind == "lane_change") {
    reader.checkKeys(node, field,
                     {"lanes", "ego_lane", "lane", "offset", "lateral_speed", "duration", "distance", "shape"});
    action.kind = ActionSpec::Kind::LaneChange;
    action.targetLaneOffset = optionalExpression(reader, node, "offset", field, inputs, 0.0);
    paces.emplace_back("distance", ActionSpec::Pace::Distance);
    const std::string target = oneOf(reader, node, field, {"lanes", "ego_lane", "lane"}, true);
    if (of_ego && target == "ego_lane") {
      reader.fail(node[target], field + ".ego_lane",
                  "the Ego's own lane: use lanes (from its lane) or lane (of the road)");
    }
    action.relativeToEgoLane = target == "ego_lane";
    action.toRoadLane = target == "lane";
    action.target = reader.expression(node[target], field + "." + target, inputs);
  } else {
    reader.checkKeys(node, field, {"offset", "lateral_speed", "lateral_accel", "duration", "shape", "continuous"});
    action.kind = ActionSpec::Kind::LateralOffset;
    if (node["continuous"]) action.continuous = flag(reader, node["continuous"], field + ".continuous");
    if (!node["offset"]) reader.fail(node, field, "missing 'offset' (m from the lane's centre, > 0 left; 0: back)");
    action.target = reader.expression(node["offset"], field + ".offset", inputs);
    paces.emplace_back("lateral_accel", ActionSpec::Pace::LateralAccel);
  }
  action.shape = parseShape(reader, node, field, TransitionShape::Smooth, /*step_allowed=*/of_ego);
  if (action.shape == TransitionShape::Step) {  // at once: no pace to give
    for (const auto& [key, pace] : paces) {
      if (node[key]) reader.fail(node[key], field + "." + key, "a step moves the lane at once: no pace");
    }
    action.pace = ActionSpec::Pace::Duration;
    action.paceValue = Expression::constant(0.0);
    return;
  }
  parsePace(reader, node, field, paces, inputs, action);
}

/// A place relative to a road user: `{from, ds, lanes[, offset]}`, `{from, ds, dd}` or `{from, dx, dy}`.
void parseRelativePlace(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const std::vector<std::string>& inputs, PositionSpec& place) {
  const bool along_road = node["ds"] || node["lanes"] || node["dd"] || node["offset"];
  const bool in_plane = node["dx"] || node["dy"] || node["axes"];
  if (in_plane ? (along_road || !node["dx"] || !node["dy"])
               : (!node["ds"] || static_cast<bool>(node["lanes"]) == static_cast<bool>(node["dd"]) ||
                  (node["dd"] && node["offset"]))) {
    reader.fail(node, field, "expected {from, ds, lanes[, offset]}, {from, ds, dd} or {from, dx, dy[, axes]}: where "
                             "from that road user");
  }
  place.from = reader.scalar(node["from"], field + ".from");
  if (place.from.empty()) reader.fail(node["from"], field + ".from", "expected a road user's id (ego or another's)");
  place.inPlane = in_plane;
  if (in_plane) {
    place.x = reader.expression(node["dx"], field + ".dx", inputs);
    place.y = reader.expression(node["dy"], field + ".dy", inputs);
    const std::string axes = node["axes"] ? reader.scalar(node["axes"], field + ".axes") : "heading";
    if (axes != "heading" && axes != "frame") {
      throw ConfigError::field(reader.where(node["axes"], field + ".axes"), field + ".axes", axes,
                               "heading (its own) or frame (the scenario frame's)");
    }
    place.frameAxes = axes == "frame";
    return;
  }
  place.s = reader.expression(node["ds"], field + ".ds", inputs);
  place.acrossFromCentre = static_cast<bool>(node["dd"]);
  if (place.acrossFromCentre) {
    place.offset = reader.expression(node["dd"], field + ".dd", inputs);
  } else {
    place.lane = reader.expression(node["lanes"], field + ".lanes", inputs);
    place.offset = optionalExpression(reader, node, "offset", field, inputs, 0.0);
  }
}

/// `teleport: {s, lane, offset}` or a place relative to a road user (parseRelativePlace): it
/// moves there at once and drives on from there in its direction, at its speed.
void parseTeleportAction(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                         const std::vector<std::string>& inputs, ActionSpec& action) {
  reader.requireMap(node, field);
  action.kind = ActionSpec::Kind::Teleport;
  if (node["from"]) {
    reader.checkKeys(node, field, {"from", "ds", "lanes", "offset", "dd", "dx", "dy", "axes"});
    parseRelativePlace(reader, node, field, inputs, action.place);
  } else {
    reader.checkKeys(node, field, {"s", "lane", "offset"});
    if (!node["s"] || !node["lane"]) {
      reader.fail(node, field, "expected {s, lane[, offset]}: where along the road it lands (or {from, ds, ...})");
    }
    parsePosition(reader, node, field, inputs, action.place);
  }
  action.shape = TransitionShape::Step;
  action.pace = ActionSpec::Pace::Duration;
  action.paceValue = Expression::constant(0.0);
}

/// The Ego's `set_speed: {target}`: its controller aims at `target` m/s from then on.
void parseSetSpeedAction(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                         const std::vector<std::string>& inputs, ActionSpec& action) {
  reader.checkKeys(node, field, {"target"});
  if (!node["target"]) reader.fail(node, field, "missing 'target' (the controller's new set speed, m/s)");
  action.kind = ActionSpec::Kind::SetSpeed;
  action.target = reader.expression(node["target"], field + ".target", inputs);
  requireNonNegative(reader, node["target"], field + ".target", action.target, false, "m/s");
  action.shape = TransitionShape::Step;
  action.pace = ActionSpec::Pace::Duration;
  action.paceValue = Expression::constant(0.0);
}

/// The Ego's `controller: {name, library, params}`: that controller drives it from the action's start.
void parseControllerAction(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                           const std::vector<std::string>& inputs, ActionSpec& action) {
  action.kind = ActionSpec::Kind::Controller;
  parseController(reader, node, field, inputs, action.controller, /*in_action=*/true);
  if (node["active_from"]) {
    reader.fail(node["active_from"], field + ".active_from", "the action's trigger says when this controller drives");
  }
  if (node["domains"]) {
    const std::string domains = reader.scalar(node["domains"], field + ".domains");
    const std::map<std::string, ControlDomains> known = {{"both", ControlDomains::Both},
                                                         {"longitudinal", ControlDomains::Longitudinal},
                                                         {"lateral", ControlDomains::Lateral}};
    const auto found = known.find(domains);
    if (found == known.end()) {
      throw ConfigError::field(reader.where(node["domains"], field + ".domains"), field + ".domains", domains,
                               "both, longitudinal or lateral");
    }
    action.domains = found->second;
  }
  action.shape = TransitionShape::Step;
  action.pace = ActionSpec::Pace::Duration;
  action.paceValue = Expression::constant(0.0);
}

void parseAction(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                 const std::vector<std::string>& inputs, const LogicalScenario& scenario, const VehicleSpec& owner,
                 std::size_t index, ActionSpec& action) {
  action.where = reader.where(node, field);
  reader.checkKeys(node, field,
                   {"id", "trigger", "repeat", "ends", "speed", "stop", "lane_change", "lateral_offset", "cross",
                    "teleport", "set_speed", "controller"});
  action.id = node["id"] ? reader.scalar(node["id"], field + ".id") : fmt::format("{}_{}", owner.id, index);
  if (!isIdentifier(action.id)) {
    throw ConfigError::field(reader.where(node["id"], field + ".id"), field + ".id", action.id,
                             "an identifier (letters, digits, _)");
  }
  if (node["trigger"]) {
    parseTrigger(reader, node["trigger"], field + ".trigger", inputs, /*delay_allowed=*/true, action.trigger);
  } else {
    action.trigger.where = action.where;
    action.trigger.value = Expression::constant(0.0);
  }
  action.repeat = reader.integer(node, "repeat", field + ".repeat", 1, 1);
  if (const auto ends = node["ends"]) {
    if (!ends.IsSequence()) reader.fail(ends, field + ".ends", "expected a list of action ids");
    for (std::size_t i = 0; i < ends.size(); ++i) {
      action.ends.push_back(reader.scalar(ends[i], fmt::format("{}.ends[{}]", field, i)));
    }
  }
  if (action.repeat > 1 && !restartsOn(action.trigger)) {
    reader.fail(node["repeat"], field + ".repeat",
                "a repeated action's trigger with a time or after inside 'any': it would start again at a moment "
                "that has passed (put them at the top or inside 'all')");
  }
  const std::string kind =
      oneOf(reader, node, field,
            {"speed", "stop", "lane_change", "lateral_offset", "cross", "teleport", "set_speed", "controller"}, true);
  const bool of_ego = &owner == &scenario.ego;
  const bool controls = kind == "set_speed" || kind == "controller";
  const bool moves_kept_lane = kind == "lane_change" || kind == "lateral_offset";
  if (of_ego ? !(controls || moves_kept_lane || kind == "teleport") : controls) {
    reader.fail(node[kind], field + "." + kind,
                of_ego ? "the Ego's controller drives it: the Ego's actions set its controller's set speed "
                         "(set_speed), change its controller (controller), move the lane it keeps (lane_change, "
                         "lateral_offset) or move it at once (teleport)"
                       : "only the Ego has a controller (set_speed and controller are actions of the Ego)");
  }
  if (of_ego && moves_kept_lane) {
    parseLateralAction(reader, node[kind], field + "." + kind, kind, inputs, /*of_ego=*/true, action);
    return;
  }
  if (of_ego && kind == "teleport") {
    parseTeleportAction(reader, node[kind], field + ".teleport", inputs, action);
    return;
  }
  if (of_ego && kind == "controller") {
    parseControllerAction(reader, node[kind], field + "." + kind, inputs, action);
    return;
  }
  if (of_ego) {
    parseSetSpeedAction(reader, node[kind], field + "." + kind, inputs, action);
    return;
  }
  const auto& type = roadUserKind(owner.type);
  if (type.stationary) reader.fail(node[kind], field + "." + kind, "a stationary object does not move");
  if ((kind == "lane_change" || kind == "lateral_offset") && !type.drivesInLanes) {
    reader.fail(node[kind], field + "." + kind, fmt::format("a {} does not drive in lanes", type.name));
  }
  if (kind == "cross" && owner.type != RoadUserType::Pedestrian) {
    reader.fail(node[kind], field + ".cross", "only pedestrians cross the road");
  }
  if (kind != "speed" && kind != "stop" && owner.keepsLaneByPurePursuit()) {
    reader.fail(node[kind], field + "." + kind,
                "a road user with heading_noise_deg keeps its lane by pure pursuit: lateral actions and teleports "
                "need one without (they move it exactly in the lane frame)");
  }
  if (kind == "speed" || kind == "stop") parseSpeedAction(reader, node[kind], field + "." + kind, kind == "stop", inputs, action);
  else if (kind == "teleport") parseTeleportAction(reader, node[kind], field + ".teleport", inputs, action);
  else parseLateralAction(reader, node[kind], field + "." + kind, kind, inputs, /*of_ego=*/false, action);
}

/// A road user's `actions` list, if it has one.
void parseActions(const YamlReader& reader, const YAML::Node& item, const std::string& field,
                  const std::vector<std::string>& inputs, const LogicalScenario& scenario, VehicleSpec& user) {
  const auto actions = item["actions"];
  if (!actions) return;
  if (!actions.IsSequence()) reader.fail(actions, field + ".actions", "expected a list of actions");
  for (std::size_t a = 0; a < actions.size(); ++a) {
    ActionSpec action;
    parseAction(reader, actions[a], fmt::format("{}.actions[{}]", field, a), inputs, scenario, user, a, action);
    user.actions.push_back(std::move(action));
  }
}

void parseOtherSpeed(const YamlReader& reader, const YAML::Node& item, const std::string& field,
                     const std::vector<std::string>& inputs, VehicleSpec& other) {
  const bool moves = !roadUserKind(other.type).stationary;
  const std::string key = oneOf(reader, item, field, {"speed_profile", "speed", "relative_speed"}, false);
  if (!moves && !key.empty()) reader.fail(item[key], field + "." + key, "a stationary object does not move");
  if (key.empty()) {
    if (roadUserKind(other.type).drivesInLanes) {
      reader.fail(item, field, "needs one of: speed_profile, speed, relative_speed");
    }
    other.speed = Expression::constant(0.0);
  } else if (key == "speed_profile") {
    parseSpeedProfile(reader, item[key], field + ".speed_profile", inputs, other);
  } else {
    other.speed = reader.expression(item[key], field + "." + key, inputs);
    other.speedRelativeToEgo = key == "relative_speed";
    if (key == "speed") requireNonNegative(reader, item[key], field + ".speed", other.speed, false, "m/s");
  }
  if (item["speed_noise"]) other.speedNoise = reader.distribution(item["speed_noise"], field + ".speed_noise", inputs);
}

void parseOther(const YamlReader& reader, const YAML::Node& item, const std::string& field,
                const std::vector<std::string>& inputs, const LogicalScenario& scenario, VehicleSpec& other) {
  other.where = reader.where(item, field);
  parseType(reader, item, field, inputs, other);
  parsePlacement(reader, item, field, /*is_ego=*/false, inputs, scenario, other);
  parseOtherSpeed(reader, item, field, inputs, other);
  parseHeadingNoise(reader, item, field, inputs, other);
  parseDirection(reader, item, field, other);
  if (item["may_start_overlapping"]) {
    other.mayStartOverlapping = flag(reader, item["may_start_overlapping"], field + ".may_start_overlapping");
  }
  parseActions(reader, item, field, inputs, scenario, other);
}

void parseEgo(const YamlReader& reader, const YAML::Node& ego, const std::vector<std::string>& inputs,
              LogicalScenario& scenario) {
  const std::string field = "vehicles.ego";
  reader.checkKeys(ego, field,
                   {"type", "x", "s", "lane", "speed", "length", "width", "reference_point", "heading_noise_deg",
                    "controller", "actions"});
  VehicleSpec& spec = scenario.ego;
  spec.id = "ego";
  spec.where = reader.where(ego, field);
  parseType(reader, ego, field, inputs, spec);
  if (!roadUserKind(spec.type).drivesInLanes) {
    reader.fail(ego["type"], field + ".type", "the Ego is a vehicle: one of car, van, truck, bus, motorbike");
  }
  parsePlacement(reader, ego, field, /*is_ego=*/true, inputs, scenario, spec);
  if (!ego["speed"]) reader.fail(ego, field, "missing 'speed' (initial speed, m/s)");
  spec.speed = reader.expression(ego["speed"], field + ".speed", inputs);
  requireNonNegative(reader, ego["speed"], field + ".speed", spec.speed, false, "m/s");
  parseHeadingNoise(reader, ego, field, inputs, spec);
  if (!ego["controller"]) reader.fail(ego, field, "missing 'controller'");
  parseController(reader, ego["controller"], field + ".controller", inputs, spec.controller);
  parseActions(reader, ego, field, inputs, scenario, spec);
}

/// A trigger's road users (`to`, `of`) and actions (`after`), members included, exist.
void checkTriggerReferences(const TriggerSpec& trigger, const std::string& owner, const std::vector<std::string>& users,
                            const std::map<std::string, const ActionSpec*>& actions,
                            const std::vector<std::string>& action_ids) {
  const std::string& subject = trigger.subject.empty() ? owner : trigger.subject;
  if (!trigger.subject.empty() && std::find(users.begin(), users.end(), trigger.subject) == users.end()) {
    throw ConfigError(fmt::format("{}.of: got '{}', expected a road user of the file: {}", trigger.where,
                                  trigger.subject, fmt::join(users, ", ")));
  }
  // A headway's `of` is one of its two road users: the acting one and `to`.
  const bool headway = trigger.kind == TriggerSpec::Kind::Headway;
  if (isRelation(trigger.kind) && (std::find(users.begin(), users.end(), trigger.reference) == users.end() ||
                                   trigger.reference == (headway ? owner : subject))) {
    throw ConfigError(fmt::format("{}.to: got '{}', expected another road user of the file: {}", trigger.where,
                                  trigger.reference, fmt::join(users, ", ")));
  }
  if (headway && !trigger.subject.empty() && trigger.subject != owner && trigger.subject != trigger.reference) {
    throw ConfigError(fmt::format("{}.of: got '{}', expected one of the headway's two road users: '{}' or '{}'",
                                  trigger.where, trigger.subject, owner, trigger.reference));
  }
  if (!trigger.position.from.empty() &&
      std::find(users.begin(), users.end(), trigger.position.from) == users.end()) {
    throw ConfigError(fmt::format("{}.position.from: got '{}', expected a road user of the file: {}", trigger.where,
                                  trigger.position.from, fmt::join(users, ", ")));
  }
  if (trigger.kind == TriggerSpec::Kind::After && !actions.count(trigger.action)) {
    throw ConfigError(fmt::format("{}.after: got '{}', expected the id of an action of the file: {}", trigger.where,
                                  trigger.action, action_ids.empty() ? "none" : fmt::format("{}", fmt::join(action_ids, ", "))));
  }
  for (const auto& member : trigger.members) checkTriggerReferences(member, owner, users, actions, action_ids);
}

/// A speed relative to another road user's names one of the file, not the acting one.
void checkSpeedReference(const ActionSpec& action, const std::string& owner, const std::vector<std::string>& users) {
  const bool relative =
      action.speedTarget == ActionSpec::SpeedTarget::Relative || action.speedTarget == ActionSpec::SpeedTarget::Factor;
  if (action.kind != ActionSpec::Kind::Speed || !relative) return;
  if (std::find(users.begin(), users.end(), action.speedReference) == users.end() || action.speedReference == owner) {
    throw ConfigError(fmt::format("{}.speed.to: got '{}', expected another road user of the file: {}", action.where,
                                  action.speedReference, fmt::join(users, ", ")));
  }
}

/// A teleport relative to a road user names one of the file (itself included).
void checkTeleportReference(const ActionSpec& action, const std::vector<std::string>& users) {
  if (action.kind != ActionSpec::Kind::Teleport || action.place.from.empty()) return;
  if (std::find(users.begin(), users.end(), action.place.from) == users.end()) {
    throw ConfigError(fmt::format("{}.teleport.from: got '{}', expected a road user of the file: {}", action.where,
                                  action.place.from, fmt::join(users, ", ")));
  }
}

/// The `after` conditions a trigger cannot fire without (itself, or members of an `all`),
/// each with the trigger that names it.
void necessaryAfters(const TriggerSpec& trigger, std::vector<const TriggerSpec*>& found) {
  if (trigger.kind == TriggerSpec::Kind::After) found.push_back(&trigger);
  if (trigger.kind != TriggerSpec::Kind::All) return;
  for (const auto& member : trigger.members) necessaryAfters(member, found);
}

/// Depth-first over necessary `after` conditions: coming back to an action on the current
/// path is a cycle, reported at its first action's `after`.
void checkNoCycle(const std::string& id, const std::map<std::string, const ActionSpec*>& actions,
                  std::vector<std::pair<std::string, const TriggerSpec*>>& path, std::map<std::string, int>& visited) {
  visited[id] = 1;  // on the path
  std::vector<const TriggerSpec*> afters;
  necessaryAfters(actions.at(id)->trigger, afters);
  for (const TriggerSpec* after : afters) {
    path.emplace_back(id, after);
    if (visited[after->action] == 1) {
      std::size_t first = 0;
      while (path[first].first != after->action) ++first;
      std::vector<std::string> chain;
      for (std::size_t i = first; i < path.size(); ++i) chain.push_back(path[i].first);
      chain.push_back(after->action);
      throw ConfigError(fmt::format("{}.after: got '{}', a cycle of triggers ({}); expected a chain that starts "
                                    "with a time or a condition",
                                    path[first].second->where, path[first].second->action, fmt::join(chain, " -> ")));
    }
    if (visited[after->action] == 0) checkNoCycle(after->action, actions, path, visited);
    path.pop_back();
  }
  visited[id] = 2;  // done
}

/// The actions an action ends are others of the file.
void checkEndedActions(const ActionSpec& action, const std::vector<std::string>& action_ids) {
  for (const auto& id : action.ends) {
    if (id == action.id || !std::binary_search(action_ids.begin(), action_ids.end(), id)) {
      throw ConfigError(fmt::format("{}.ends: got '{}', expected the id of another action of the file: {}",
                                    action.where, id, fmt::join(action_ids, ", ")));
    }
  }
}

/// Trigger references name existing road users and actions; `after` chains have no cycle.
void resolveReferences(const LogicalScenario& scenario) {
  std::vector<std::string> users = {"ego"};
  for (const auto& other : scenario.others) users.push_back(other.id);
  std::vector<const VehicleSpec*> acting = {&scenario.ego};
  for (const auto& other : scenario.others) acting.push_back(&other);
  std::map<std::string, const ActionSpec*> actions;
  for (const VehicleSpec* user : acting) {
    for (const auto& action : user->actions) {
      if (!actions.emplace(action.id, &action).second) {
        throw ConfigError(fmt::format("{}.id: got '{}', expected an action id used once in the file", action.where,
                                      action.id));
      }
    }
  }
  std::vector<std::string> action_ids;
  for (const auto& [id, action] : actions) action_ids.push_back(id);
  for (const VehicleSpec* user : acting) {
    for (const auto& action : user->actions) {
      checkTriggerReferences(action.trigger, user->id, users, actions, action_ids);
      checkSpeedReference(action, user->id, users);
      checkTeleportReference(action, users);
      checkEndedActions(action, action_ids);
    }
  }
  std::map<std::string, int> visited;
  for (const auto& [id, action] : actions) {
    std::vector<std::pair<std::string, const TriggerSpec*>> path;
    if (visited[id] == 0) checkNoCycle(id, actions, path, visited);
  }
}

}  // namespace

void parseRoadUsers(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) reader.fail(YAML::Node(), "vehicles", "missing section 'vehicles' (at least 'ego')");
  reader.checkKeys(node, "vehicles", {"ego", "others"});
  const auto inputs = scenario.inputNames();
  if (!node["ego"]) reader.fail(node, "vehicles.ego", "missing: every scenario needs an Ego (the vehicle under test)");
  parseEgo(reader, node["ego"], inputs, scenario);

  std::set<std::string> ids = {"ego"};
  const auto others = node["others"];
  if (!others) return;
  if (!others.IsSequence()) reader.fail(others, "vehicles.others", "expected a list of road users");
  for (std::size_t i = 0; i < others.size(); ++i) {
    const auto item = others[i];
    const std::string field = fmt::format("vehicles.others[{}]", i);
    reader.checkKeys(item, field,
                     {"id", "type", "x", "s", "ds", "gap", "from", "lane", "relative_lane", "offset", "heading_deg",
                      "direction", "may_start_overlapping", "length", "width", "reference_point",
                      "speed_profile", "speed", "relative_speed", "speed_noise", "heading_noise_deg", "actions"});
    VehicleSpec other;
    other.id = item["id"] ? reader.scalar(item["id"], field + ".id") : fmt::format("other{}", i);
    if (!isIdentifier(other.id) || !ids.insert(other.id).second) {
      throw ConfigError::field(reader.where(item["id"], field + ".id"), field + ".id", other.id,
                               "a unique identifier (letters, digits, _)");
    }
    parseOther(reader, item, field, inputs, scenario, other);
    scenario.others.push_back(std::move(other));
  }
  resolveReferences(scenario);
}

}  // namespace vsd::scenario::detail
