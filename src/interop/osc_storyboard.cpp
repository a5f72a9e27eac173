// The Storyboard of an OpenSCENARIO file: actions with their start conditions, in the
// scenario language (docs/openscenario-import.md "Storyboard").

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "osc_parameters.hpp"
#include "osc_template.hpp"
#include "vsd/core/geometry.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/trace.hpp"

namespace vsd::interop::osc {

namespace {

std::string num(double value) { return xml::number(value); }

/// A language trigger (or any node) on one line, as notes and messages show it.
std::string flowText(const YAML::Node& node) {
  YAML::Emitter flow;
  flow << YAML::Flow << node;
  return flow.c_str();
}

}  // namespace

std::string shapeOf(Translation& translation, const pugi::xml_node& dynamics, bool step_allowed) {
  const xml::Reader& reader = translation.reader;
  const std::string shape = reader.oneOf(dynamics, "dynamicsShape", {"step", "linear", "cubic", "sinusoidal"});
  if (shape == "step" && !step_allowed) {
    reader.fail(dynamics, "dynamicsShape=\"step\": a lateral jump; use linear, cubic or sinusoidal");
  }
  return shape == "sinusoidal" ? "smooth" : shape;
}

void requireLaneFrame(const xml::Reader& reader, const pugi::xml_node& node, const std::string& why) {
  const auto system = reader.optionalText(node, "coordinateSystem");
  if (system && *system != "entity" && *system != "road" && *system != "lane") {
    reader.fail(node, fmt::format("coordinateSystem=\"{}\": {}", *system, why));
  }
}

namespace {

/// A pace (rate, time or distance) of a TransitionDynamics: the key and value of the language
/// (`rate_key` for a rate, `distance` for a distance).
void pace(Translation& translation, const pugi::xml_node& dynamics, const char* rate_key, YAML::Node& action) {
  const xml::Reader& reader = translation.reader;
  const std::string dimension = reader.oneOf(dynamics, "dynamicsDimension", {"time", "rate", "distance"});
  if (dimension == "distance") {
    action["distance"] = num(reader.number(dynamics, "value", NumberRange::aboveUpTo(0.0, 1e6)));
    return;
  }
  double value = reader.number(dynamics, "value");
  if (dimension == "rate" && value < 0) {
    // The standard's range is [0, inf[; published files write signed rates, meaning the magnitude.
    translation.findings.note(reader.where(dynamics), fmt::format("rate {} read as its magnitude", num(value)));
    value = -value;
  }
  if (dimension == "rate" && value == 0) reader.fail(dynamics, "rate 0: the change would never end");
  if (value < 0) reader.fail(dynamics, fmt::format("time {} s: expected >= 0", num(value)));
  action[dimension == "rate" ? rate_key : "duration"] = num(value);
}

}  // namespace

void readAppearanceDomains(Translation& translation, const pugi::xml_node& action,
                           std::initializer_list<const char*> attributes) {
  for (const char* attribute : attributes) {
    if (translation.reader.optionalBoolean(action, attribute).value_or(false)) {
      translation.findings.note(translation.reader.where(action),
                                fmt::format("{}=\"true\": vsd-sumo simulates no lights or animations", attribute));
    }
  }
}

void unusedPace(const xml::Reader& reader, const pugi::xml_node& dynamics) {
  reader.oneOf(dynamics, "dynamicsDimension", {"time", "rate", "distance"});
  reader.number(dynamics, "value");
}

namespace {

/// The target of a lane change of `actor`: a number of lanes from its own lane (`lanes`, also
/// relative to itself), from the Ego's lane at the start (`ego_lane`, relative to the Ego), or a
/// lane of the road (`lane`: an absolute lane, or one relative to another road user that keeps
/// its lane).
YAML::Node laneTarget(Translation& translation, const Entity& actor, const pugi::xml_node& target, YAML::Node& item) {
  const xml::Reader& reader = translation.reader;
  if (std::string(target.name()) == "AbsoluteTargetLane") {
    item["lane"] = translation.road.languageLane(reader.integer(target, "value", -100, 100), reader.where(target));
    return item;
  }
  const std::string reference = reader.text(target, "entityRef");
  const long lanes = reader.integer(target, "value", -100, 100);
  // Lanes left (+) of the reference entity as it faces; the language counts to the road's left.
  const auto road_lanes = [&](const Entity& entity) { return entity.drivesAgainstRoad() ? -lanes : lanes; };
  if (reference == actor.name) {
    item["lanes"] = std::to_string(road_lanes(actor));
  } else if (reference == translation.ego->name) {
    item["ego_lane"] = std::to_string(lanes);
  } else {
    const Entity& other = translation.entity(target, reference);
    if (other.movesLaterally) reader.fail(target, fmt::format("a lane relative to '{}', who changes lanes", reference));
    item["lane"] = std::to_string(other.placement->lane + road_lanes(other));
  }
  return item;
}

YAML::Node laneChange(Translation& translation, const Entity& actor, const pugi::xml_node& action) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(action, {"LaneChangeActionDynamics", "LaneChangeTarget"});
  if (!actor.isVehicle()) reader.fail(action, "lane changes are for vehicles (the language's rule)");
  const bool of_ego = &actor == translation.ego;
  YAML::Node item;
  // Along t (left of the reference line), as esmini reads it: turned on a reversed road.
  const double target_offset =
      reader.optionalNumber(action, "targetLaneOffset", NumberRange::closed(-100.0, 100.0)).value_or(0.0);
  if (target_offset != 0.0) item["offset"] = num(translation.road.ownT(target_offset));
  const pugi::xml_node dynamics = reader.only(action, "LaneChangeActionDynamics");
  item["shape"] = shapeOf(translation, dynamics, /*step_allowed=*/of_ego);
  if (item["shape"].as<std::string>() == "step") {  // the Ego's: its lane moves at once
    unusedPace(reader, dynamics);
    translation.findings.note(reader.where(dynamics), "a step moves the lane at once: its value is not used");
  } else {
    pace(translation, dynamics, "lateral_speed", item);
    if (item["distance"]) {
      translation.findings.note(reader.where(dynamics),
                                "over a distance: it lasts the distance over its speed when it starts (esmini "
                                "follows the distance it travels: the same while its speed holds)");
    }
  }
  const pugi::xml_node target = reader.choice(reader.only(action, "LaneChangeTarget"),
                                              {"RelativeTargetLane", "AbsoluteTargetLane"});
  return laneTarget(translation, actor, target, item);
}

YAML::Node laneOffset(Translation& translation, const Entity& actor, const pugi::xml_node& action) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(action, {"LaneOffsetActionDynamics", "LaneOffsetTarget"});
  // continuous="true": the standard keeps the action running until something ends it; esmini
  // does not read the attribute and ends it where the offset is reached, as with "false" (the
  // road user holds the offset either way). The reference player's reading is followed.
  const auto endless = reader.optionalBoolean(action, "continuous");
  if (!endless) reader.fail(action, "continuous: expected true or false (the attribute is required)");
  YAML::Node item;
  if (*endless) {
    translation.findings.note(reader.where(action), "continuous=\"true\": read as esmini reads it, as \"false\": the "
                                                    "offset is held and the action ends where it is reached (the "
                                                    "standard runs it on until something ends it)");
  }
  const pugi::xml_node dynamics = reader.only(action, "LaneOffsetActionDynamics");
  reader.requireSubset(dynamics, {});
  item["shape"] = shapeOf(translation, dynamics, false);
  const auto accel = reader.optionalNumber(dynamics, "maxLateralAcc", NumberRange::above(0.0));
  if (!accel) reader.fail(dynamics, "no maxLateralAcc: the language needs a pace for a lateral offset");

  item["lateral_accel"] = num(*accel);
  const pugi::xml_node target = reader.choice(reader.only(action, "LaneOffsetTarget"),
                                              {"AbsoluteTargetLaneOffset", "RelativeTargetLaneOffset"});
  const double value = reader.number(target, "value");
  // Along t (left of the reference line), as esmini reads it: turned on a reversed road.
  double offset = translation.road.ownT(value);
  if (std::string(target.name()) == "RelativeTargetLaneOffset") {
    const Entity& other = translation.entity(target, reader.text(target, "entityRef"));
    if (&other == &actor || other.placement->lane != actor.placement->lane || other.movesLaterally) {
      reader.fail(target, "an offset relative to another road user's: the language needs one that keeps the "
                          "actor's starting lane and its own offset");
    }
    const double other_offset = other.placement->t - translation.road.laneCentreT(other.placement->lane);
    // esmini counts a relative value to the left of the reference entity as it faces (on a
    // reversed road too: its own direction is the language road's).
    offset = (other.drivesAgainstRoad() ? -value : value) + other_offset;
    if (&other == translation.ego) {
      translation.findings.note(reader.where(target), "relative to the Ego's starting offset (its controller keeps its lane)");
    }
  }
  item["offset"] = num(offset);
  return item;
}

/// m: how far a trajectory's first vertex may lie from where its pedestrian stands, and how far
/// its two vertices may lie apart along the road, for a walk straight across it.
constexpr double kCrossingTolerance = 0.05;

/// One <Vertex> of a crossing: its time (s) and where it is.
std::pair<double, Placement> crossingVertex(Translation& translation, const pugi::xml_node& vertex) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(vertex, {"Position"});
  const pugi::xml_node position = reader.only(vertex, "Position");
  reader.choice(position, {"LanePosition", "RoadPosition", "WorldPosition"});
  return {reader.number(vertex, "time", NumberRange::atLeast(0.0)), fixedPlace(translation, position)};
}

/// A <FollowTrajectoryAction> that walks a pedestrian straight across the road: an inline
/// trajectory of two timed vertices at the same place along the road, the first where the
/// pedestrian stands, at a constant pace (ASAM's 4.2.3 crosses the Ego's lane so). The
/// language's `cross` at the pace of the two vertices; any other trajectory is refused.
YAML::Node crossing(Translation& translation, const Entity& actor, const pugi::xml_node& routing) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node follow = reader.choice(routing, {"FollowTrajectoryAction"});
  if (actor.type != RoadUserType::Pedestrian) {
    reader.fail(follow, "a trajectory of a vehicle or object: the language walks pedestrians across the road only");
  }
  reader.requireSubset(follow, {"TrajectoryRef", "TimeReference", "TrajectoryFollowingMode"});
  const pugi::xml_node trajectory = reader.only(reader.only(follow, "TrajectoryRef"), "Trajectory");
  reader.requireSubset(trajectory, {"Shape"});
  if (reader.boolean(trajectory, "closed")) reader.fail(trajectory, "a closed trajectory: a crossing ends");
  const pugi::xml_node polyline = reader.choice(reader.only(trajectory, "Shape"), {"Polyline"});
  reader.requireSubset(polyline, {"Vertex"});
  std::vector<pugi::xml_node> vertices(polyline.children("Vertex").begin(), polyline.children("Vertex").end());
  if (vertices.size() != 2) {
    reader.fail(polyline, fmt::format("{} vertices: the language walks straight across the road (two)", vertices.size()));
  }
  const auto [start_time, from] = crossingVertex(translation, vertices[0]);
  const auto [end_time, to] = crossingVertex(translation, vertices[1]);
  // The walk starts with its event: a later first vertex would make the pedestrian wait there
  // first, an initial distance would start it part-way.
  if (start_time != 0.0) {
    reader.fail(vertices[0],
                fmt::format("time {} s: the crossing starts with its event (expected 0)", num(start_time)));
  }
  if (reader.optionalNumber(follow, "initialDistanceOffset").value_or(0.0) != 0.0) {
    reader.fail(follow, "initialDistanceOffset: the crossing starts where the pedestrian stands (expected 0)");
  }
  const pugi::xml_node timing = reader.only(reader.only(follow, "TimeReference"), "Timing");
  if (reader.oneOf(timing, "domainAbsoluteRelative", {"relative", "absolute"}) != "relative" ||
      reader.number(timing, "scale") != 1.0 || reader.number(timing, "offset") != 0.0) {
    reader.fail(timing, "a timing other than relative, scale 1, offset 0: the crossing starts with its event");
  }
  reader.oneOf(reader.only(follow, "TrajectoryFollowingMode"), "followingMode", {"position", "follow"});
  if (!(end_time > start_time)) reader.fail(vertices[1], "time: the second vertex must come after the first");
  if (std::abs(to.s - from.s) > kCrossingTolerance) {
    reader.fail(vertices[1], fmt::format("{} m along the road from the first vertex: the language walks straight across",
                                         num(to.s - from.s)));
  }
  const Placement& stands = *actor.placement;
  if (std::abs(from.s - stands.s) > kCrossingTolerance || std::abs(from.t - stands.t) > kCrossingTolerance) {
    reader.fail(vertices[0], fmt::format("the trajectory starts {} m along and {} m across from where '{}' stands",
                                         num(from.s - stands.s), num(from.t - stands.t), actor.name));
  }
  YAML::Node item;
  item["speed"] = num(std::abs(to.t - from.t) / (end_time - start_time));
  item["to_offset"] = num(to.t - translation.road.laneCentreT(stands.lane));
  translation.findings.mapped(reader.where(follow), fmt::format("'{}' walks across the road to {} m from its lane's "
                                                                "centre at {} m/s",
                                                                actor.name, item["to_offset"].as<std::string>(),
                                                                item["speed"].as<std::string>()));
  return item;
}

}  // namespace

namespace {

/// The target of a <RelativeTargetSpeed> into `item`: a delta to the road user's own speed, or
/// a delta or factor of another's (kept up with if `continuous`).
void relativeSpeed(Translation& translation, const Entity& actor, const pugi::xml_node& target, bool continuous,
                   YAML::Node& item) {
  const xml::Reader& reader = translation.reader;
  const double value = reader.number(target, "value");
  const bool factor = reader.oneOf(target, "speedTargetValueType", {"delta", "factor"}) == "factor";
  const Entity& reference = translation.entity(target, reader.text(target, "entityRef"));
  if (&reference == &actor && !continuous && !factor) {
    item["delta"] = num(value);
    return;
  }
  if (&reference == &actor) {
    reader.fail(target, "a speed relative to the road user's own that is continuous or a factor: it would follow "
                        "itself (the language adds a fixed delta to its own speed)");
  }
  item[factor ? "relative_factor" : "relative_target"] = num(value);
  if (&reference != translation.ego) item["to"] = reference.id;
  if (continuous) {
    item["continuous"] = true;
    const char* relation = factor ? "a factor of" : "a delta to";
    translation.findings.mapped(reader.where(target),
                                fmt::format("'{}' keeps {} the speed of '{}'", actor.name, relation, reference.name));
  }
}

/// A moving action of a stationary object is refused.
void refuseStationary(const xml::Reader& reader, const Entity& actor, const pugi::xml_node& action) {
  if (actor.type == RoadUserType::StationaryObject) {
    reader.fail(action, "stationary objects never move (the language's rule)");
  }
}

}  // namespace

YAML::Node speedAction(Translation& translation, const Entity& actor, const pugi::xml_node& action) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(action, {"SpeedActionDynamics", "SpeedActionTarget"});
  refuseStationary(reader, actor, action);
  const double facing = actor.placement ? std::abs(actor.placement->heading) : 0.0;
  const pugi::xml_node absolute = action.child("SpeedActionTarget").child("AbsoluteTargetSpeed");
  if (!actor.isVehicle() && facing > 1e-9 && !(absolute && reader.number(absolute, "value") == 0.0)) {
    // The language moves road users along the road: one facing off it stands until it crosses.
    reader.fail(action,
                fmt::format("a speed for '{}', which faces {} deg off the road: the language's road users move "
                            "along the road, so one facing off it stands (a crossing: a FollowTrajectoryAction)",
                            actor.name, num(facing * 180.0 / kPi)));
  }
  YAML::Node item;
  const pugi::xml_node dynamics = reader.only(action, "SpeedActionDynamics");
  reader.requireSubset(dynamics, {});
  item["shape"] = shapeOf(translation, dynamics, true);
  if (item["shape"].as<std::string>() != "step") {
    pace(translation, dynamics, "rate", item);
  } else {
    unusedPace(reader, dynamics);
  }
  const pugi::xml_node target = reader.choice(reader.only(action, "SpeedActionTarget"),
                                              {"AbsoluteTargetSpeed", "RelativeTargetSpeed"});
  const double value = reader.number(target, "value");
  if (std::string(target.name()) == "AbsoluteTargetSpeed") {
    item["target"] = num(value);
    return item;
  }
  const bool continuous = reader.boolean(target, "continuous");
  if (continuous && item["shape"].as<std::string>() != "step") {
    reader.fail(dynamics, fmt::format("dynamicsShape=\"{}\" with a continuous target: the language follows the other's "
                                      "speed at once (step)",
                                      reader.text(dynamics, "dynamicsShape")));
  }
  if (!continuous && item["shape"].as<std::string>() != "step" && reader.text(target, "entityRef") != actor.name) {
    // The standard does not say whether the target moves with its reference during the change.
    translation.findings.note(reader.where(target),
                              fmt::format("the target is the reference's speed {} m/s when the change starts (esmini "
                                          "follows the reference's speed until it is reached)",
                                          value < 0 ? "less " + num(-value) : "plus " + num(value)));
  }
  relativeSpeed(translation, actor, target, continuous, item);
  return item;
}

YAML::Node egoSetSpeed(Translation& translation, const pugi::xml_node& action) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(action, {"SpeedActionDynamics", "SpeedActionTarget"});
  const pugi::xml_node dynamics = reader.only(action, "SpeedActionDynamics");
  reader.requireSubset(dynamics, {});
  shapeOf(translation, dynamics, true);
  unusedPace(reader, dynamics);
  const pugi::xml_node target = reader.choice(reader.only(action, "SpeedActionTarget"),
                                              {"AbsoluteTargetSpeed", "RelativeTargetSpeed"});
  if (std::string(target.name()) != "AbsoluteTargetSpeed") {
    reader.fail(target, "a relative speed of the Ego: the language sets its controller's set speed, an absolute one");
  }
  const double value = reader.number(target, "value", NumberRange::closed(0.0, 1e3));
  translation.findings.mapped(reader.where(action),
                              fmt::format("the Ego's controller takes {} m/s as its set speed and reaches it its own "
                                          "way (the dynamics are not followed)",
                                          num(value)));
  YAML::Node item;
  item["target"] = num(value);
  return item;
}

YAML::Node continuousSpeed(Translation& translation, const Entity& actor, const pugi::xml_node& target) {
  YAML::Node item;
  item["shape"] = "step";
  relativeSpeed(translation, actor, target, /*continuous=*/true, item);
  return item;
}

namespace {

/// Mark the items privateAction returns for an ActivateControllerAction and for an
/// AssignControllerAction of the Ego (no language actions of their own).
constexpr const char* kActivation = "activate_controller";
constexpr const char* kAssignment = "assign_controller";

/// The domains an activation switches on (the others it switches off): "true" (both),
/// "longitudinal", "lateral" or "none" (the item privateAction marks with kActivation).
std::string activationOf(bool longitudinal, bool lateral) {
  return longitudinal && lateral ? "true" : longitudinal ? "longitudinal" : lateral ? "lateral" : "none";
}

/// The language's controller an AssignControllerAction of the Ego names (through the controller
/// map; `script` is keep_lane for the Ego: it follows its script there). Its
/// activateLateral/activateLongitudinal attributes (OpenSCENARIO 1.2) mark `item` as an
/// activation too; an ActivateControllerAction beside them must agree.
YAML::Node assignedController(Translation& translation, const pugi::xml_node& assign, YAML::Node& item) {
  const xml::Reader& reader = translation.reader;
  std::string where;
  const std::string name = controllerName(translation, *translation.catalogs, assign, where);
  ControllerChoice choice = translation.controllerMap.choice(name, where);
  if (choice.name == kFollowsItsScript) {
    // The Ego follows its script where this controller drives: it keeps its speed and lane.
    choice = {kKeepsItsLane, YAML::Node(), {}};
    translation.findings.note(where, fmt::format("controller '{}' is mapped to '{}': the Ego follows its script where "
                                                 "it drives (keeps its speed and lane: vsd-sumo's '{}')",
                                                 name, kFollowsItsScript, kKeepsItsLane));
  }
  const bool lateral = reader.optionalBoolean(assign, "activateLateral").value_or(false);
  const bool longitudinal = reader.optionalBoolean(assign, "activateLongitudinal").value_or(false);
  if (lateral || longitudinal) {
    const std::string domains = activationOf(longitudinal, lateral);
    if (item[kActivation] && item[kActivation].as<std::string>() != domains) {
      reader.fail(assign, "activateLateral / activateLongitudinal differ from the ActivateControllerAction beside "
                          "them");
    }
    item[kActivation] = domains;
  }
  const YAML::Node controller = choice.languageNode();
  translation.findings.mapped(where, fmt::format("the Ego's controller '{}' is vsd-sumo's '{}' (its properties are "
                                                 "not passed on)",
                                                 name, choice.name));
  return controller;
}

/// A teleport that lands `actor` facing `heading` (rad, relative to the road's direction) is
/// refused unless that is the heading it has: the language keeps it.
void refuseTurn(const Translation& translation, const Entity& actor, const pugi::xml_node& position, double heading) {
  const double turn = wrapAngle(heading - actor.placement->heading);
  if (std::abs(turn) > 1e-3) {
    translation.reader.fail(position, fmt::format("a heading {} rad from the one '{}' has: a teleported road user "
                                                  "keeps its heading in the language (it drives on along its lane)",
                                                  num(turn), actor.name));
  }
}

/// Whether a position lies in the plane relative to a road user (RelativeObjectPosition,
/// RelativeWorldPosition).
bool inPlane(const pugi::xml_node& kind) {
  const std::string name = kind.name();
  return name == "RelativeObjectPosition" || name == "RelativeWorldPosition";
}

/// The language's place `{from, dx, dy}` of a RelativeObjectPosition: in the road user's own
/// axes from its reference point, where the file measures from (the language's plane places
/// do); of a RelativeWorldPosition, `axes: frame`: the world's axes turned into the scenario
/// frame's, whose x runs along the road where it starts.
YAML::Node objectPlace(Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(position, {});
  if (reader.optionalNumber(position, "dz").value_or(0.0) != 0.0) {
    reader.fail(position, "dz: vsd-sumo is planar (expected 0)");
  }
  // Measured from reference points: every road user carries its own.
  translation.measuresReferencePoints = true;
  YAML::Node item;
  item["from"] = translation.entity(position, reader.text(position, "entityRef")).id;
  const double dx = reader.number(position, "dx");
  const double dy = reader.number(position, "dy");
  if (std::string(position.name()) == "RelativeObjectPosition") {
    item["dx"] = num(dx);
    item["dy"] = num(dy);
    return item;
  }
  const double heading = frameHeading(translation.road);
  const double cos_h = std::cos(heading);
  const double sin_h = std::sin(heading);
  item["dx"] = num(cos_h * dx + sin_h * dy);
  item["dy"] = num(-sin_h * dx + cos_h * dy);
  item["axes"] = "frame";
  return item;
}

/// The language's place (`{from, ds, lanes[, offset]}` or `{from, ds, dd}`) of a
/// RelativeLanePosition or RelativeRoadPosition: relative to that road user where it is when
/// the place is asked for, from its centre to the centre of what is placed there, which lies
/// `centre_ahead` m ahead of the place along the road (the file's ds runs between reference
/// points; dLane counts lane ids as the Init reads them).
YAML::Node relativePlace(Translation& translation, const pugi::xml_node& position, double centre_ahead) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(position, {});
  if (inPlane(position)) return objectPlace(translation, position);
  const CarriagewayRoad& road = translation.road;
  if (!road.oneCurvature) {
    reader.fail(position, "a place relative to a road user on a road of several curvatures: esmini's ds runs "
                          "along the reference line, the language's along the lanes' centre line");
  }
  // m along the lanes' centre line per m of reference line (an arc's are parallel).
  const double stretch = 1.0 - road.curvature * road.centreT();
  const Entity& reference = translation.entity(position, reader.text(position, "entityRef"));
  // m its centre lies ahead of its reference point along the road's direction
  const double reference_ahead = reference.drivesAgainstRoad() ? -reference.centreAhead : reference.centreAhead;
  YAML::Node item;
  item["from"] = reference.id;
  if (std::string(position.name()) == "RelativeRoadPosition") {
    item["ds"] = num(road.ownDs(reader.number(position, "ds")) * stretch + centre_ahead - reference_ahead);
    item["dd"] = num(road.ownT(reader.number(position, "dt")));
    return item;
  }
  if (position.attribute("dsLane")) reader.fail(position, "dsLane: use ds (along the road's reference line)");
  const double ds = road.ownDs(reader.optionalNumber(position, "ds").value_or(0.0)) * stretch;
  item["ds"] = num(ds + centre_ahead - reference_ahead);
  item["lanes"] = std::to_string(road.ownLaneId(reader.integer(position, "dLane", -100, 100)));
  const double offset = road.ownT(reader.optionalNumber(position, "offset").value_or(0.0));
  if (offset != 0.0) item["offset"] = num(offset);
  return item;
}

/// The positions a teleport or a distance condition reads: fixed places, and places relative
/// to a road user; the chosen one.
pugi::xml_node placeKind(const xml::Reader& reader, const pugi::xml_node& position) {
  return reader.choice(position, {"WorldPosition", "LanePosition", "RoadPosition", "RelativeLanePosition",
                                   "RelativeRoadPosition", "RelativeObjectPosition", "RelativeWorldPosition"});
}

bool isRelative(const pugi::xml_node& kind) { return std::string(kind.name()).rfind("Relative", 0) == 0; }

/// A Story <TeleportAction> of a scripted road user: its reference point lands on a place that
/// does not move (its centre that far ahead along its heading), which must keep its heading,
/// or relative to a road user (relativePlace).
YAML::Node teleport(Translation& translation, const Entity& actor, const pugi::xml_node& action) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(action, {"Position"});
  refuseStationary(reader, actor, action);
  const pugi::xml_node position = reader.only(action, "Position");
  const pugi::xml_node kind = placeKind(reader, position);
  if (isRelative(kind)) {
    // Without an Orientation esmini faces it along the file's reference line, at a place in the
    // plane as its road user faces (the same while it drives along its lane: noted).
    const bool object = inPlane(kind);
    const Entity* reference = object ? &translation.entity(kind, reader.text(kind, "entityRef")) : nullptr;
    refuseTurn(translation, actor, kind,
               object && reference->placement ? reference->placement->heading : translation.road.reversed ? kPi : 0.0);
    if (object) {
      translation.findings.note(reader.where(kind), fmt::format("'{}' lands facing along its lane (esmini: as '{}' "
                                                                "faces, the same while it drives along its lane on a "
                                                                "straight road; on a bend the road turns between them)",
                                                                actor.name, reference->name));
    }
    return relativePlace(translation, kind, actor.drivesAgainstRoad() ? -actor.centreAhead : actor.centreAhead);
  }
  const Placement p = fixedPlace(translation, position);
  refuseTurn(translation, actor, position.first_child(), p.heading);
  const LanguagePlace place = languagePlace(translation.road, p, actor.centreAhead, /*keep_lane=*/true);
  YAML::Node item;
  item["s"] = num(place.s);
  item["lane"] = std::to_string(place.lane);
  if (place.offset != 0.0) item["offset"] = num(place.offset);
  return item;
}

/// The language's action (without trigger) for one <PrivateAction> of `actor`.
std::optional<YAML::Node> privateAction(Translation& translation, Entity& actor, const pugi::xml_node& node) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node action =
      reader.choice(node, {"LongitudinalAction", "LateralAction", "ControllerAction", "ActivateControllerAction",
                           "RoutingAction", "TeleportAction"});
  const std::string kind = action.name();
  // OpenSCENARIO 1.0 puts ActivateControllerAction in PrivateAction, 1.1 and 1.2 in ControllerAction.
  const pugi::xml_node activate =
      kind == "ActivateControllerAction" ? action : action.child("ActivateControllerAction");
  if (&actor == translation.ego) {
    const pugi::xml_node assign =
        kind == "ControllerAction" ? action.child("AssignControllerAction") : pugi::xml_node();
    if (activate || assign) {
      // No language action: readStories turns the Event into active_from or a controller action.
      if (kind == "ControllerAction") {
        reader.requireSubset(action, {"ActivateControllerAction", "AssignControllerAction"});
      }
      YAML::Node item;
      if (activate) {
        readAppearanceDomains(translation, activate, {"animation", "lighting"});
        // An absent domain is activated, as esmini reads it.
        item[kActivation] = activationOf(reader.optionalBoolean(activate, "longitudinal").value_or(true),
                                         reader.optionalBoolean(activate, "lateral").value_or(true));
      }
      if (assign) {
        readAppearanceDomains(translation, assign, {"activateAnimation", "activateLighting"});
        item[kAssignment] = assignedController(translation, assign, item);
      }
      return item;
    }
    if (kind == "LongitudinalAction") {
      YAML::Node item;
      item["set_speed"] = egoSetSpeed(translation, reader.choice(action, {"SpeedAction"}));
      return item;
    }
    if (kind == "LateralAction") {
      const pugi::xml_node lateral = reader.choice(action, {"LaneChangeAction", "LaneOffsetAction"});
      YAML::Node item;
      if (std::string(lateral.name()) == "LaneChangeAction") {
        item["lane_change"] = laneChange(translation, actor, lateral);
      } else {
        item["lateral_offset"] = laneOffset(translation, actor, lateral);
      }
      translation.findings.note(reader.where(lateral), "a lateral action of the Ego moves the lane its controller "
                                                       "keeps, as the file's dynamics say; the controller follows "
                                                       "its own way");
      return item;
    }
    if (kind == "TeleportAction") {
      // It lands there and its controller drives on from there.
      translation.findings.note(reader.where(action),
                                "the Ego lands there and its controller drives on (esmini leaves an Ego in place "
                                "whose controller overrides its motion, as most do by default; the teleport then "
                                "only ends its running actions)");
      YAML::Node item;
      item["teleport"] = teleport(translation, actor, action);
      return item;
    }
    reader.fail(action, "an action of the Ego: its controller drives it (the language scripts its set speed, a "
                        "SpeedAction, the lane it keeps, a LaneChangeAction or LaneOffsetAction, and moves it at "
                        "once, a TeleportAction)");
  }
  YAML::Node item;
  if (kind == "TeleportAction") {
    item["teleport"] = teleport(translation, actor, action);
    actor.movesLaterally = true;
  } else if (kind == "LongitudinalAction") {
    const pugi::xml_node speed = reader.choice(action, {"SpeedAction"});
    const pugi::xml_node dynamics = speed.child("SpeedActionDynamics");
    if (dynamics && reader.optionalText(dynamics, "dynamicsDimension") == std::optional<std::string>("rate") &&
        reader.optionalNumber(dynamics, "value") == std::optional<double>(0.0) &&
        reader.optionalText(dynamics, "dynamicsShape") != std::optional<std::string>("step")) {
      // A rate of 0 never changes the speed: the action would run without effect and never end.
      translation.findings.note(reader.where(dynamics), "rate 0: the speed never changes, the action is left out");
      return std::nullopt;
    }
    item["speed"] = speedAction(translation, actor, speed);
  } else if (kind == "LateralAction") {
    const pugi::xml_node lateral = reader.choice(action, {"LaneChangeAction", "LaneOffsetAction"});
    if (std::string(lateral.name()) == "LaneChangeAction") {
      item["lane_change"] = laneChange(translation, actor, lateral);
    } else {
      item["lateral_offset"] = laneOffset(translation, actor, lateral);
    }
    actor.movesLaterally = true;
  } else if (kind == "RoutingAction") {
    item["cross"] = crossing(translation, actor, action);
    actor.movesLaterally = true;
  } else {
    reader.fail(action, "a controller action on a scripted road user (only the Ego has a controller)");
  }
  return item;
}

}  // namespace

namespace {

/// A relation between two road users (gap, headway, TTC) as seen from `actor`: the other
/// one's language id, or a refusal if neither is the actor.
std::string counterpart(Translation& translation, const Entity& actor, const pugi::xml_node& condition,
                        const Entity& triggering, const std::string& reference) {
  const xml::Reader& reader = translation.reader;
  const Entity& reference_entity = translation.entity(condition, reference);
  if (&triggering == &actor) return reference_entity.id;
  if (&reference_entity == &actor) return triggering.id;
  reader.fail(condition, fmt::format("a condition between '{}' and '{}' starts an action of '{}': the language relates "
                                     "the acting road user to another",
                                     triggering.name, reference, actor.name));
}

/// The language's bound of a rule ("at_least" / "at_most"); `value` may change (equalTo 0 of a
/// quantity that is never negative is "at most 0").
std::string boundOf(const xml::Reader& reader, const pugi::xml_node& node, bool never_negative, double value) {
  const std::string rule = reader.oneOf(node, "rule", {"lessThan", "lessOrEqual", "greaterThan", "greaterOrEqual",
                                                       "equalTo", "notEqualTo"});
  if (rule == "greaterThan" || rule == "greaterOrEqual") return "at_least";
  if (rule == "lessThan" || rule == "lessOrEqual") return "at_most";
  if (rule == "equalTo" && never_negative && value == 0.0) return "at_most";
  reader.fail(node, fmt::format("rule=\"{}\": compared at recorded instants a value equals another only by chance; "
                                "the language fires when it is at least or at most a bound (greater*/less*; equalTo "
                                "only of 0 for a speed or distance)",
                                rule));
}

/// Speeds and accelerations: along the road user's direction (the language's), not across or up.
void requireLongitudinal(const xml::Reader& reader, const pugi::xml_node& condition) {
  const auto direction = reader.optionalText(condition, "direction");
  if (direction && *direction != "longitudinal") {
    reader.fail(condition, fmt::format("direction=\"{}\": the language measures speeds and accelerations along the road "
                                       "user's direction of motion",
                                       *direction));
  }
}

/// gap / headway / ttc of `triggering` (one of the condition's TriggeringEntities).
/// The language's `measure` of a condition's relativeDistanceType: along_lane (longitudinal),
/// lateral, or straight_line (euclidian or cartesian; also without one: OpenSCENARIO 1.1's
/// default, esmini's reading also with 1.0's alongRoute).
std::string measureOf(const xml::Reader& reader, const pugi::xml_node& condition) {
  if (!condition.attribute("relativeDistanceType")) return "straight_line";
  const std::string type = reader.oneOf(condition, "relativeDistanceType",
                                        {"longitudinal", "lateral", "euclidianDistance", "cartesianDistance"});
  return type == "longitudinal" ? "along_lane" : type == "lateral" ? "lateral" : "straight_line";
}

YAML::Node relationLeaf(Translation& translation, const Entity& actor, const Entity& triggering,
                        const pugi::xml_node& condition) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(condition, {"TimeToCollisionConditionTarget"});
  const std::string kind = condition.name();
  YAML::Node trigger;
  std::string reference;
  if (kind == "TimeToCollisionCondition") {
    const pugi::xml_node target = reader.choice(reader.only(condition, "TimeToCollisionConditionTarget"), {"EntityRef"});
    reference = reader.text(target, "entityRef");
  } else {
    reference = reader.text(condition, "entityRef");
  }
  // freespace="false": between the entities' reference points (their places in the language).
  const bool freespace = reader.boolean(condition, "freespace");
  // Longitudinal is along the lane and lateral across it in any coordinate system the language
  // has (entity, road, lane: one lane frame, the entity's while it drives along the road).
  const std::string measure = measureOf(reader, condition);
  if (measure == "lateral" && kind != "RelativeDistanceCondition") {
    reader.fail(condition, "relativeDistanceType=\"lateral\": a headway or time to collision across the lane (the "
                           "language measures them along the Ego's lane or in a straight line)");
  }
  // alongRoute (deprecated since 1.1) is read either way as the measure above, as esmini reads it.
  reader.optionalBoolean(condition, "alongRoute");
  requireLaneFrame(reader, condition, "the language measures along or across the Ego's lane or in a straight line");
  const std::string quantity = kind == "RelativeDistanceCondition" ? "gap"
                               : kind == "TimeHeadwayCondition"    ? "headway"
                                                                   : "ttc";
  const double value = reader.number(condition, "value", NumberRange::atLeast(0.0));
  // The language's gap / headway / ttc fire at most at a bound; `_at_least` at least.
  const bool at_least = boundOf(reader, condition, /*never_negative=*/quantity != "gap", value) == "at_least";
  if (at_least && quantity == "ttc") {
    // OpenSCENARIO's time to collision runs from the triggering entity to the reference ahead of
    // it and is undefined (false) otherwise; the language's is the rear one's, whichever of the
    // two that is - a lower bound would hold while the order is the other way.
    reader.fail(condition, fmt::format("rule=\"{}\": a lower bound on a time to collision measured from the "
                                       "triggering entity (the language measures from the rear one of the two, "
                                       "whichever it is)",
                                       reader.text(condition, "rule")));
  }
  trigger[at_least ? quantity + "_at_least" : quantity] = num(value);
  const std::string other = counterpart(translation, actor, condition, triggering, reference);
  if (other != "ego") trigger["to"] = other;
  if (!freespace) {
    trigger["between"] = "reference_points";
    translation.measuresReferencePoints = true;
  }
  if (measure != "along_lane") trigger["measure"] = measure;
  // OpenSCENARIO's headway is the triggering entity's, to the reference ahead of it (undefined
  // while the reference is not ahead): the language's `of`.
  if (quantity == "headway") trigger["of"] = triggering.id;
  return trigger;
}

/// The language's place of a condition's <Position>: where `subject`'s centre is when its
/// reference point (what the file measures from) is there, in its direction along the road; the place
/// itself where the file measures from the subject's body (`from_body`, freespace="true"). A
/// place relative to a road user moves with it.
YAML::Node placeOf(Translation& translation, const Entity& subject, const pugi::xml_node& condition, bool from_body) {
  const CarriagewayRoad& road = translation.road;
  const pugi::xml_node position = translation.reader.only(condition, "Position");
  // m along the road's direction (against it for a road user driving that way)
  const double centre_ahead = from_body                   ? 0.0
                              : subject.drivesAgainstRoad() ? -subject.centreAhead
                                                            : subject.centreAhead;
  if (centre_ahead != 0.0) {
    translation.findings.note(translation.where(condition),
                              fmt::format("measured at the centre of '{}': the position moves {} m along the road, where "
                                          "its centre is when its reference point is there",
                                          subject.name, num(centre_ahead)));
  }
  const pugi::xml_node kind = placeKind(translation.reader, position);
  if (isRelative(kind)) return relativePlace(translation, kind, centre_ahead);
  const Placement p = fixedPlace(translation, position);
  const double stretch = 1.0 - road.curvatureAt(p.s) * p.t;
  const int lane = road.nearestLane(p.t);
  YAML::Node place;
  place["s"] = num(road.languageS(p.s + centre_ahead / stretch));
  place["lane"] = std::to_string(lane);
  const double offset = p.t - road.laneCentreT(lane);
  if (offset != 0.0) place["offset"] = num(offset);
  return place;
}

/// A DistanceCondition's measure and start: freespace="true" from the body's nearest point;
/// euclidian in a straight line (in any coordinate system, as esmini measures it); longitudinal
/// along the Ego's lane and lateral across it (in the entity, road or lane system: noted, as
/// esmini's differ from it on bends). True if it measures from the body.
bool distanceMeasure(Translation& translation, const pugi::xml_node& condition, YAML::Node& trigger) {
  const xml::Reader& reader = translation.reader;
  const bool from_body = reader.boolean(condition, "freespace");
  if (from_body) trigger["from"] = "body";
  if (reader.optionalBoolean(condition, "alongRoute").value_or(false)) {
    reader.fail(condition, "alongRoute=\"true\": the language measures a distance to a position in a straight line, "
                           "or along or across the Ego's lane (relativeDistanceType)");
  }
  const std::string measure = measureOf(reader, condition);
  const auto system = reader.optionalText(condition, "coordinateSystem").value_or("entity");
  if (system != "entity" && system != "road" && system != "lane") {
    reader.fail(condition, fmt::format("coordinateSystem=\"{}\": the language measures a straight distance in the "
                                       "plane, and longitudinal or lateral ones along or across the Ego's lane",
                                       system));
  }
  if (measure != "straight_line") {
    trigger["measure"] = measure;
    const char* way = measure == "along_lane" ? "along" : "across";
    translation.findings.note(reader.where(condition),
                              fmt::format("measured {} the Ego's starting lane (esmini measures {} {}; the same on a "
                                          "straight road while the road user drives along its lane)",
                                          way, way,
                                          system == "entity" ? "its heading, in straight lines"
                                                             : "the road's reference line"));
  }
  return from_body;
}

/// The distance conditions: ReachPosition (within a tolerance) and Distance to a position.
YAML::Node distanceLeaf(Translation& translation, const Entity& subject, const pugi::xml_node& condition) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(condition, {"Position"});
  YAML::Node trigger;
  bool from_body = false;
  if (std::string(condition.name()) == "ReachPositionCondition") {
    const pugi::xml_node place = reader.only(condition, "Position").first_child();
    if (const pugi::xml_node orientation = place.child("Orientation")) {
      reader.fail(orientation, "a heading to reach (esmini also requires it within 0.05 rad): the language's "
                               "condition is a place only");
    }
    trigger["distance_at_most"] = num(reader.number(condition, "tolerance", NumberRange::atLeast(0.0)));
  } else {
    from_body = distanceMeasure(translation, condition, trigger);
    const double value = reader.number(condition, "value", NumberRange::atLeast(0.0));
    trigger["distance_" + boundOf(reader, condition, true, value)] = num(value);
  }
  // At a place relative to a road user in the plane the language measures from the reference
  // point too, where the file measures from.
  const pugi::xml_node kind = placeKind(reader, reader.only(condition, "Position"));
  if (inPlane(kind)) {
    if (!from_body) trigger["from"] = "reference_point";
    trigger["position"] = objectPlace(translation, kind);
    return trigger;
  }
  trigger["position"] = placeOf(translation, subject, condition, from_body);
  return trigger;
}

/// One triggering entity's condition on its own motion (speed, acceleration, distance, road end).
YAML::Node motionLeaf(Translation& translation, const Entity& actor, const Entity& subject,
                      const pugi::xml_node& condition) {
  const xml::Reader& reader = translation.reader;
  const std::string kind = condition.name();
  YAML::Node trigger;
  if (kind == "ReachPositionCondition" || kind == "DistanceCondition") {
    trigger = distanceLeaf(translation, subject, condition);
  } else if (kind == "EndOfRoadCondition") {
    reader.requireSubset(condition, {});
    const double region = regionLength(translation.road);
    if (translation.road.languageS(translation.road.length) > region + 1e-6) {
      reader.fail(condition, fmt::format("the road goes on beyond vsd-sumo's region ({} m): the language's end of road is "
                                         "the region's end", num(region)));
    }
    trigger["end_of_road"] = num(reader.number(condition, "duration", NumberRange::atLeast(0.0)));
    const double front = subject.centreAhead + 0.5 * subject.length;  // m ahead of its reference point
    if (front > 0.0) {
      translation.findings.note(translation.where(condition),
                                fmt::format("measured at the front of '{}', {} m ahead of its reference point "
                                            "(OpenSCENARIO's): it holds that much earlier",
                                            subject.name, num(front)));
    }
  } else if (kind == "TraveledDistanceCondition") {
    reader.requireSubset(condition, {});
    trigger["travelled"] = num(reader.number(condition, "value", NumberRange::atLeast(0.0)));
  } else {
    reader.requireSubset(condition, {});
    requireLongitudinal(reader, condition);
    if (kind == "AccelerationCondition" && !condition.attribute("direction")) {
      translation.findings.note(translation.where(condition),
                                fmt::format("no direction: OpenSCENARIO compares the total acceleration (esmini: "
                                            "lateral included); the language compares the change of speed of '{}', "
                                            "the same while it neither turns nor changes lanes",
                                            subject.name));
    }
    const double value = reader.number(condition, "value");
    const std::string bound = boundOf(reader, condition, kind == "SpeedCondition", value);
    const std::string quantity = kind == "SpeedCondition" ? "speed" : kind == "RelativeSpeedCondition" ? "relative_speed" : "accel";
    if (kind == "SpeedCondition" && value < 0) reader.fail(condition, fmt::format("value {}: a speed is >= 0", num(value)));
    trigger[quantity + "_" + bound] = num(value);
    if (kind == "RelativeSpeedCondition") {
      const Entity& reference = translation.entity(condition, reader.text(condition, "entityRef"));
      if (&reference == &subject) reader.fail(condition, "entityRef: the triggering entity relative to itself");
      if (reference.id != "ego") trigger["to"] = reference.id;
    }
  }
  if (&subject != &actor) trigger["of"] = subject.id;
  return trigger;
}

std::optional<YAML::Node> entityCondition(Translation& translation, const Entity& actor, const pugi::xml_node& by_entity) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(by_entity, {"TriggeringEntities", "EntityCondition"});
  const pugi::xml_node condition = reader.choice(
      reader.only(by_entity, "EntityCondition"),
      {"RelativeDistanceCondition", "TimeHeadwayCondition", "TimeToCollisionCondition", "SpeedCondition",
       "RelativeSpeedCondition", "AccelerationCondition", "ReachPositionCondition", "TraveledDistanceCondition",
       "EndOfRoadCondition", "DistanceCondition"});
  const std::string kind = condition.name();
  const bool relation = kind == "RelativeDistanceCondition" || kind == "TimeHeadwayCondition" ||
                        kind == "TimeToCollisionCondition";
  const pugi::xml_node triggering = reader.only(by_entity, "TriggeringEntities");
  reader.requireSubset(triggering, {"EntityRef"});
  const std::string rule = reader.oneOf(triggering, "triggeringEntitiesRule", {"any", "all"});
  std::vector<YAML::Node> leaves;
  for (const pugi::xml_node& ref : triggering.children("EntityRef")) {
    const Entity& subject = translation.entity(ref, reader.text(ref, "entityRef"));
    leaves.push_back(relation ? relationLeaf(translation, actor, subject, condition)
                              : motionLeaf(translation, actor, subject, condition));
  }
  if (leaves.empty()) reader.fail(triggering, "expected at least one <EntityRef>");
  if (leaves.size() == 1) return leaves.front();
  YAML::Node combined;
  for (const auto& leaf : leaves) combined[rule].push_back(leaf);  // any: one of them; all: every one
  return combined;
}

std::optional<YAML::Node> startTrigger(Translation& translation, const Entity& actor, const pugi::xml_node& event,
                                       bool note);
std::optional<YAML::Node> eventTrigger(Translation& translation, const Entity& actor, const pugi::xml_node& event,
                                       int act, bool note);
std::optional<YAML::Node> actStart(Translation& translation, const pugi::xml_node& node, int act);
std::optional<YAML::Node> actEnd(Translation& translation, const pugi::xml_node& node, int act);
bool waitsForItsAct(const Translation& translation, const Translation::ActRecord& act, const YAML::Node& trigger);

/// The Act a condition names (`node`: the condition): its index into Translation::acts.
int actNamed(Translation& translation, const pugi::xml_node& node, const std::string& name) {
  const auto found = translation.actByName.find(name);
  if (found == translation.actByName.end() || found->second < 0) {
    translation.reader.fail(node, fmt::format("storyboardElementRef=\"{}\": expected the name of one Act", name));
  }
  return found->second;
}

/// `text` as a number within `range`; nullopt if it is none (an expression, a word, out of range).
std::optional<double> realOrNothing(const std::string& text, const NumberRange& range) {
  try {
    return parseReal(text, range, "", "");
  } catch (const ConfigError&) {
    return std::nullopt;
  }
}

/// A number of a language trigger written by the import (a time, a delay); nullopt if it is an
/// expression (of a distribution's inputs) or no number >= 0.
std::optional<double> constantOf(const YAML::Node& node) {
  if (!node || !node.IsScalar()) return std::nullopt;
  return realOrNothing(node.as<std::string>(), NumberRange::atLeast(0.0));
}

/// Runs `body` with `scope` as the reader's parameters, one level deeper into Event and Act
/// starts (more than 8 levels: a cycle, refused at `node`).
template <typename Body>
auto followingStarts(Translation& translation, const pugi::xml_node& node, const ParameterValues& scope, Body body) {
  xml::Reader& reader = translation.reader;
  if (translation.eventStartsFollowed >= 8) {
    reader.fail(node, "Event and Act starts that follow each other more than 8 deep (a cycle?)");
  }
  const ParameterValues own = reader.parameters();
  ++translation.eventStartsFollowed;
  reader.setParameters(scope);
  try {
    auto result = body();
    --translation.eventStartsFollowed;
    reader.setParameters(own);
    return result;
  } catch (...) {
    --translation.eventStartsFollowed;
    reader.setParameters(own);
    throw;
  }
}

/// An Event's maximumExecutionCount, read in the parameters of its Story.
double executionsOf(Translation& translation, const pugi::xml_node& node, const Translation::EventRecord& event) {
  return followingStarts(translation, node, event.scope, [&] {
    return translation.reader.optionalNumber(event.node, "maximumExecutionCount").value_or(1.0);
  });
}

/// The language trigger of the end of an Event's action `id`: its end ({after}), or, where the
/// Event runs more than once, the end of its last run ({after, last: true}: esmini completes an
/// Event after its maximumExecutionCount runs).
YAML::Node endOf(const std::string& id, double executions) {
  YAML::Node end;
  end["after"] = id;
  if (executions > 1.0) end["last"] = true;
  return end;
}

/// Whether a language trigger holds for good once it holds - a time, an action's end, all of
/// them - so that it can start an Act (whose Events then check their own conditions).
bool isMoment(const YAML::Node& trigger) {
  if (!trigger.IsMap() || !(trigger["time"] || trigger["after"] || trigger["all"])) return false;
  for (const auto& entry : trigger) {
    const auto key = entry.first.as<std::string>();
    if (key != "time" && key != "after" && key != "last" && key != "delay" && key != "all") return false;
  }
  for (const YAML::Node& member : trigger["all"]) {
    if ((member["delay"] && member["all"]) || !isMoment(member)) return false;  // a time or an end may be delayed
  }
  return true;
}

/// `moment` with the delay of an `all` added to each of its members' instead (a later moment
/// each): it holds at the same instants, and an action repeated on it starts again at its end
/// without waiting the delay again (as esmini restarts an Event whose Act has started).
YAML::Node delayOnMembers(const YAML::Node& moment) {
  if (!moment["all"] || !moment["delay"]) return moment;
  YAML::Node result;
  for (const YAML::Node& member : moment["all"]) {
    YAML::Node copy = YAML::Clone(member);
    const double own = member["delay"] ? member["delay"].as<double>() : 0.0;
    copy["delay"] = num(own + moment["delay"].as<double>());
    result["all"].push_back(copy);
  }
  return result;
}

/// `trigger` as one that fires at a time or when an action ends ({time: t}, a delay folded
/// into the time, or {after: id} without a delay, which the condition's own delay would
/// replace); nullopt if it is any other.
std::optional<YAML::Node> timeOrActionEnd(const YAML::Node& trigger) {
  if (!trigger.IsMap()) return std::nullopt;
  for (const auto& entry : trigger) {
    const auto key = entry.first.as<std::string>();
    if (key != "time" && key != "after" && key != "last" && key != "delay") return std::nullopt;
  }
  if (trigger["after"]) return trigger["time"] || trigger["delay"] ? std::nullopt : std::optional<YAML::Node>(trigger);
  if (!trigger["time"]) return std::nullopt;
  const auto time = constantOf(trigger["time"]);
  const auto delay = trigger["delay"] ? constantOf(trigger["delay"]) : std::optional<double>(0.0);
  if (!time || !delay) return std::nullopt;
  YAML::Node folded;
  folded["time"] = num(*time + *delay);
  return folded;
}

/// When the Event `name` starts, as a trigger any road user's action can use: its own
/// StartTrigger, translated for its actor in its Story's parameters, if that is a time or an
/// action's end; nullopt: it never starts.
std::optional<YAML::Node> eventStart(Translation& translation, const pugi::xml_node& condition,
                                     const std::string& name) {
  xml::Reader& reader = translation.reader;
  const auto found = translation.events.find(name);
  if (found == translation.events.end() || !found->second.actor) {
    reader.fail(condition, fmt::format("storyboardElementRef=\"{}\": expected one Event (or an action of one) of a "
                                       "scripted road user", name));
  }
  const Translation::EventRecord& event = found->second;
  const auto start = followingStarts(translation, condition, event.scope, [&] {
    return eventTrigger(translation, *event.actor, event.node, event.act, /*note=*/false);
  });
  if (!start) return std::nullopt;
  const auto usable = timeOrActionEnd(*start);
  if (!usable) {
    const std::string flow = flowText(*start);
    reader.fail(condition, fmt::format("the start of Event '{}' ({}) is neither a time nor an action's end: another "
                                       "road user's action cannot follow it (a road user's state is measured by the "
                                       "acting one)",
                                       name, flow));
  }
  return usable;
}

/// A StoryboardElementStateCondition on a Story or an Act: a Story starts at t = 0 (it has no
/// StartTrigger) and runs until the scenario ends; an Act starts as actStart and ends as actEnd
/// say (its StopTrigger has no conditions: requireActRunsToItsEnd). nullopt: it never holds.
std::optional<YAML::Node> containerState(Translation& translation, const pugi::xml_node& condition,
                                         const std::string& type, const std::string& name, const std::string& state) {
  const xml::Reader& reader = translation.reader;
  const bool starts = state == "startTransition" || state == "runningState";
  if (type == "act" && (starts || state == "endTransition" || state == "completeState")) {
    const int act = actNamed(translation, condition, name);
    const auto moment = starts ? actStart(translation, condition, act) : actEnd(translation, condition, act);
    const std::string when = moment ? flowText(*moment) : "never";
    translation.findings.note(reader.where(condition), fmt::format("the {} of Act '{}': {}", starts ? "start" : "end",
                                                                   name, when));
    return moment;
  }
  if (!starts) {
    reader.fail(condition, fmt::format("state=\"{}\" of {} '{}': the language follows a Story's start and an Act's "
                                       "start and end (a Story runs until the scenario ends)",
                                       state, type, name));
  }
  bool found = false;
  for (const pugi::xpath_node& candidate : condition.root().select_nodes("//Story")) {
    found = found || reader.text(candidate.node(), "name") == name;
  }
  if (!found) reader.fail(condition, fmt::format("storyboardElementRef=\"{}\": no Story of that name", name));
  translation.findings.note(reader.where(condition), fmt::format("the start of Story '{}': t = 0 (every Story starts "
                                                                 "then)",
                                                                 name));
  YAML::Node trigger;
  trigger["time"] = 0;
  return trigger;
}

/// A StoryboardElementStateCondition on an Event or an action: its end is its one action's
/// end (`after`); its start (startTransition, runningState) is its Event's start (eventStart).
std::optional<YAML::Node> storyboardElementState(Translation& translation, const pugi::xml_node& condition) {
  const xml::Reader& reader = translation.reader;
  const std::string type = reader.text(condition, "storyboardElementType");
  const std::string name = reader.text(condition, "storyboardElementRef");
  const std::string state = reader.text(condition, "state");
  if (type == "act" || type == "story") return containerState(translation, condition, type, name, state);
  if (type != "action" && type != "event") {
    reader.fail(condition, fmt::format("storyboardElementType=\"{}\": the language follows a Story's start, an Act, "
                                       "an Event or an action",
                                       type));
  }
  if (state == "startTransition" || state == "runningState") {
    const auto event = translation.eventOfAction.find(name);
    return eventStart(translation, condition,
                      type == "event" ? name : event == translation.eventOfAction.end() ? "" : event->second);
  }
  if (state != "endTransition" && state != "completeState") {
    reader.fail(condition, fmt::format("state=\"{}\": the language follows an action's start or end", state));
  }
  const std::vector<std::string>* ids = nullptr;
  if (type == "action") {
    const auto found = translation.actionIds.find(name);
    if (found != translation.actionIds.end()) ids = &found->second;
  } else {
    const auto found = translation.events.find(name);
    if (found != translation.events.end() && found->second.actor) ids = &found->second.actionIds;
  }
  if (!ids || ids->size() != 1) {
    reader.fail(condition, fmt::format("storyboardElementRef=\"{}\": expected {} with one action of a scripted road "
                                       "user", name, type == "action" ? "an action" : "an Event"));
  }
  // An Event's completeState waits for its last run; its endTransition, and an action's either
  // state, come at its first end (esmini completes an action at each run's end).
  const auto event = translation.events.find(name);
  const bool last = type == "event" && state == "completeState" && event != translation.events.end();
  return endOf(ids->front(), last ? executionsOf(translation, condition, event->second) : 1.0);
}

std::optional<YAML::Node> valueCondition(Translation& translation, const pugi::xml_node& by_value) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node condition = reader.choice(by_value, {"SimulationTimeCondition", "StoryboardElementStateCondition",
                                                            "ParameterCondition"});
  reader.requireSubset(condition, {});
  const std::string kind = condition.name();
  YAML::Node trigger;
  if (kind == "SimulationTimeCondition") {
    const std::string rule = reader.oneOf(condition, "rule", {"greaterThan", "greaterOrEqual", "lessThan", "lessOrEqual",
                                                              "equalTo", "notEqualTo"});
    if (rule != "greaterThan" && rule != "greaterOrEqual") {
      reader.fail(condition, fmt::format("rule=\"{}\": the language's time trigger fires once time reaches a value", rule));
    }
    trigger["time"] = num(reader.number(condition, "value", NumberRange::atLeast(0.0)));
  } else if (kind == "StoryboardElementStateCondition") {
    return storyboardElementState(translation, condition);
  } else {
    // Parameters are constants of a concrete scenario: the condition is decided here.
    const std::string rule = reader.oneOf(condition, "rule", {"equalTo", "greaterThan", "lessThan", "greaterOrEqual",
                                                              "lessOrEqual", "notEqualTo"});
    const std::string value = reader.text(condition, "value");
    const auto parameter = reader.parameters().find(reader.text(condition, "parameterRef"));
    if (parameter == reader.parameters().end()) reader.fail(condition, "parameterRef names no declared parameter");
    bool holds = false;
    if (rule == "equalTo" || rule == "notEqualTo") {
      // Numbers compare as numbers (72 equals 72.0), anything else as text.
      const auto left = realOrNothing(parameter->second, NumberRange::any());
      const auto right = realOrNothing(value, NumberRange::any());
      const bool equal = left && right ? *left == *right : parameter->second == value;
      holds = equal == (rule == "equalTo");
    } else {
      const double left = parseReal(parameter->second, NumberRange::any(), reader.where(condition), "parameter");
      const double right = parseReal(value, NumberRange::any(), reader.where(condition), "value");
      holds = rule == "greaterThan" ? left > right : rule == "lessThan" ? left < right
              : rule == "greaterOrEqual" ? left >= right : left <= right;
    }
    if (!holds) return std::nullopt;
    trigger["time"] = "0";
  }
  return trigger;
}

/// A condition's edge (`edge`: rising, falling or risingOrFalling) on its language trigger.
/// esmini takes the edge of the condition as a whole, so one over several triggering entities
/// (an `all`/`any` of one condition per entity, whose members would each change on their own)
/// is refused. A moment (a time, actions' ends, all of them: an Act's end) rises once, when it comes.
void markEdge(const xml::Reader& reader, const pugi::xml_node& node, const std::string& edge, YAML::Node trigger) {
  if (isMoment(std::as_const(trigger))) return;
  if (std::as_const(trigger)["all"] || std::as_const(trigger)["any"]) {
    reader.fail(node, fmt::format("conditionEdge=\"{}\" over several triggering entities: the language takes the "
                                  "edge of each entity's condition, esmini of their combination",
                                  edge));
  }
  if (edge != "falling") trigger["rising"] = "true";
  if (edge != "rising") trigger["falling"] = "true";
}

/// Translation::firstCheck for one scope, restored at its end.
/// And Translation::laterAct (`act`, -1 for none), restored with it.
class FirstCheckAt {
 public:
  FirstCheckAt(Translation& translation, double time, int act = -1)
      : translation_(translation), outer_(translation.firstCheck), outerAct_(translation.laterAct) {
    translation.firstCheck = time;
    translation.laterAct = act;
  }
  ~FirstCheckAt() {
    translation_.firstCheck = outer_;
    translation_.laterAct = outerAct_;
  }
  FirstCheckAt(const FirstCheckAt&) = delete;
  FirstCheckAt& operator=(const FirstCheckAt&) = delete;

 private:
  Translation& translation_;
  double outer_;
  int outerAct_;
};

/// Whether a rising SimulationTime or Parameter condition holds when first checked (at
/// `first_check` s: a time reached by then, a parameter comparison that holds): it never rises,
/// so esmini never fires it.
bool holdsAtFirstCheck(const pugi::xml_node& by, const YAML::Node& trigger, double first_check) {
  const pugi::xml_node time = by.child("SimulationTimeCondition");
  if (!(time || by.child("ParameterCondition")) || !trigger["time"]) return false;
  // A parameter comparison that holds reads as time 0; a condition's own trigger has no delay.
  const double from = trigger["time"].as<double>();
  // greaterThan does not hold at its own value (esmini compares with a margin of 1e-6 s).
  const bool strict = time && std::string(time.attribute("rule").value()) == "greaterThan";
  return strict ? from < first_check : from <= first_check;
}

/// Whether a language trigger can stop holding and hold again: no time or action end in it.
bool canHoldAgain(const YAML::Node& trigger) {
  if (trigger["time"] || trigger["after"]) return false;
  for (const char* list : {"all", "any"}) {
    for (const YAML::Node& member : trigger[list]) {
      if (!canHoldAgain(member)) return false;
    }
  }
  return true;
}

/// esmini holds a storyboard element's startTransition and endTransition for one step and its
/// runningState while it runs: they fall (a step later, at its end), where the language's
/// states are moments that hold from then on. A falling edge on them (or either edge, which
/// a repeated Event would see twice) is refused; a completeState never falls.
void refuseEdgeOnPassingState(const xml::Reader& reader, const pugi::xml_node& state, const std::string& edge) {
  if (!state || edge == "rising" || std::string(state.attribute("state").value()) == "completeState") return;
  reader.fail(state, fmt::format("state=\"{}\" with conditionEdge=\"{}\": esmini's {} falls {}, the language's "
                                 "states hold from their moment on (use rising, or completeState)",
                                 state.attribute("state").value(), edge, state.attribute("state").value(),
                                 std::string(state.attribute("state").value()) == "runningState"
                                     ? "when the element ends"
                                     : "one step after it"));
}

/// esmini checks an Event's conditions first when its Act starts, and a rising (or
/// risingOrFalling) one that holds then never fires. For an Act that starts later, a moment
/// that may have come by then - a time, where the Act starts at actions' ends; the end of an
/// action outside the Act - cannot be decided here (a time against an Act that starts at a
/// time is: holdsAtFirstCheck), so it is refused; an end of the Act's own actions is fine.
void refuseRisingMomentOfALaterAct(const Translation& translation, const pugi::xml_node& node, const std::string& edge,
                                   const YAML::Node& result) {
  if (translation.laterAct < 0 || edge == "none" || edge == "falling" || !isMoment(result)) return;
  const Translation::ActRecord& act = translation.acts.at(static_cast<std::size_t>(translation.laterAct));
  if (waitsForItsAct(translation, act, result)) return;
  if (result["time"] && translation.firstCheck > 0.0) return;
  translation.reader.fail(node, fmt::format("conditionEdge=\"{}\" on {} in Act '{}', which starts later: esmini "
                                            "never fires it if it holds when the Act starts, which only a run can "
                                            "tell",
                                            edge, result["time"] ? "a time" : "the state of an element outside the Act",
                                            act.name));
}

/// One <Condition> without its delay; nullopt: it never holds.
std::optional<YAML::Node> condition(Translation& translation, const Entity& actor, const pugi::xml_node& node) {
  const xml::Reader& reader = translation.reader;
  const std::string edge = reader.oneOf(node, "conditionEdge", {"none", "rising", "falling", "risingOrFalling"});
  reader.requireSubset(node, {"ByValueCondition", "ByEntityCondition"});
  const pugi::xml_node by = reader.choice(node, {"ByValueCondition", "ByEntityCondition"});
  if (edge != "none") refuseEdgeOnPassingState(reader, by.child("StoryboardElementStateCondition"), edge);
  auto result = std::string(by.name()) == "ByValueCondition" ? valueCondition(translation, by)
                                                             : entityCondition(translation, actor, by);
  if (!result || edge == "none") return result;
  if (edge == "falling" && isMoment(*result)) {
    translation.findings.note(reader.where(node), fmt::format("conditionEdge=\"falling\" on a condition that holds "
                                                              "from a moment on ({}): it never falls, so it never "
                                                              "fires",
                                                              flowText(*result)));
    return std::nullopt;
  }
  if (edge != "falling" && holdsAtFirstCheck(by, *result, translation.firstCheck)) {
    const std::string when = translation.firstCheck > 0.0
                                 ? fmt::format("when its Act starts ({} s)", num(translation.firstCheck))
                                 : std::string("from t = 0");
    translation.findings.note(reader.where(node), fmt::format("conditionEdge=\"{}\" on a condition that holds {}: it "
                                                              "never rises{}, so it never fires (as esmini reads it)",
                                                              edge, when, edge == "rising" ? "" : " or falls"));
    return std::nullopt;
  }
  refuseRisingMomentOfALaterAct(translation, node, edge, *result);
  markEdge(reader, node, edge, *result);
  return result;
}

/// A <ConditionGroup>: all its conditions at one instant, plus their delay (one for the
/// group: the language delays a group as a whole); nullopt: it never holds.
std::optional<YAML::Node> conditionGroup(Translation& translation, const Entity& actor, const pugi::xml_node& group) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(group, {"Condition"});
  std::vector<YAML::Node> members;
  std::optional<double> delay;
  bool never = false;
  for (const pugi::xml_node& node : group.children("Condition")) {
    const double own = reader.number(node, "delay", NumberRange::atLeast(0.0));
    if (delay && own != *delay) {
      reader.fail(node, fmt::format("delay {} s, another condition of its group {} s: the language delays a group as a "
                                    "whole (one delay per ConditionGroup)", num(own), num(*delay)));
    }
    delay = own;
    const auto member = condition(translation, actor, node);
    if (member) members.push_back(*member);
    never = never || !member;
  }
  if (!delay) reader.fail(group, "expected at least one <Condition>");
  if (never) return std::nullopt;
  YAML::Node trigger;
  if (members.size() == 1) {
    trigger = members.front();
  } else {
    for (const auto& member : members) trigger["all"].push_back(member);
  }
  if (*delay > 0) trigger["delay"] = num(*delay);
  return trigger;
}

/// True for a StartTrigger without conditions (absent, or without a ConditionGroup): it
/// starts its element at once, as esmini reads it. Noted when empty, and when absent if
/// `note_absent` (an Event's; a Story has none, and an Act without one is common).
bool startsAtOnce(Translation& translation, const pugi::xml_node& parent, bool note_absent, bool note = true) {
  const pugi::xml_node start = parent.child("StartTrigger");
  if (start) translation.reader.requireSubset(start, {"ConditionGroup"});
  if (start && start.child("ConditionGroup")) return false;
  if (!note || (!start && !note_absent)) return true;
  const bool event = std::string(parent.name()) == "Event";
  translation.findings.note(translation.reader.where(start ? start : parent),
                            fmt::format("{} StartTrigger: <{}> starts {}", start ? "an empty" : "no", parent.name(),
                                        event ? "with its Act" : "at t = 0"));
  return true;
}

/// The language trigger of an Event's StartTrigger for `actor`: its groups ORed ({time: 0}
/// without conditions, noted if `note`: once per Event); nullopt: it never fires.
std::optional<YAML::Node> startTrigger(Translation& translation, const Entity& actor, const pugi::xml_node& event,
                                       bool note) {
  if (startsAtOnce(translation, event, /*note_absent=*/true, note)) {
    YAML::Node now;
    now["time"] = 0;
    return now;
  }
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node start = reader.only(event, "StartTrigger");
  reader.requireSubset(start, {"ConditionGroup"});
  std::vector<YAML::Node> groups;
  for (const pugi::xml_node& group : start.children("ConditionGroup")) {
    if (const auto trigger = conditionGroup(translation, actor, group)) groups.push_back(*trigger);
  }
  if (groups.empty()) return std::nullopt;
  if (groups.size() == 1) return groups.front();
  YAML::Node trigger;
  for (const auto& group : groups) trigger["any"].push_back(group);
  return trigger;
}

/// Whether an Act's StartTrigger is one simulation time of at most 0 s without a delay that
/// holds from the start: it starts the Act at t = 0 (esmini's examples write `SimulationTime > 0`
/// with a rising or risingOrFalling edge for Acts that run from the start). Other rules and
/// edges are read as any other condition (a falling edge on a time never fires, a time that
/// never comes never starts the Act).
bool startsAtZero(const Translation& translation, const pugi::xml_node& act) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node start = act.child("StartTrigger");
  const pugi::xml_node group = start.child("ConditionGroup");
  if (!group || group.next_sibling("ConditionGroup")) return false;
  const pugi::xml_node condition = group.child("Condition");
  if (!condition || condition.next_sibling("Condition")) return false;
  const pugi::xml_node time = condition.child("ByValueCondition").child("SimulationTimeCondition");
  if (!time) return false;
  const double value = reader.number(time, "value");
  if (!(value <= 0 && reader.number(condition, "delay") <= 0)) return false;
  const std::string rule = reader.optionalText(time, "rule").value_or("");
  const std::string edge = reader.optionalText(condition, "conditionEdge").value_or("");
  if (edge == "none") return rule == "greaterThan" || rule == "greaterOrEqual";
  // `> 0` rises just after the start; a time already reached when first checked never rises.
  return rule == "greaterThan" && value == 0 && (edge == "rising" || edge == "risingOrFalling");
}

/// When the Act `name` starts: at once ({time: 0}), or at the moment its StartTrigger gives
/// (a time, with its delay folded in, or actions' ends); nullopt: it never starts.
std::optional<YAML::Node> actStart(Translation& translation, const pugi::xml_node& node, int index) {
  const Translation::ActRecord& act = translation.acts.at(static_cast<std::size_t>(index));
  // An Act's conditions are checked from the Story's start (t = 0), whichever Event asks.
  const FirstCheckAt first_check(translation, 0.0);
  // Read in the parameters of the Act's Story.
  const auto start = followingStarts(translation, node, act.scope, [&]() -> std::optional<YAML::Node> {
    if (startsAtOnce(translation, act.node, /*note_absent=*/false, /*note=*/false) ||
        startsAtZero(translation, act.node)) {
      YAML::Node now;
      now["time"] = 0;
      return now;
    }
    return startTrigger(translation, translation.entities.front(), act.node, /*note=*/false);
  });
  if (!start) return std::nullopt;
  if (!isMoment(*start)) {
    translation.reader.fail(act.node.child("StartTrigger"), "an Act started by a condition on road users: the language "
                                                            "starts an Act at a time or at actions' ends (move the "
                                                            "condition to its Events)");
  }
  return timeOrActionEnd(*start).value_or(delayOnMembers(*start));
}

/// When the Act `name` ends: when every Event's action has ended its last run ({after} or {all:
/// [{after}, ...]}, endOf); nullopt: it never ends (an Event that never starts, an action that
/// never ends). Acts whose Events hand the Ego's controller over are refused.
std::optional<YAML::Node> actEnd(Translation& translation, const pugi::xml_node& node, int index) {
  const Translation::ActRecord& act = translation.acts.at(static_cast<std::size_t>(index));
  const std::string& name = act.name;
  for (const std::string& event_name : act.events) {
    const Translation::EventRecord& event = translation.events.at(event_name);
    if (!event.actor || event.actionIds.empty()) {
      translation.reader.fail(node, fmt::format("the end of Act '{}': its Event '{}' is not a run of actions of "
                                                "road users (the language follows those ends only)",
                                                name, event_name));
    }
  }
  YAML::Node ends;
  for (const std::string& event_name : act.events) {
    const Translation::EventRecord& event = translation.events.at(event_name);
    const bool starts = followingStarts(translation, node, event.scope, [&] {
      return eventTrigger(translation, *event.actor, event.node, event.act, /*note=*/false).has_value();
    });
    if (!starts) return std::nullopt;
    const double executions = executionsOf(translation, node, event);
    for (const std::string& id : event.actionIds) ends.push_back(endOf(id, executions));
  }
  if (ends.size() == 0) translation.reader.fail(node, fmt::format("the end of Act '{}': it has no Event", name));
  if (ends.size() == 1) return ends[0];
  YAML::Node all;
  all["all"] = ends;
  return all;
}

/// Whether `trigger` (an Event's own) can only hold once its Act has started: it waits for the
/// end of an action of that Act.
bool waitsForItsAct(const Translation& translation, const Translation::ActRecord& act, const YAML::Node& trigger) {
  std::set<std::string> ids;
  for (const std::string& event : act.events) {
    for (const std::string& id : translation.events.at(event).actionIds) ids.insert(id);
  }
  const auto waits = [&](const YAML::Node& node) {
    return node["after"] && ids.count(node["after"].as<std::string>()) > 0;
  };
  if (waits(trigger)) return true;
  for (const YAML::Node& member : trigger["all"]) {
    if (waits(member)) return true;
  }
  return false;
}

/// An Event's own trigger checked from `start` (a time, s) on, as OpenSCENARIO checks the
/// conditions of an Event once its Act runs: a time becomes the later of the two; any other
/// condition must hold at or after `start` (an `all` with it); a delay stays the condition's.
/// Condition groups without delays wait for the start together (an `all` of it and their `any`,
/// which a repeated action can restart on); each group with a delay waits for it on its own.
YAML::Node fromTime(const YAML::Node& start, const YAML::Node& own) {
  YAML::Node result;
  if (own["any"]) {
    const bool delays = std::any_of(own["any"].begin(), own["any"].end(),
                                    [](const YAML::Node& member) { return bool(member["delay"]); });
    if (!delays) {
      result["all"].push_back(YAML::Clone(start));
      result["all"].push_back(YAML::Clone(own));
      return result;
    }
    for (const YAML::Node& member : own["any"]) result["any"].push_back(fromTime(start, member));
    return result;
  }
  const auto from = constantOf(start["time"]);
  const auto time = own["time"] ? constantOf(own["time"]) : std::nullopt;
  if (from && time && own["time"] && (own.size() == 1 || (own.size() == 2 && own["delay"]))) {
    result["time"] = num(std::max(*from, *time));
  } else {
    result["all"].push_back(start);
    for (const YAML::Node& member : own["all"] ? own["all"] : YAML::Node(YAML::NodeType::Sequence)) {
      result["all"].push_back(member);
    }
    if (!own["all"]) {
      YAML::Node condition = YAML::Clone(own);
      condition.remove("delay");
      result["all"].push_back(condition);
    }
  }
  if (own["delay"]) result["delay"] = own["delay"];
  return result;
}

/// An Event's own trigger checked from `start` on, an Act's start that is no time (actions'
/// ends, all of them, with a delay): an `all` of that moment's members, each with the Act's
/// delay (a later moment), and of the Event's own condition (its members, if an `all`), with
/// its own delay on the whole. The members of an `all` are checked in order while the ones
/// before hold, so its conditions are first checked when the Act starts, as esmini checks
/// them (a rising moment of its own that may hold by then is refused as it is read:
/// refuseRisingMomentOfALaterAct).
YAML::Node fromMoment(const Translation& translation, const pugi::xml_node& event, const YAML::Node& start,
                      const YAML::Node& own) {
  YAML::Node result;
  // The start's members carry its delay already (delayOnMembers); the Event's carry none.
  const auto add_members = [&](const YAML::Node& trigger, bool own_delay_apart) {
    if (!trigger["all"]) {
      YAML::Node copy = YAML::Clone(trigger);
      if (own_delay_apart) copy.remove("delay");
      result["all"].push_back(copy);
      return;
    }
    for (const YAML::Node& member : trigger["all"]) result["all"].push_back(YAML::Clone(member));
  };
  for (const YAML::Node& member : own["any"]) {
    if (member["delay"]) {
      translation.reader.fail(event, "condition groups with delays in an Act that starts at actions' ends: the "
                                     "language delays the conditions of an `all` as a whole");
    }
  }
  add_members(start, false);
  add_members(own, true);
  if (own["delay"]) result["delay"] = own["delay"].as<std::string>();
  return result;
}

/// The trigger of an Event in the Act `act_name`: its own StartTrigger (startTrigger), checked
/// once the Act has started; nullopt: it never starts.
std::optional<YAML::Node> eventTrigger(Translation& translation, const Entity& actor, const pugi::xml_node& event,
                                       int act_index, bool note) {
  const auto act_start = actStart(translation, event, act_index);
  const bool at_a_time = act_start && (*act_start)["time"] && act_start->size() == 1;
  std::optional<YAML::Node> own;
  {
    // Its conditions are first checked when the Act starts (a rising one that holds then never fires).
    const double first = at_a_time ? constantOf((*act_start)["time"]).value_or(0.0) : 0.0;
    const bool later = act_start && (!at_a_time || first > 0.0);
    const FirstCheckAt first_check(translation, first, later ? act_index : -1);
    own = startTrigger(translation, actor, event, note);
  }
  if (!own || !act_start) return std::nullopt;
  const YAML::Node& start = *act_start;
  if (at_a_time && constantOf(start["time"]) == 0.0) return own;  // the Act runs from t = 0
  if (!event.child("StartTrigger").child("ConditionGroup")) return start;  // no condition of its own
  const Translation::ActRecord& act = translation.acts.at(static_cast<std::size_t>(act_index));
  if (waitsForItsAct(translation, act, *own)) return own;
  if (!at_a_time) return fromMoment(translation, event, start, *own);
  return fromTime(start, *own);
}

/// An Act's StopTrigger: an empty one never fires (accepted, noted); one with conditions would
/// cut its actions short, which the language does not do.
void requireActRunsToItsEnd(Translation& translation, const pugi::xml_node& act) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node stop = act.child("StopTrigger");
  if (!stop) return;
  reader.requireSubset(stop, {"ConditionGroup"});
  if (stop.child("ConditionGroup")) {
    reader.fail(stop, "an Act's StopTrigger with conditions: the language runs each started action to its end (end "
                      "the scenario with the Storyboard's StopTrigger or --duration)");
  }
  translation.findings.note(reader.where(stop), "an empty StopTrigger: it never fires");
}

struct PendingAction {
  Entity* actor;
  YAML::Node item;
};
struct PendingEvent {
  pugi::xml_node node;
  std::vector<PendingAction> actions;
  ParameterValues scope;  ///< the parameters its Story sees (the file's, and the Story's own)
  int executions = 1;     ///< its maximumExecutionCount
  int act = -1;           ///< the Act it is in (index into Translation::acts)
};

void readEvent(Translation& translation, const std::vector<Entity*>& actors, const pugi::xml_node& event,
               std::vector<PendingEvent>& events) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(event, {"Action", "StartTrigger"});
  const std::string priority = reader.oneOf(event, "priority", {"overwrite", "override", "parallel", "skip"});
  if (priority == "skip") reader.fail(event, "priority=\"skip\": the language starts every triggered action");
  const double executions = reader.optionalNumber(event, "maximumExecutionCount").value_or(1.0);
  if (!(executions >= 1.0 && executions <= 1e6 && std::floor(executions) == executions)) {
    reader.fail(event, fmt::format("maximumExecutionCount={}: expected a whole number 1 .. 1000000",
                                   xml::number(executions)));
  }
  PendingEvent pending{event, {}, reader.parameters(), static_cast<int>(executions), -1};
  const std::string event_name = reader.text(event, "name");
  const bool first = translation.events.count(event_name) == 0;
  Translation::EventRecord& record = translation.events[event_name];
  const Entity* first_actor = actors.empty() ? nullptr : actors.front();
  record = first ? Translation::EventRecord{event, first_actor, reader.parameters(), {}, -1}
                 : Translation::EventRecord{};  // a name given twice names no one Event
  for (const pugi::xml_node& action : event.children("Action")) {
    translation.findings.attempt([&] {
      reader.requireSubset(action, {"PrivateAction"});
      const std::string name = reader.text(action, "name");
      // An Action name in two Events names neither's start.
      const auto known = translation.eventOfAction.find(name);
      const bool unique = known == translation.eventOfAction.end() || known->second == event_name;
      translation.eventOfAction[name] = unique ? event_name : "";
      for (Entity* actor : actors) {
        const auto item = privateAction(translation, *actor, reader.only(action, "PrivateAction"));
        if (!item) continue;
        if ((*item)[kActivation] || (*item)[kAssignment]) {  // the Ego's controller: readStories takes the Event
          pending.actions.push_back({actor, *item});
          continue;
        }
        YAML::Node copy = *item;
        copy["id"] = identifier(actors.size() == 1 ? name : name + "_" + actor->name, translation.usedIds);
        translation.actionIds[name].push_back(copy["id"].as<std::string>());
        if (first) record.actionIds.push_back(copy["id"].as<std::string>());
        pending.actions.push_back({actor, copy});
        translation.findings.mapped(reader.where(action), fmt::format("action '{}' of '{}'", copy["id"].as<std::string>(),
                                                                      actor->name));
      }
    });
  }
  events.push_back(std::move(pending));
}

/// Whether the language's parser lets an action repeat on `trigger`: no time or action end
/// inside `any` (a moment at its top or inside `all` still holds when a run ends).
bool restartsOn(const YAML::Node& trigger) {
  if (trigger["any"]) return canHoldAgain(trigger);
  for (const YAML::Node& member : trigger["all"]) {
    if (!restartsOn(member)) return false;
  }
  return true;
}

/// Why an Event's own moment (a ByValueCondition) starts it once only, where esmini, after a run,
/// resets its conditions and checks them again: a storyboard element's state; an edge, which
/// rises once (esmini keeps a condition's last value through the reset); a delay, which esmini
/// waits again from the run's end while the language's moment restarts at once. nullopt: a
/// simulation time reached, or a parameter comparison that holds, with conditionEdge="none" and
/// no delay, holds on, and the action starts again at its end, as the language restarts it.
std::optional<std::string> startsOnceBecause(const xml::Reader& reader, const pugi::xml_node& condition) {
  const pugi::xml_node by_value = condition.child("ByValueCondition");
  if (!by_value) return std::nullopt;
  if (by_value.child("StoryboardElementStateCondition")) return std::string("a storyboard element's state");
  const std::string kind = by_value.child("SimulationTimeCondition") ? "a simulation time" : "a parameter comparison";
  const std::string edge = condition.attribute("conditionEdge").value();
  if (edge != "none") return fmt::format("conditionEdge=\"{}\" on {}: it changes once", edge, kind);
  const double delay = reader.number(condition, "delay", NumberRange::atLeast(0.0));
  if (delay > 0.0) {
    return fmt::format("a delay of {} s on {}: esmini waits it again after each run", xml::number(delay), kind);
  }
  return std::nullopt;
}

/// An Event that runs several times (maximumExecutionCount > 1) restarts as esmini restarts it
/// after resetting its conditions: one without conditions of its own at once (the language's
/// action on its Act's start, a moment that has come, starts again at its end), one with
/// conditions when they hold again. Moments of its own are read as startsOnceBecause says.
void requireRepeatable(const Translation& translation, const PendingEvent& event, const YAML::Node& trigger) {
  std::optional<std::string> once;
  for (const pugi::xml_node& group : event.node.child("StartTrigger").children("ConditionGroup")) {
    for (const pugi::xml_node& condition : group.children("Condition")) {
      if (!once) once = startsOnceBecause(translation.reader, condition);
    }
  }
  if (!once && !restartsOn(trigger)) once = "a time or an action's end in one of several condition groups";
  if (once) {
    translation.reader.fail(event.node, fmt::format("maximumExecutionCount={} with a start that happens once ({}): "
                                                    "the language repeats an action when its condition holds again",
                                                    event.executions, *once));
  }
}

/// An Event that may run several times (maximumExecutionCount > 1) as its action's `repeat`:
/// the language restarts an action once it has ended, when its trigger fires again.
void repeatAction(const Translation& translation, const PendingEvent& event, const YAML::Node& trigger,
                  YAML::Node& item) {
  const xml::Reader& reader = translation.reader;
  if (event.actions.size() > 1) {
    reader.fail(event.node, fmt::format("maximumExecutionCount={} on an Event of {} actions (or actors): the language "
                                        "repeats each action on its own, not an Event as a whole",
                                        event.executions, event.actions.size()));
  }
  requireRepeatable(translation, event, trigger);
  item["repeat"] = event.executions;
}

/// Whether a language trigger is a time alone (with its delay, if any).
bool startsAtATime(const YAML::Node& trigger) {
  return trigger["time"] && (trigger.size() == 1 || (trigger.size() == 2 && trigger["delay"]));
}

/// The Ego's ActivateControllerAction in an Event that starts at a time: its controller drives
/// from the first such time (the language's active_from); before, the Ego keeps its initial
/// speed on its lane, as esmini's default controller drives it. Activated in the Init, it
/// drives from t = 0 and a later activation changes nothing.
void activateEgoController(Translation& translation, const pugi::xml_node& event, const YAML::Node& trigger) {
  const xml::Reader& reader = translation.reader;
  if (!startsAtATime(trigger)) {
    const std::string flow = flowText(trigger);
    reader.fail(event, fmt::format("the Ego's ActivateControllerAction starts on {}: the language activates the "
                                   "Ego's controller at a time (its active_from)",
                                   flow));
  }
  if (translation.ego->activatedAtStart) {
    translation.findings.note(reader.where(event), "the Ego's controller drives from t = 0 (the Init activates it)");
    return;
  }
  const double at = trigger["time"].as<double>() + (trigger["delay"] ? trigger["delay"].as<double>() : 0.0);
  if (!translation.egoActiveFrom || at < *translation.egoActiveFrom) translation.egoActiveFrom = at;
  translation.findings.mapped(reader.where(event),
                              fmt::format("the Ego's controller drives from t = {} s; before, the Ego keeps its "
                                          "initial speed on its lane's centre line",
                                          num(at)));
}

/// The controller that keeps the Ego's speed and lane (it follows its script).
YAML::Node keepLane() {
  YAML::Node script;
  script["name"] = kKeepsItsLane;
  return script;
}

/// The language's controller action `controller` (a map: name, params) of the Ego for `event`,
/// driving `domains` ("true": both), started by `trigger` and repeated as the Event is.
YAML::Node egoControllerAction(Translation& translation, const PendingEvent& event, const YAML::Node& trigger,
                               YAML::Node controller, const std::string& domains, const std::string& suffix) {
  const xml::Reader& reader = translation.reader;
  controller = YAML::Clone(controller);  // the Event's assignment stays as it is
  if (domains != "true") controller["domains"] = domains;
  YAML::Node item;
  item["controller"] = controller;
  item["id"] = identifier(reader.text(event.node, "name") + suffix, translation.usedIds);
  item["trigger"] = trigger;
  if (event.executions > 1) {
    requireRepeatable(translation, event, trigger);
    item["repeat"] = event.executions;
  }
  const std::string flow = flowText(trigger);
  translation.findings.mapped(reader.where(event.node),
                              fmt::format("the Ego is handed to '{}'{} from {}", controller["name"].as<std::string>(),
                                          domains == "true" ? "" : " for its " + domains + " domain", flow));
  return item;
}

/// An Event of the Ego's controller actions: an assignment and an activation hand the Ego to
/// that controller from the Event's start (a language controller action, repeated as the Event
/// is) in the domains activated, and the domains switched off to keep_lane (the Ego follows its
/// script there); an activation alone starts the assigned controller at a time (active_from).
/// Other actions in such an Event are refused.
void takeEgoControllerEvent(Translation& translation, const PendingEvent& event, const YAML::Node& trigger) {
  const xml::Reader& reader = translation.reader;
  std::optional<YAML::Node> assigned;
  std::string activation;
  for (const auto& pending : event.actions) {
    if (pending.actor != translation.ego || !(pending.item[kAssignment] || pending.item[kActivation])) {
      reader.fail(event.node, "an Event of the Ego's controller actions with other actions: the language hands the "
                              "Ego to a controller by an action of its own (move the others to another Event)");
    }
    if (pending.item[kAssignment]) assigned = pending.item[kAssignment];
    if (!pending.item[kActivation]) continue;
    const auto domains = pending.item[kActivation].as<std::string>();
    if (!activation.empty() && activation != domains) {
      reader.fail(event.node, "activations of different domains in one Event: the language hands each Event's "
                              "domains over at once");
    }
    activation = domains;
  }
  if (activation.empty() || activation == "none") {
    reader.fail(event.node, "an AssignControllerAction of the Ego without an activation in its Event: the language "
                            "hands the Ego to a controller that drives at once (add ActivateControllerAction)");
  }
  translation.ego->actions.push_back(egoControllerAction(translation, event, trigger, *assigned, activation, ""));
  if (activation != "true") {  // the domain switched off: the Ego follows its script there
    translation.ego->actions.push_back(egoControllerAction(translation, event, trigger, keepLane(),
                                                           activation == "lateral" ? "longitudinal" : "lateral",
                                                           "_off"));
  }
  // The Ego's own controller, never activated, drives until the hand-over's time at most.
  if (!translation.ego->activatedAtStart && startsAtATime(trigger)) {
    activateEgoController(translation, event.node, trigger);
  } else if (!translation.ego->activatedAtStart && !translation.egoActiveFrom) {
    translation.findings.note(reader.where(event.node), "the Ego's own controller, never activated, drives until this "
                                                        "hand-over (its start is a condition, not a time)");
  }
}

/// An ActivateControllerAction of the Ego without an assignment in its Event: both domains on
/// start its controller (activateEgoController); both off hand the Ego to keep_lane (it follows
/// its script: keeps its speed and lane); one domain alone is refused.
void activateAlone(Translation& translation, const PendingEvent& event, const std::string& domains,
                   const YAML::Node& trigger) {
  if (domains == "true") {
    activateEgoController(translation, event.node, trigger);
    // Where the file hands the Ego over, an activation hands it back to its own controller.
    if (translation.egoHandedOver) {
      translation.ego->actions.push_back(
          egoControllerAction(translation, event, trigger, translation.controller.languageNode(), "true", ""));
    }
    return;
  }
  if (domains != "none") {
    translation.reader.fail(event.node, fmt::format("an activation of the {} domain alone: the language hands a "
                                                    "domain to a controller an Event assigns",
                                                    domains));
  }
  translation.ego->actions.push_back(egoControllerAction(translation, event, trigger, keepLane(), "true", ""));
}

/// Event priority overwrite (override in 1.2): esmini ends the running Events of its Maneuver when
/// it starts, whatever their actions' domains; each of its actions `ends` the actions of the
/// Maneuver's other Events (events[first..]), which end there if under way.
void endOverwrittenEvents(Translation& translation, std::vector<PendingEvent>& events, std::size_t first) {
  for (std::size_t e = first; e < events.size(); ++e) {
    const std::string priority = translation.reader.text(events[e].node, "priority");
    if (priority != "overwrite" && priority != "override") continue;
    YAML::Node ends;
    for (std::size_t other = first; other < events.size(); ++other) {
      if (other == e) continue;
      for (const PendingAction& action : events[other].actions) {
        if (action.item["id"]) ends.push_back(action.item["id"].as<std::string>());
      }
    }
    if (ends.size() == 0) continue;
    bool ending = false;
    for (PendingAction& action : events[e].actions) {
      if (!action.item["id"]) continue;  // the Ego's controller: done at once
      action.item["ends"] = ends;
      ending = true;
    }
    if (ending) {
      translation.findings.mapped(translation.reader.where(events[e].node),
                                  fmt::format("priority=\"{}\": its actions end those of its Maneuver's other Events "
                                              "under way where it starts (esmini ends those Events)",
                                              priority));
    }
  }
}

void readManeuverGroup(Translation& translation, const pugi::xml_node& group, std::vector<PendingEvent>& events) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(group, {"Actors", "Maneuver"});
  if (reader.number(group, "maximumExecutionCount") != 1.0) {
    reader.fail(group, "maximumExecutionCount: the language runs each action once (expected 1)");
  }
  const pugi::xml_node actors_node = reader.only(group, "Actors");
  reader.requireSubset(actors_node, {"EntityRef"});
  if (reader.boolean(actors_node, "selectTriggeringEntities")) {
    reader.fail(actors_node, "selectTriggeringEntities=\"true\": name the actors");
  }
  std::vector<Entity*> actors;
  for (const pugi::xml_node& ref : actors_node.children("EntityRef")) {
    actors.push_back(&translation.entity(ref, reader.text(ref, "entityRef")));
  }
  for (const pugi::xml_node& maneuver : group.children("Maneuver")) {
    reader.requireSubset(maneuver, {"Event"});
    const std::size_t first = events.size();
    for (const pugi::xml_node& event : maneuver.children("Event")) {
      translation.findings.attempt([&] { readEvent(translation, actors, event, events); });
    }
    endOverwrittenEvents(translation, events, first);
  }
}

/// Records the Act `act` whose Events are events[first..]: the Act of each, its Events by name.
void recordAct(Translation& translation, const pugi::xml_node& act, std::vector<PendingEvent>& events,
               std::size_t first) {
  const xml::Reader& reader = translation.reader;
  const std::string name = reader.text(act, "name");
  startsAtOnce(translation, act, /*note_absent=*/false);  // notes an empty StartTrigger, once
  const int index = static_cast<int>(translation.acts.size());
  Translation::ActRecord record{name, act, reader.parameters(), {}};
  for (std::size_t e = first; e < events.size(); ++e) {
    events[e].act = index;
    const std::string event_name = reader.text(events[e].node, "name");
    auto& known = translation.events[event_name];
    if (known.node == events[e].node) known.act = index;
    record.events.push_back(event_name);
  }
  translation.acts.push_back(std::move(record));
  // A name given twice names no one Act (for conditions on its state; its Events keep theirs).
  const bool unique = translation.actByName.count(name) == 0;
  translation.actByName[name] = unique ? index : -1;
}

/// Marks the road users that move across lanes in the file (relative lane and offset targets need to know).
void markLateralMotion(Translation& translation, const pugi::xml_node& storyboard) {
  for (const pugi::xpath_node& found : storyboard.select_nodes(".//ManeuverGroup[.//LateralAction]/Actors/EntityRef")) {
    for (auto& entity : translation.entities) {
      if (entity.name == found.node().attribute("entityRef").value()) entity.movesLaterally = true;
    }
  }
}

}  // namespace

/// A Story's own <ParameterDeclarations> (OpenSCENARIO 1.0) on top of the file's parameters:
/// in scope inside the Story only. Their values are the file's and never inputs (a parameter
/// distribution varies global parameters); constraints on them are refused.
void readStoryParameters(Translation& translation, const pugi::xml_node& story, const ParameterValues& global) {
  xml::Reader& reader = translation.reader;
  const pugi::xml_node declarations = story.child("ParameterDeclarations");
  if (!declarations) return;
  for (const pugi::xml_node& declaration : declarations.children("ParameterDeclaration")) {
    if (declaration.child("ConstraintGroup")) {
      reader.fail(declaration.child("ConstraintGroup"),
                  "a constraint on a Story's parameter: constraints apply to the file's global parameters");
    }
  }
  for (const auto& [where, what] : readParameters(reader, story, global, {}, "").notes) {
    translation.findings.note(where, what);
  }
  translation.findings.mapped(reader.where(declarations),
                              fmt::format("parameters of Story '{}', in scope inside it", reader.text(story, "name")));
}

/// An Init that activates one domain of the Ego's controller: the other is keep_lane's from
/// t = 0 (the Ego follows its script there), a language controller action.
static void keepInitiallyOffDomain(Translation& translation) {
  const Entity& ego = *translation.ego;
  if (!ego.activatedAtStart || ego.initDomains == "true") return;
  YAML::Node controller = keepLane();
  controller["domains"] = ego.initDomains == "lateral" ? "longitudinal" : "lateral";
  YAML::Node item;
  item["controller"] = controller;
  item["id"] = identifier("init_" + controller["domains"].as<std::string>() + "_off", translation.usedIds);
  item["trigger"]["time"] = 0;
  translation.ego->actions.push_back(item);
  translation.findings.note(ego.where, fmt::format("the Init activates the Ego's {} domain only: its {} domain is "
                                                   "'{}' from t = 0 (it keeps its lane or speed)",
                                                   ego.initDomains, controller["domains"].as<std::string>(),
                                                   kKeepsItsLane));
  translation.egoHandedOver = true;
}

/// An action's `ends` name only actions of the translation (an Event that never starts is left out).
void keepEndsThatStart(Translation& translation) {
  std::set<std::string> ids;
  for (const Entity& entity : translation.entities) {
    for (const auto& action : entity.actions) {
      if (action["id"]) ids.insert(action["id"].as<std::string>());
    }
  }
  for (Entity& entity : translation.entities) {
    for (auto action : entity.actions) {
      if (!static_cast<const YAML::Node&>(action)["ends"]) continue;
      YAML::Node kept;
      for (const auto& id : action["ends"]) {
        if (ids.count(id.as<std::string>())) kept.push_back(id);
      }
      if (kept.size() == 0) action.remove("ends");
      else action["ends"] = kept;
    }
  }
}

void readStories(Translation& translation, const pugi::xml_node& storyboard) {
  xml::Reader& reader = translation.reader;
  markLateralMotion(translation, storyboard);
  const ParameterValues global = reader.parameters();
  std::vector<PendingEvent> events;
  for (const pugi::xml_node& story : storyboard.children("Story")) {
    translation.findings.attempt([&] {
      reader.setParameters(global);
      reader.requireSubset(story, {"ParameterDeclarations", "Act"});
      readStoryParameters(translation, story, global);
      for (const pugi::xml_node& act : story.children("Act")) {
        translation.findings.attempt([&] {
          reader.requireSubset(act, {"ManeuverGroup", "StartTrigger", "StopTrigger"});
          requireActRunsToItsEnd(translation, act);
          const std::size_t first = events.size();
          for (const pugi::xml_node& group : act.children("ManeuverGroup")) {
            translation.findings.attempt([&] { readManeuverGroup(translation, group, events); });
          }
          recordAct(translation, act, events, first);
        });
      }
    });
  }
  for (const auto& event : events) {
    for (const auto& pending : event.actions) {
      const bool switches = pending.item[kActivation] && pending.item[kActivation].as<std::string>() != "true";
      translation.egoHandedOver = translation.egoHandedOver || pending.item[kAssignment] || switches;
    }
  }
  keepInitiallyOffDomain(translation);
  // Triggers after all actions have ids (a condition may name an action of a later Story),
  // each in its Story's parameters.
  for (auto& event : events) {
    translation.findings.attempt([&] {
      reader.setParameters(event.scope);
      const bool hands_over = std::any_of(event.actions.begin(), event.actions.end(), [](const PendingAction& pending) {
        return static_cast<bool>(pending.item[kAssignment]);
      });
      for (auto& pending : event.actions) {
        const auto trigger =
            eventTrigger(translation, *pending.actor, event.node, event.act, &pending == &event.actions.front());
        if (!trigger) {
          translation.findings.note(reader.where(event.node), "its condition never holds: the event never starts");
          return;
        }
        if (hands_over) {  // the whole Event is one controller action (its other actions are refused there)
          takeEgoControllerEvent(translation, event, *trigger);
          break;
        }
        if (pending.item[kActivation]) {  // an activation alone: the Event's other actions stay
          activateAlone(translation, event, pending.item[kActivation].as<std::string>(), *trigger);
          continue;
        }
        pending.item["trigger"] = *trigger;
        if (event.executions > 1) repeatAction(translation, event, *trigger, pending.item);
        pending.actor->actions.push_back(pending.item);
        const std::string flow = flowText(*trigger);
        const pugi::xml_node start = event.node.child("StartTrigger");
        translation.findings.mapped(reader.where(start ? start : event.node),
                                    fmt::format("start of '{}': {}", pending.item["id"].as<std::string>(), flow));
      }
    });
  }
  keepEndsThatStart(translation);
  reader.setParameters(global);
}

void readStopTrigger(Translation& translation, const pugi::xml_node& storyboard, bool window_bound) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node stop = storyboard.child("StopTrigger");
  const double step = translation.options.step.value_or(scenario::LogicalScenario{}.step);
  const double longest = window_bound ? step * kMaxWindowSteps : std::numeric_limits<double>::infinity();
  if (translation.options.duration) {
    translation.duration = *translation.options.duration;
    if (stop) {
      translation.findings.note(reader.where(stop),
                                fmt::format("--duration {} s replaces it", num(translation.duration)));
      reader.leaveAll(stop);
    }
    return;
  }
  if (!stop) reader.fail(storyboard, "no StopTrigger: pass --duration (s)");
  // One simulation time is the scenario's end. Anything else - another condition, several
  // conditions (AND) or groups (OR) - ends it at a moment only a run can tell, so the user says
  // how long to simulate.
  reader.requireSubset(stop, {"ConditionGroup"});
  const auto groups = stop.children("ConditionGroup");
  const pugi::xml_node group = stop.child("ConditionGroup");
  const auto conditions = group.children("Condition");
  const bool one = std::distance(groups.begin(), groups.end()) == 1 &&
                   std::distance(conditions.begin(), conditions.end()) == 1;
  const pugi::xml_node condition = group.child("Condition");
  const pugi::xml_node time =
      one ? condition.child("ByValueCondition").child("SimulationTimeCondition") : pugi::xml_node();
  if (!time) {
    reader.fail(one ? condition : stop,
                "a StopTrigger other than a simulation time: pass --duration (s) to say how long to simulate");
  }
  // A time reached ends the run: `>` or `>=` becoming true, or `<` or `<=` becoming false.
  const std::string rule =
      reader.oneOf(time, "rule", {"greaterThan", "greaterOrEqual", "lessThan", "lessOrEqual", "equalTo", "notEqualTo"});
  const std::string edge = reader.oneOf(condition, "conditionEdge", {"none", "rising", "falling", "risingOrFalling"});
  const bool reached = rule == "greaterThan" || rule == "greaterOrEqual";
  const bool left = rule == "lessThan" || rule == "lessOrEqual";
  if (!((reached && (edge == "none" || edge == "rising")) || (left && edge == "falling"))) {
    reader.fail(condition, fmt::format("conditionEdge=\"{}\" on rule=\"{}\": the language ends a run when a time is "
                                       "reached (greaterThan or greaterOrEqual, edge none or rising; lessThan or "
                                       "lessOrEqual, edge falling): pass --duration (s)",
                                       edge, rule));
  }
  const double end = reader.number(time, "value", NumberRange::atLeast(0.0)) +
                     reader.number(condition, "delay", NumberRange::atLeast(0.0));
  if (end > longest) {
    reader.fail(time, fmt::format("the scenario ends at {} s, beyond the longest window ({} steps, {} s): pass "
                                  "--duration (s)", num(end), kMaxWindowSteps, num(longest)));
  }
  translation.duration = end;
  translation.findings.mapped(reader.where(stop), fmt::format("simulated for {} s", num(end)));
}

}  // namespace vsd::interop::osc
