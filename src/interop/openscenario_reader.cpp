// Reads OpenSCENARIO files within the supported subset (README "OpenSCENARIO subset")
// into a scenario `vsd-sumo run` can simulate.

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "openscenario_names.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/tool_options.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/interop/opendrive.hpp"
#include "vsd/interop/openscenario.hpp"
#include "xml_support.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

/// Start positions and controller properties are exact in exported files; hand-written
/// ones may round. Larger deviations mean a vehicle is not where vsd-sumo can put it.
constexpr double kOnLaneTolerance = 0.01;  // m
/// An instant after every window's end: a condition that never holds within the simulation.
constexpr int kNever = kMaxWindowSteps + 2;
/// m: where the bounding box centre may lie relative to the reference point.
constexpr NumberRange kReferenceOffset = NumberRange::closed(-100.0, 100.0);

struct Entity {
  std::string name;
  pugi::xml_node node;
  double length = 0.0;
  double width = 0.0;
  double referenceAhead = 0.0;  ///< m the box centre lies ahead of the entity's reference point
  pugi::xml_node headingDisturbance;  ///< the vehicle's Property holding it, if any (scripted vehicles)
  // From the Init:
  std::optional<Vec2> position;  ///< box centre, scenario frame
  int lane = 0;
  double initialSpeed = 0.0;
  pugi::xml_node controller;    ///< <Controller>, if the entity has one
  // From the Story: speed changes (instant index, the change).
  struct SpeedChange {
    int instant = 0;
    double target = 0.0;
    double duration = 0.0;  ///< s over which the speed changes linearly (0: a step)
    double rate = 0.0;      ///< m/s^2 (> 0: ramp with this rate instead of a duration)
  };
  std::vector<SpeedChange> speedChanges;
};

struct Document {
  const xml::Reader& reader;
  std::map<std::string, std::string> properties;            ///< FileHeader properties
  std::vector<std::pair<std::string, double>> parameters;   ///< numeric ParameterDeclarations, in order
  OpenDriveRoad road;
  std::vector<Entity> entities;
  double step = 0.0;
  double duration = 0.0;

  Entity& entity(const pugi::xml_node& node, const std::string& name) {
    for (auto& candidate : entities) {
      if (candidate.name == name) return candidate;
    }
    reader.fail(node, fmt::format("entityRef=\"{}\" names no entity of <Entities>", name));
  }
  /// The instant at which a time condition becomes true; times beyond the longest
  /// window (kMaxWindowSteps steps) are all "after the end" (kNever).
  int instantOf(const pugi::xml_node& node, double time) const {
    if (!(time >= 0.0)) reader.fail(node, fmt::format("time {} s: expected >= 0 s", xml::number(time)));
    const double instants = time / step;
    if (instants > kMaxWindowSteps + 1.0) return kNever;
    const double rounded = std::round(instants);
    // Times between two instants take effect at the next one (the condition becomes true there).
    return static_cast<int>(std::abs(instants - rounded) < 1e-6 ? rounded : std::ceil(instants));
  }
};

std::map<std::string, std::string> readFileHeader(const xml::Reader& reader, const pugi::xml_node& root) {
  const pugi::xml_node header = reader.only(root, "FileHeader");
  reader.requireSubset(header, {"License", "Properties"});
  if (reader.number(header, "revMajor") != names::kRevMajor) {
    reader.fail(header, fmt::format("revMajor=\"{}\": expected OpenSCENARIO 1.x", reader.text(header, "revMajor")));
  }
  std::map<std::string, std::string> properties;
  if (const pugi::xml_node list = header.child("Properties")) {
    reader.requireSubset(list, {"Property"});
    for (const pugi::xml_node& property : list.children("Property")) {
      properties[reader.text(property, "name")] = reader.text(property, "value");
    }
  }
  return properties;
}

std::vector<std::pair<std::string, double>> readParameters(xml::Reader& reader, const pugi::xml_node& root) {
  std::vector<std::pair<std::string, double>> numeric;
  std::map<std::string, std::string> values;
  if (const pugi::xml_node declarations = root.child("ParameterDeclarations")) {
    reader.requireSubset(declarations, {"ParameterDeclaration"});
    for (const pugi::xml_node& declaration : declarations.children("ParameterDeclaration")) {
      reader.requireSubset(declaration, {});
      const std::string name = reader.text(declaration, "name");
      const std::string type = reader.oneOf(declaration, "parameterType",
                                            {"double", "int", "integer", "unsignedInt", "unsignedShort", "string", "boolean"});
      values[name] = reader.text(declaration, "value");
      if (type == "double") {
        numeric.emplace_back(name, reader.number(declaration, "value"));
      } else if (type != "string" && type != "boolean") {
        const std::int64_t low = type == "int" || type == "integer" ? -(std::int64_t{1} << 31) : 0;
        const std::int64_t high = type == "unsignedShort" ? 65535 : (std::int64_t{1} << 32) - 1;
        numeric.emplace_back(name, static_cast<double>(reader.integer(declaration, "value", low, high)));
      }
    }
  }
  reader.setParameters(std::move(values));
  return numeric;
}

/// Performance: not simulated (vsd-sumo's vehicle model has its own limits) but checked,
/// so that a file's nonsense is refused rather than carried on.
void readPerformance(const xml::Reader& reader, const pugi::xml_node& performance) {
  reader.requireSubset(performance, {});
  for (const char* limit : {"maxSpeed", "maxAcceleration", "maxDeceleration"}) {
    reader.optionalNumber(performance, limit, NumberRange::closed(0.0, 1000.0));
  }
  for (const char* rate : {"maxAccelerationRate", "maxDecelerationRate"}) {
    reader.optionalNumber(performance, rate, NumberRange::atLeast(0.0));
  }
}

void readEntities(Document& document, const pugi::xml_node& root) {
  const xml::Reader& reader = document.reader;
  const pugi::xml_node entities = reader.only(root, "Entities");
  reader.requireSubset(entities, {"ScenarioObject"});
  for (const pugi::xml_node& object : entities.children("ScenarioObject")) {
    reader.requireSubset(object, {"Vehicle", "ObjectController"});
    Entity entity;
    entity.name = reader.text(object, "name");
    entity.node = object;
    const pugi::xml_node vehicle = reader.only(object, "Vehicle");
    reader.requireSubset(vehicle, {"BoundingBox", "Performance", "Axles", "Properties"});
    const pugi::xml_node box = reader.only(vehicle, "BoundingBox");
    reader.requireSubset(box, {"Center", "Dimensions"});
    const pugi::xml_node dimensions = reader.only(box, "Dimensions");
    entity.length = reader.number(dimensions, "length", scenario_bounds::kVehicleLength);
    entity.width = reader.number(dimensions, "width", scenario_bounds::kVehicleWidth);
    reader.optionalNumber(dimensions, "height", NumberRange::above(0.0));
    const pugi::xml_node center = reader.only(box, "Center");
    entity.referenceAhead = reader.number(center, "x", kReferenceOffset);
    if (std::abs(reader.number(center, "y")) > kOnLaneTolerance) {
      reader.fail(center, "y: expected 0 (the bounding box centred on the vehicle's axis)");
    }
    if (const pugi::xml_node performance = vehicle.child("Performance")) readPerformance(reader, performance);
    if (const pugi::xml_node properties = vehicle.child("Properties")) {
      reader.requireSubset(properties, {"Property"});
      for (const pugi::xml_node& property : properties.children("Property")) {
        if (reader.text(property, "name") == names::kHeadingDisturbance) entity.headingDisturbance = property;
      }
    }
    if (const pugi::xml_node object_controller = object.child("ObjectController")) {
      reader.requireSubset(object_controller, {"Controller"});
      entity.controller = reader.only(object_controller, "Controller");
    }
    for (const auto& other : document.entities) {
      if (other.name == entity.name) reader.fail(object, fmt::format("entity name '{}' is used twice", entity.name));
    }
    document.entities.push_back(entity);
  }
  if (document.entities.empty()) reader.fail(entities, "expected at least one <ScenarioObject>");
}

/// Where a LanePosition or WorldPosition puts the entity's box centre, and on which lane.
void readPosition(Document& document, Entity& entity, const pugi::xml_node& position_node) {
  const xml::Reader& reader = document.reader;
  const road::RoadGeometry& road = document.road.geometry;
  const pugi::xml_node position = reader.choice(position_node, {"LanePosition", "WorldPosition"});
  RoadCoordinate coordinate;
  int lane = 0;
  if (std::string(position.name()) == "LanePosition") {
    reader.requireSubset(position, {"Orientation"});
    if (reader.text(position, "roadId") != document.road.id) {
      reader.fail(position, fmt::format("roadId=\"{}\": the road network has road \"{}\" only",
                                        reader.text(position, "roadId"), document.road.id));
    }
    const auto lane_id = reader.integer(position, "laneId", -scenario_bounds::kMaxLanes, scenario_bounds::kMaxLanes);
    const auto found = laneFromOpenDrive(static_cast<int>(lane_id), road.lanes);
    if (!found) {
      reader.fail(position, fmt::format("laneId=\"{}\": expected a driving lane, -1 .. -{}", reader.text(position, "laneId"), road.lanes));
    }
    lane = *found;
    const double offset = reader.optionalNumber(position, "offset").value_or(0.0);
    if (std::abs(offset) > kOnLaneTolerance) {
      reader.fail(position, fmt::format("offset=\"{}\": vehicles start on their lane's centre line (|offset| <= {} m)",
                                        reader.text(position, "offset"), kOnLaneTolerance));
    }
    if (const pugi::xml_node orientation = position.child("Orientation")) {
      const bool relative = reader.optionalText(orientation, "type").value_or("relative") == "relative";
      if (!relative || std::abs(reader.optionalNumber(orientation, "h").value_or(0.0)) > 1e-6) {
        reader.fail(orientation, "vehicles start heading along their lane (relative h = 0)");
      }
    }
    coordinate = {reader.number(position, "s", NumberRange::closed(0.0, MeasuredPolyline(road.centre).length())),
                  road.laneOffset(lane) + offset};
  } else {
    reader.requireSubset(position, {});
    const NumberRange coordinates = NumberRange::closed(-1e7, 1e7);
    coordinate = toRoadCoordinate(road, Vec2(reader.number(position, "x", coordinates), reader.number(position, "y", coordinates)));
    lane = road.laneAt(coordinate.t);
    if (std::abs(coordinate.t - road.laneOffset(lane)) > kOnLaneTolerance) {
      reader.fail(position, fmt::format("({}, {}) is not on a lane's centre line (vehicles start there)",
                                        reader.text(position, "x"), reader.text(position, "y")));
    }
  }
  const MeasuredPolyline lane_centre(road.laneCentre(lane));
  const Vec2 reference = fromRoadCoordinate(road, coordinate);
  const double along = lane_centre.project(reference).arcLength + entity.referenceAhead;
  entity.position = entity.referenceAhead == 0.0 ? reference : lane_centre.pointAt(along);
  entity.lane = lane;
}

/// The target speed of a SpeedAction and how it gets there.
Entity::SpeedChange readSpeedAction(const xml::Reader& reader, const pugi::xml_node& longitudinal) {
  const pugi::xml_node action = reader.choice(longitudinal, {"SpeedAction"});
  reader.requireSubset(action, {"SpeedActionDynamics", "SpeedActionTarget"});
  const pugi::xml_node dynamics = reader.only(action, "SpeedActionDynamics");
  const pugi::xml_node target = reader.choice(reader.only(action, "SpeedActionTarget"), {"AbsoluteTargetSpeed"});
  Entity::SpeedChange change;
  // >= 0: vehicles do not reverse.
  change.target = reader.number(target, "value", NumberRange::closed(0.0, 1000.0));
  const std::string shape = reader.oneOf(dynamics, "dynamicsShape", {"step", "linear"});
  if (shape == "linear") {
    const std::string dimension = reader.oneOf(dynamics, "dynamicsDimension", {"time", "rate"});
    const double value = reader.number(dynamics, "value", NumberRange::atLeast(0.0));
    (dimension == "time" ? change.duration : change.rate) = value;
  }
  return change;
}

void readInit(Document& document, const pugi::xml_node& storyboard) {
  const xml::Reader& reader = document.reader;
  const pugi::xml_node actions = reader.only(reader.only(storyboard, "Init"), "Actions");
  reader.requireSubset(actions, {"Private"});
  for (const pugi::xml_node& private_node : actions.children("Private")) {
    Entity& entity = document.entity(private_node, reader.text(private_node, "entityRef"));
    reader.requireSubset(private_node, {"PrivateAction"});
    for (const pugi::xml_node& action_node : private_node.children("PrivateAction")) {
      const pugi::xml_node action = reader.choice(
          action_node, {"TeleportAction", "LongitudinalAction", "ControllerAction", "ActivateControllerAction"});
      const std::string kind = action.name();
      if (kind == "TeleportAction") {
        reader.requireSubset(action, {"Position"});
        readPosition(document, entity, reader.only(action, "Position"));
      } else if (kind == "LongitudinalAction") {
        entity.initialSpeed = readSpeedAction(reader, action).target;
      } else if (kind == "ControllerAction") {
        reader.requireSubset(action, {"AssignControllerAction", "ActivateControllerAction"});
        if (const pugi::xml_node assign = action.child("AssignControllerAction")) {
          reader.requireSubset(assign, {"Controller"});
          entity.controller = reader.only(assign, "Controller");
        }
      }
      // ActivateControllerAction: vsd-sumo's controllers drive both directions from the start.
    }
  }
  for (const auto& entity : document.entities) {
    if (!entity.position) reader.fail(entity.node, fmt::format("entity '{}' has no TeleportAction in the Init (where does it start?)", entity.name));
  }
}

/// Instant at which a trigger made of one SimulationTimeCondition fires; `time` (if
/// given) receives the condition's time in s (value + delay).
int readTimeTrigger(const Document& document, const pugi::xml_node& trigger, double* time_out = nullptr) {
  const xml::Reader& reader = document.reader;
  reader.requireSubset(trigger, {"ConditionGroup"});
  const pugi::xml_node group = reader.only(trigger, "ConditionGroup");
  reader.requireSubset(group, {"Condition"});
  const pugi::xml_node condition = reader.only(group, "Condition");
  reader.oneOf(condition, "conditionEdge", {"none", "rising"});
  const double delay = reader.number(condition, "delay", NumberRange::atLeast(0.0));
  const pugi::xml_node by_value = reader.choice(condition, {"ByValueCondition"});
  const pugi::xml_node time = reader.choice(by_value, {"SimulationTimeCondition"});
  const std::string rule = reader.oneOf(time, "rule", {"greaterOrEqual", "greaterThan", "equalTo"});
  double value = reader.number(time, "value", NumberRange::atLeast(0.0)) + delay;
  if (time_out != nullptr) *time_out = value;
  // greaterThan t holds from the first instant after t.
  const int instant = document.instantOf(time, value);
  return rule == "greaterThan" && std::abs(instant * document.step - value) < 1e-6 * document.step ? instant + 1 : instant;
}

void readEvent(Document& document, Entity& actor, const pugi::xml_node& event, int act_start) {
  const xml::Reader& reader = document.reader;
  reader.requireSubset(event, {"Action", "StartTrigger"});
  const int start = std::max(act_start, event.child("StartTrigger") ? readTimeTrigger(document, event.child("StartTrigger")) : 0);
  for (const pugi::xml_node& action : event.children("Action")) {
    const pugi::xml_node private_action = reader.choice(action, {"PrivateAction"});
    Entity::SpeedChange change = readSpeedAction(reader, reader.choice(private_action, {"LongitudinalAction"}));
    change.instant = start;
    actor.speedChanges.push_back(change);
  }
}

void readStories(Document& document, const pugi::xml_node& storyboard) {
  const xml::Reader& reader = document.reader;
  for (const pugi::xml_node& story : storyboard.children("Story")) {
    reader.requireSubset(story, {"Act"});
    for (const pugi::xml_node& act : story.children("Act")) {
      reader.requireSubset(act, {"ManeuverGroup", "StartTrigger"});
      const int act_start = readTimeTrigger(document, reader.only(act, "StartTrigger"));
      for (const pugi::xml_node& group : act.children("ManeuverGroup")) {
        reader.requireSubset(group, {"Actors", "Maneuver"});
        const pugi::xml_node actors = reader.only(group, "Actors");
        reader.requireSubset(actors, {"EntityRef"});
        Entity& actor = document.entity(actors, reader.text(reader.only(actors, "EntityRef"), "entityRef"));
        if (actor.controller) {
          reader.fail(actors, fmt::format("'{}' is driven by its controller; the supported subset scripts only the "
                                          "other vehicles",
                                          actor.name));
        }
        for (const pugi::xml_node& maneuver : group.children("Maneuver")) {
          reader.requireSubset(maneuver, {"Event"});
          for (const pugi::xml_node& event : maneuver.children("Event")) readEvent(document, actor, event, act_start);
        }
      }
    }
  }
}

std::string headerWhere(const Document& document) {
  return fmt::format("{}: FileHeader property", document.reader.file().string());
}

void readTimeBase(Document& document, const pugi::xml_node& storyboard, const ImportOptions& options) {
  const xml::Reader& reader = document.reader;
  const auto property = document.properties.find(names::kStep);
  if (property != document.properties.end()) {
    const std::string where = headerWhere(document);
    const double step =
        checkStep(parseReal(property->second, NumberRange::any(), where, names::kStep), where, names::kStep, property->second);
    if (options.step && std::abs(*options.step - step) > 1e-12) {
      throw ConfigError(fmt::format("{}: --step {} contradicts the file's step {} s ({})", reader.file().string(),
                                    xml::number(*options.step), property->second, names::kStep));
    }
    document.step = step;
  } else if (options.step) {
    document.step = checkStep(*options.step, "command line", "--step");
  } else {
    throw ConfigError(fmt::format("{}: the simulation step is not in the file (FileHeader property {}); pass --step",
                                  reader.file().string(), names::kStep));
  }
  const pugi::xml_node stop = reader.only(storyboard, "StopTrigger");
  double stop_time = 0.0;
  const int steps = readTimeTrigger(document, stop, &stop_time);
  // The duration sizes every trace and dataset array: bounded here, before any is made.
  checkDurationSteps(steps == kNever ? stop_time : steps * document.step, document.step, reader.where(stop),
                     "duration (SimulationTimeCondition value + delay, s)");
  document.duration = steps * document.step;
}

/// Speeds at instants 0..steps: the initial speed, then the speed changes in time order.
/// A change that starts at t_k shapes the speed from t_k on; the value at t_k+1 is what
/// the vehicle drives with over [t_k, t_k+1] (SUMO's Euler update, see the writer).
std::vector<double> speedProfile(const Entity& entity, int steps, double step) {
  std::vector<Entity::SpeedChange> changes = entity.speedChanges;
  std::stable_sort(changes.begin(), changes.end(), [](const auto& a, const auto& b) { return a.instant < b.instant; });
  std::vector<double> speeds(static_cast<std::size_t>(steps) + 1, entity.initialSpeed);
  double ramp_start_time = 0.0;
  double ramp_start_speed = entity.initialSpeed;
  Entity::SpeedChange ramp;
  ramp.target = entity.initialSpeed;
  std::size_t next = 0;
  for (int k = 0; k < steps; ++k) {
    for (; next < changes.size() && changes[next].instant <= k; ++next) {
      ramp = changes[next];
      ramp_start_time = k * step;
      ramp_start_speed = speeds[static_cast<std::size_t>(k)];
    }
    double span = ramp.duration;
    if (ramp.rate > 0.0) span = std::abs(ramp.target - ramp_start_speed) / ramp.rate;
    const double elapsed = (k + 1) * step - ramp_start_time;
    const double fraction = span > 0.0 ? std::min(1.0, elapsed / span) : 1.0;
    speeds[static_cast<std::size_t>(k) + 1] = ramp_start_speed + (ramp.target - ramp_start_speed) * fraction;
  }
  return speeds;
}

std::string property(const Document& document, const char* name, const std::string& fallback) {
  const auto it = document.properties.find(name);
  return it == document.properties.end() ? fallback : it->second;
}

nlohmann::json jsonProperty(const Document& document, const char* name, const char* fallback) {
  const std::string text = property(document, name, fallback);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    throw ConfigError(fmt::format("{}: FileHeader property {}=\"{}\": expected JSON", document.reader.file().string(),
                                  name, text));
  }
}

/// A FileHeader property of two numbers "a b", each within `range`.
std::pair<double, double> numberPair(const Document& document, const char* name, std::pair<double, double> fallback,
                                     const NumberRange& range) {
  const auto it = document.properties.find(name);
  if (it == document.properties.end()) return fallback;
  std::istringstream stream(it->second);
  std::vector<std::string> words;
  for (std::string word; stream >> word;) words.push_back(word);
  if (words.size() != 2) {
    throw ConfigError::field(headerWhere(document), name, it->second, "two numbers separated by a space");
  }
  return {parseReal(words[0], range, headerWhere(document), fmt::format("{} (first number)", name)),
          parseReal(words[1], range, headerWhere(document), fmt::format("{} (second number)", name))};
}

const Entity& findEgo(const Document& document) {
  const Entity* ego = nullptr;
  for (const auto& entity : document.entities) {
    if (!entity.controller) continue;
    if (ego) {
      document.reader.fail(entity.node, fmt::format("'{}' and '{}' both have a controller; the supported subset has "
                                                    "one controller-driven vehicle (the Ego)",
                                                    ego->name, entity.name));
    }
    ego = &entity;
  }
  if (!ego) {
    document.reader.fail(document.entities.front().node,
                         "no vehicle has a controller (assign the Ego's with an AssignControllerAction in the Init)");
  }
  return *ego;
}

void readRoadSpec(const Document& document, scenario::LogicalScenario& logical) {
  const road::RoadGeometry& road = document.road.geometry;
  double lowest = road.centre.front().x();
  double highest = lowest;
  for (const auto& point : road.centre) {
    lowest = std::min(lowest, point.x());
    highest = std::max(highest, point.x());
  }
  const auto [x_min, x_max] = numberPair(document, names::kRegion, {lowest, highest}, scenario_bounds::kRegionEnd);
  if (!(x_min < x_max) || x_max - x_min > scenario_bounds::kMaxExtent) {
    throw ConfigError::field(headerWhere(document), names::kRegion, property(document, names::kRegion, ""),
                             fmt::format("x_min < x_max, at most {} m apart", xml::number(scenario_bounds::kMaxExtent)));
  }
  const auto [before, after] = numberPair(document, names::kExtension, {0.0, 0.0}, scenario_bounds::kExtension);
  logical.road.xMin = x_min;
  logical.road.xMax = x_max;
  logical.road.extensionBefore = before;
  logical.road.extensionAfter = after;
  logical.road.lanes = road.lanes;
  if (scenario::oneLaneWidth(road.laneWidths)) {
    logical.road.laneWidth = scenario::Expression::constant(road.laneWidths.front());
  } else {
    for (const double width : road.laneWidths) logical.road.laneWidths.push_back(scenario::Expression::constant(width));
  }
  logical.road.speedLimit = road.speedLimit;
  logical.road.points = static_cast<int>(std::count_if(road.centre.begin(), road.centre.end(), [&](const Vec2& p) {
    return p.x() >= x_min - 1e-6 && p.x() <= x_max + 1e-6;
  }));
}

/// A Property holding one number per step (e.g. a heading disturbance in rad).
std::vector<double> perStepValues(const xml::Reader& reader, const pugi::xml_node& property, int steps) {
  const std::string name = reader.text(property, "name");
  std::istringstream stream(reader.text(property, "value"));
  std::vector<double> values;
  for (std::string word; stream >> word;) {
    if (values.size() == static_cast<std::size_t>(steps)) break;
    // rad: a disturbance of more than a half turn per step is no disturbance.
    values.push_back(parseReal(word, NumberRange::closed(-kPi, kPi), reader.where(property),
                               fmt::format("{}[{}]", name, values.size())));
  }
  std::string rest;
  if (values.size() != static_cast<std::size_t>(steps) || (stream >> rest)) {
    reader.fail(property, fmt::format("{}: expected {} numbers (one per step)", name, steps));
  }
  return values;
}

/// The Ego's controller: its name, parameters (numeric Properties), disturbances and library.
void readController(const Document& document, const Entity& ego, scenario::LogicalScenario& logical,
                    scenario::ConcreteScenario& concrete) {
  const xml::Reader& reader = document.reader;
  const pugi::xml_node controller = ego.controller;
  reader.requireSubset(controller, {"Properties"});
  auto& spec = logical.ego.controller;
  spec.name = reader.text(controller, "name");
  spec.where = reader.where(controller);
  concrete.ego.headingNoise.assign(static_cast<std::size_t>(logical.steps()), 0.0);
  const pugi::xml_node properties = reader.only(controller, "Properties");
  reader.requireSubset(properties, {"Property"});
  for (const pugi::xml_node& property : properties.children("Property")) {
    const std::string name = reader.text(property, "name");
    if (name == names::kLibrary) {
      // A plugin is code: a file from elsewhere may load one only from its own folder.
      spec.library = requirePathInside(fs::absolute(reader.file()).parent_path(), reader.text(property, "value"),
                                       reader.where(property), names::kLibrary);
    } else if (name == names::kHeadingDisturbance) {
      concrete.ego.headingNoise = perStepValues(reader, property, logical.steps());
    } else if (name != names::kDescription) {
      const double value = parseReal(reader.text(property, "value"), NumberRange::any(), reader.where(property), name);
      spec.params.emplace_back(name, scenario::Expression::constant(value));
      concrete.controllerParams.emplace_back(name, value);
    }
  }
}

scenario::VehicleSpec vehicleSpec(const Entity& entity, const std::string& where) {
  scenario::VehicleSpec spec;
  spec.id = entity.name;
  spec.lane = entity.lane;
  spec.length = entity.length;
  spec.width = entity.width;
  spec.x = scenario::Expression::constant(entity.position->x());
  spec.where = where;
  return spec;
}

scenario::ConcreteVehicle concreteVehicle(const Entity& entity, double speed) {
  scenario::ConcreteVehicle vehicle;
  vehicle.id = entity.name;
  vehicle.lane = entity.lane;
  vehicle.length = entity.length;
  vehicle.width = entity.width;
  vehicle.x = entity.position->x();
  vehicle.speed = speed;
  return vehicle;
}

void readSumoOptions(const Document& document, scenario::LogicalScenario& logical) {
  const std::string where = document.reader.file().string() + ": FileHeader properties";
  try {
    logical.sumo.collisionAction = property(document, names::kCollisionAction, logical.sumo.collisionAction);
    if (!isCollisionAction(logical.sumo.collisionAction)) {
      throw ConfigError::field(headerWhere(document), names::kCollisionAction, logical.sumo.collisionAction,
                               collisionActionsExpected());
    }
    logical.sumo.sumoOptions = jsonProperty(document, names::kSumoOptions, "[]").get<std::vector<std::string>>();
    logical.sumo.netconvertOptions = jsonProperty(document, names::kNetconvertOptions, "[]").get<std::vector<std::string>>();
    checkScenarioToolOptions(SumoTool::Sumo, logical.sumo.sumoOptions, headerWhere(document), names::kSumoOptions);
    checkScenarioToolOptions(SumoTool::Netconvert, logical.sumo.netconvertOptions, headerWhere(document),
                             names::kNetconvertOptions);
    logical.metrics = jsonProperty(document, names::kMetrics, "[]").get<std::vector<std::string>>();
    for (const auto& criterion : jsonProperty(document, names::kCriteria, "[]")) {
      logical.criteria.push_back({criterion.at("name").get<std::string>(), criterion.at("fail_if").get<std::string>(),
                                  where + " " + names::kCriteria});
    }
  } catch (const nlohmann::json::exception& error) {
    throw ConfigError(fmt::format("{}: unexpected structure ({})", where, error.what()));
  }
}

ImportedScenario buildScenario(const Document& document, const fs::path& xosc) {
  auto logical = std::make_shared<scenario::LogicalScenario>();
  ImportedScenario imported;
  scenario::ConcreteScenario& concrete = imported.concrete;
  logical->name = property(document, names::kFunctionalScenario, xosc.stem().string());
  logical->description = "imported from " + xosc.filename().string();
  logical->sourceFile = xosc;
  logical->step = document.step;
  logical->duration = document.duration;
  for (const auto& [name, value] : document.parameters) {
    scenario::InputSpec input;
    input.name = name;
    input.distribution.kind = scenario::Distribution::Kind::Constant;
    input.distribution.value = scenario::Expression::constant(value);
    logical->inputs.push_back(input);
    concrete.inputs.push_back(value);
  }
  readRoadSpec(document, *logical);
  readSumoOptions(document, *logical);

  const Entity& ego = findEgo(document);
  logical->ego = vehicleSpec(ego, document.reader.where(ego.node));
  logical->ego.speed = scenario::Expression::constant(ego.initialSpeed);
  concrete.ego = concreteVehicle(ego, ego.initialSpeed);
  readController(document, ego, *logical, concrete);  // after: it sets the Ego's disturbance
  for (const auto& entity : document.entities) {
    if (&entity == &ego) continue;
    logical->others.push_back(vehicleSpec(entity, document.reader.where(entity.node)));
    scenario::ConcreteVehicle other = concreteVehicle(entity, entity.initialSpeed);
    other.scriptedSpeed = speedProfile(entity, logical->steps(), logical->step);
    other.headingNoise = entity.headingDisturbance
                             ? perStepValues(document.reader, entity.headingDisturbance, logical->steps())
                             : std::vector<double>(static_cast<std::size_t>(logical->steps()), 0.0);
    concrete.others.push_back(std::move(other));
  }

  concrete.seed = parseUnsigned(property(document, names::kSeed, "0"), std::numeric_limits<std::uint64_t>::max(),
                                headerWhere(document), names::kSeed);
  concrete.index = parseUnsigned(property(document, names::kSample, "0"), scenario_bounds::kMaxSampleIndex,
                                 headerWhere(document), names::kSample);
  concrete.laneWidths = document.road.geometry.laneWidths;
  imported.road = document.road.geometry;
  imported.road.regionBegin = 0;
  imported.road.regionEnd = imported.road.centre.size();
  concrete.logical = logical;
  imported.logical = logical;
  return imported;
}

}  // namespace

ImportedScenario importOpenScenario(const fs::path& xosc, const ImportOptions& options) {
  xml::Reader reader(xosc, read_limits::kScenario);
  const pugi::xml_node root = reader.root();
  if (std::string(root.name()) != "OpenSCENARIO") reader.fail(root, "expected the root element <OpenSCENARIO>");
  if (root.child("Catalog") || root.child("ParameterValueDistribution")) {
    reader.fail(root, "this is a catalog or a parameter distribution; `vsd-sumo run` takes a concrete scenario");
  }
  reader.requireSubset(root, {"FileHeader", "ParameterDeclarations", "CatalogLocations", "RoadNetwork", "Entities",
                              "Storyboard"});
  Document document{reader, readFileHeader(reader, root), readParameters(reader, root), {}, {}, 0.0, 0.0};
  const pugi::xml_node network = reader.only(root, "RoadNetwork");
  reader.requireSubset(network, {"LogicFile", "SceneGraphFile"});
  const pugi::xml_node logic = reader.only(network, "LogicFile");
  // The road network must lie next to the scenario file or below it (never /dev/zero, never ../../elsewhere).
  const fs::path xodr = requirePathInside(fs::absolute(xosc).parent_path(), reader.text(logic, "filepath"),
                                          reader.where(logic), "filepath");
  if (!fs::exists(xodr)) {
    reader.fail(network.child("LogicFile"), fmt::format("the road network {} does not exist", xodr.string()));
  }
  document.road = readOpenDrive(xodr);
  readEntities(document, root);
  const pugi::xml_node storyboard = reader.only(root, "Storyboard");
  reader.requireSubset(storyboard, {"Init", "Story", "StopTrigger"});
  readTimeBase(document, storyboard, options);
  readInit(document, storyboard);
  readStories(document, storyboard);
  ImportedScenario imported = buildScenario(document, xosc);
  imported.roadFile = xodr;
  imported.roadId = document.road.id;
  return imported;
}

}  // namespace vsd::interop
