// Entities and the Init of an OpenSCENARIO file, translated into the scenario language.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>

#include "osc_template.hpp"
#include "vsd/core/numbers.hpp"

namespace vsd::interop::osc {

namespace {

/// m: a bounding box off the entity's axis by more than this is refused (the language's
/// road users are centred on their reference line).
constexpr double kAxisTolerance = 0.01;

RoadUserType categoryType(const xml::Reader& reader, const pugi::xml_node& object) {
  const std::string kind = object.name();
  // 3D models are not used (as the SceneGraphFile), nor a vehicle's role (1.2).
  reader.leave(object, {"model3d", "model", "role"});
  if (kind == "MiscObject") {
    reader.oneOf(object, "miscObjectCategory",
                 {"none", "obstacle", "pole", "tree", "vegetation", "barrier", "building", "parkingSpace", "patch",
                  "railing", "trafficIsland", "crosswalk", "streetLamp", "gantry", "soundBarrier", "wind", "roadMark"});
    return RoadUserType::StationaryObject;
  }
  if (kind == "Pedestrian") {
    const std::string category = reader.text(object, "pedestrianCategory");
    if (category != "pedestrian") {
      reader.fail(object, fmt::format("pedestrianCategory=\"{}\": the language's road users are {}", category,
                                      roadUserTypeList()));
    }
    return RoadUserType::Pedestrian;
  }
  const std::string category = reader.text(object, "vehicleCategory");
  const auto type = findRoadUserType(category);
  if (!type || !roadUserKind(*type).drivesInLanes) {
    std::vector<std::string> vehicles;
    for (const auto& entry : roadUserKinds()) {
      if (entry.drivesInLanes) vehicles.emplace_back(entry.name);
    }
    reader.fail(object, fmt::format("vehicleCategory=\"{}\": vehicles of the language are {}", category,
                                    fmt::join(vehicles, ", ")));
  }
  return *type;
}

/// m along a road user's axis from its reference point (OpenSCENARIO's, the rear axle for
/// vehicles), and across it: where its bounding box lies.
struct Body {
  double rear = 0.0;
  double front = 0.0;
  double width = 0.0;
};

/// The numbers of an object the language does not simulate (its mass, height, Performance,
/// Axles) are still numbers: a bad one is refused by name, as any other (esmini reads it as 0).
void checkNumbersNotSimulated(const xml::Reader& reader, const pugi::xml_node& object) {
  reader.optionalNumber(object, "mass", NumberRange::atLeast(0.0));
  const pugi::xml_node box = object.child("BoundingBox");
  reader.number(box.child("Dimensions"), "height", NumberRange::atLeast(0.0));
  reader.number(box.child("Center"), "z");
  if (const pugi::xml_node performance = object.child("Performance")) {
    reader.requireSubset(performance, {});
    for (const char* limit : {"maxSpeed", "maxAcceleration", "maxDeceleration"}) {
      reader.number(performance, limit, NumberRange::atLeast(0.0));
    }
    for (const char* rate : {"maxAccelerationRate", "maxDecelerationRate"}) {
      reader.optionalNumber(performance, rate, NumberRange::atLeast(0.0));
    }
  }
  if (object.child("Axles")) reader.requireSubset(object.child("Axles"), {"FrontAxle", "RearAxle", "AdditionalAxle"});
  for (const pugi::xml_node& axle : object.child("Axles").children()) {
    if (axle.type() != pugi::node_element) continue;
    reader.requireSubset(axle, {});
    for (const char* size : {"maxSteering", "wheelDiameter", "trackWidth"}) {
      reader.number(axle, size, NumberRange::atLeast(0.0));
    }
    for (const char* place : {"positionX", "positionZ"}) reader.number(axle, place);
  }
}

/// The <BoundingBox> of a <Vehicle>, <Pedestrian> or <MiscObject>.
Body boxOf(const xml::Reader& reader, const pugi::xml_node& object) {
  const pugi::xml_node box = reader.only(object, "BoundingBox");
  reader.requireSubset(box, {"Center", "Dimensions"});
  const pugi::xml_node dimensions = reader.only(box, "Dimensions");
  const double length = reader.number(dimensions, "length", scenario_bounds::kVehicleLength);
  const double width = reader.number(dimensions, "width", scenario_bounds::kVehicleWidth);
  checkNumbersNotSimulated(reader, object);
  const pugi::xml_node centre = reader.only(box, "Center");
  const double ahead = reader.number(centre, "x", NumberRange::closed(-100.0, 100.0));
  if (std::abs(reader.number(centre, "y")) > kAxisTolerance) {
    reader.fail(centre, "y: expected 0 (the language's road users are centred on their axis)");
  }
  return {ahead - length / 2, ahead + length / 2, width};
}

/// Trailers towing trailers: deeper than this is refused (a catalog entry that tows itself).
constexpr int kMaxTrailers = 4;

Body vehicleBody(Translation& translation, Catalogs& catalogs, const xml::Reader& reader,
                 const pugi::xml_node& vehicle, int towed);

/// The <Vehicle> of a trailer defined in place (OpenSCENARIO 1.3: <Trailer name> holding a
/// <Vehicle>, or a <CatalogReference> to one: then `entry` keeps the catalog file's reader).
struct TrailerVehicle {
  CatalogEntry entry;
  const xml::Reader* reader = nullptr;
  pugi::xml_node vehicle;
};

TrailerVehicle trailerVehicle(const xml::Reader& reader, Catalogs& catalogs, const pugi::xml_node& trailer) {
  reader.requireSubset(trailer, {"Vehicle", "CatalogReference"});
  const pugi::xml_node inline_or_reference = reader.choice(trailer, {"Vehicle", "CatalogReference"});
  if (std::string(inline_or_reference.name()) == "Vehicle") return {{}, &reader, inline_or_reference};
  TrailerVehicle found{catalogs.resolve(reader, inline_or_reference, {"Vehicle"}), nullptr, {}};
  found.reader = found.entry.reader.get();
  found.vehicle = found.entry.node;
  return found;
}

/// A <Vehicle>'s trailer (OpenSCENARIO 1.2/1.3). Where a trailer would attach (TrailerHitch,
/// TrailerCoupler) is harmless without one — esmini's catalog cars declare both, with a
/// <Trailer> whose TrailerRef is an empty parameter by default, which attaches none. A trailer
/// defined in place (<Trailer name>) is hitched straight behind: its coupler on the vehicle's
/// hitch, one rigid body from the vehicle's front to the trailer's rear, as wide as the wider
/// (the language has no articulated road users: on a bend the real trailer runs inside the
/// tractor's path; noted). A TrailerRef naming another entity is refused.
Body withTrailer(Translation& translation, Catalogs& catalogs, const xml::Reader& reader,
                 const pugi::xml_node& vehicle, Body body, int towed) {
  const pugi::xml_node trailer = vehicle.child("Trailer");
  if (!trailer) return body;
  reader.requireSubset(trailer, {"TrailerRef", "Trailer"});
  const pugi::xml_node attached = reader.choice(trailer, {"TrailerRef", "Trailer"});
  if (std::string(attached.name()) == "TrailerRef") {
    const std::string entity = reader.text(attached, "entityRef");
    if (!entity.empty()) {
      reader.fail(attached, fmt::format("entityRef=\"{}\": a trailer that is an entity of its own is not simulated "
                                        "(the scenario language has no articulated road users)", entity));
    }
    return body;
  }
  if (towed >= kMaxTrailers) reader.fail(attached, fmt::format("more than {} trailers in a row", kMaxTrailers));
  // Read before the trailer's entry is resolved, which may set this file's parameters anew.
  const std::string trailer_name = reader.text(attached, "name");
  const std::string where = reader.where(attached);
  const pugi::xml_node hitch = reader.only(vehicle, "TrailerHitch");
  const double hitch_ahead = reader.number(hitch, "dx", NumberRange::closed(-100.0, 100.0));
  const TrailerVehicle towed_vehicle = trailerVehicle(reader, catalogs, attached);
  const xml::Reader& towed_reader = *towed_vehicle.reader;
  const pugi::xml_node coupler = towed_reader.only(towed_vehicle.vehicle, "TrailerCoupler");
  const double coupler_ahead = towed_reader.number(coupler, "dx", NumberRange::closed(-100.0, 100.0));
  const Body towed_body = vehicleBody(translation, catalogs, towed_reader, towed_vehicle.vehicle, towed + 1);
  const double shift = hitch_ahead - coupler_ahead;  // the trailer's reference point in the vehicle's frame
  body.rear = std::min(body.rear, towed_body.rear + shift);
  body.front = std::max(body.front, towed_body.front + shift);
  body.width = std::max(body.width, towed_body.width);
  translation.findings.note(where, fmt::format("trailer '{}' hitched straight behind: one rigid road user {} m long "
                                               "(on a bend the real trailer runs inside the tractor's path)",
                                               trailer_name, xml::number(body.front - body.rear)));
  return body;
}

/// A <Vehicle>'s bounding box with the trailers it tows.
Body vehicleBody(Translation& translation, Catalogs& catalogs, const xml::Reader& reader,
                 const pugi::xml_node& vehicle, int towed) {
  reader.requireSubset(vehicle, {"ParameterDeclarations", "BoundingBox", "Performance", "Axles", "TrailerHitch",
                                 "TrailerCoupler", "Trailer", "Properties"});
  if (towed > 0) {  // a trailer is part of its tractor's body: its category is only checked
    reader.leave(vehicle, {"model3d", "role"});
    reader.oneOf(vehicle, "vehicleCategory", {"car", "van", "truck", "trailer", "semitrailer", "bus", "motorbike",
                                              "bicycle", "train", "tram"});
  }
  return withTrailer(translation, catalogs, reader, vehicle, boxOf(reader, vehicle), towed);
}

/// Type and bounding box of a <Vehicle> (with its trailers), <Pedestrian> or <MiscObject>.
void readObject(Translation& translation, Catalogs& catalogs, const xml::Reader& reader,
                const pugi::xml_node& object, Entity& entity) {
  // Its type first: a trailer from the same catalog file sets that file's parameters anew.
  entity.type = categoryType(reader, object);
  Body body;
  if (std::string(object.name()) == "Vehicle") {
    body = vehicleBody(translation, catalogs, reader, object, 0);
  } else {
    reader.requireSubset(object, {"ParameterDeclarations", "BoundingBox", "Properties"});
    body = boxOf(reader, object);
  }
  entity.length = body.front - body.rear;
  entity.width = body.width;
  entity.centreAhead = (body.front + body.rear) / 2;
}

}  // namespace

std::string controllerName(Translation& translation, Catalogs& catalogs, const pugi::xml_node& parent,
                           std::string& where, ControllerDefinition* definition) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(parent, {"Controller", "CatalogReference"});
  if (const pugi::xml_node reference = parent.child("CatalogReference")) {
    const CatalogEntry entry = catalogs.resolve(translation.reader, reference, {"Controller"});
    where = reader.where(reference);
    if (definition) *definition = {entry.reader, entry.reader.get(), entry.node};
    return entry.reader->text(entry.node, "name");
  }
  const pugi::xml_node controller = reader.only(parent, "Controller");
  where = reader.where(controller);
  if (definition) *definition = {nullptr, &reader, controller};
  return reader.text(controller, "name");
}

namespace {

void readScenarioObject(Translation& translation, Catalogs& catalogs, const pugi::xml_node& object) {
  const xml::Reader& reader = translation.reader;
  reader.requireSubset(object, {"Vehicle", "Pedestrian", "MiscObject", "CatalogReference", "ObjectController"});
  Entity entity;
  entity.name = reader.text(object, "name");
  entity.where = reader.where(object);
  for (const auto& other : translation.entities) {
    if (other.name == entity.name) reader.fail(object, fmt::format("entity name '{}' is used twice", entity.name));
  }
  // One definition (inline or from a catalog) and at most one controller (OpenSCENARIO 1.0-1.2).
  pugi::xml_node definition;
  for (const pugi::xml_node& child : object.children()) {
    if (child.type() != pugi::node_element) continue;
    const bool controller = std::string(child.name()) == "ObjectController";
    if (controller && child != object.child("ObjectController")) {
      reader.fail(child, "a second <ObjectController>: an entity has one controller (OpenSCENARIO 1.0-1.2)");
    }
    if (controller) continue;
    if (definition) {
      reader.fail(child, fmt::format("<{}> after <{}>: an entity is defined once (one of Vehicle, Pedestrian, "
                                     "MiscObject, CatalogReference)",
                                     child.name(), definition.name()));
    }
    definition = child;
  }
  if (!definition) reader.fail(object, "expected one of: Vehicle, Pedestrian, MiscObject, CatalogReference");
  if (std::string(definition.name()) == "CatalogReference") {
    const CatalogEntry entry =
        catalogs.resolve(translation.reader, definition, {"Vehicle", "Pedestrian", "MiscObject"});
    readObject(translation, catalogs, *entry.reader, entry.node, entity);
  } else {
    readObject(translation, catalogs, reader, definition, entity);
  }
  if (const pugi::xml_node controller = object.child("ObjectController")) {
    entity.controller =
        controllerName(translation, catalogs, controller, entity.controllerWhere, &entity.controllerDefinition);
  }
  translation.findings.mapped(entity.where, fmt::format("{} '{}', {} x {} m (Performance, Axles and Properties are "
                                                        "not simulated)",
                                                        roadUserKind(entity.type).name, entity.name,
                                                        xml::number(entity.length), xml::number(entity.width)));
  translation.entities.push_back(std::move(entity));
}

}  // namespace

Entity& Translation::entity(const pugi::xml_node& node, const std::string& name) {
  for (auto& candidate : entities) {
    if (candidate.name == name) return candidate;
  }
  if (refusedEntities.count(name)) {
    throw FollowsARefusal(fmt::format("{}: entityRef=\"{}\": an entity refused above", reader.where(node), name));
  }
  reader.fail(node, fmt::format("entityRef=\"{}\" names no entity of <Entities>", name));
}

void readEntities(Translation& translation, const pugi::xml_node& root, Catalogs& catalogs) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node entities = reader.only(root, "Entities");
  reader.requireSubset(entities, {"ScenarioObject"});
  for (const pugi::xml_node& object : entities.children("ScenarioObject")) {
    if (!translation.findings.attempt([&] { readScenarioObject(translation, catalogs, object); })) {
      translation.refusedEntities.insert(object.attribute("name").value());
    }
  }
  if (translation.entities.empty()) reader.fail(entities, "expected at least one <ScenarioObject> the import can use");
}

namespace {

/// An Init's ActivateControllerAction: the Ego's controller drives from t = 0, and a scripted
/// road user follows its script (which of the two the entity is, is not known yet).
void noteActivation(Translation& translation, const pugi::xml_node& action, Entity& entity) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node activate =
      std::string(action.name()) == "ActivateControllerAction" ? action : action.child("ActivateControllerAction");
  const pugi::xml_node assign = action.child("AssignControllerAction");
  if (activate) readAppearanceDomains(translation, activate, {"animation", "lighting"});
  if (assign) readAppearanceDomains(translation, assign, {"activateAnimation", "activateLighting"});
  // An absent attribute of an ActivateControllerAction activates its domain, as esmini reads it.
  const bool longitudinal = activate ? reader.optionalBoolean(activate, "longitudinal").value_or(true)
                                     : reader.optionalBoolean(assign, "activateLongitudinal").value_or(false);
  const bool lateral = activate ? reader.optionalBoolean(activate, "lateral").value_or(true)
                                : reader.optionalBoolean(assign, "activateLateral").value_or(false);
  if (!longitudinal && !lateral) return;  // nothing activated: the Ego keeps its initial speed and lane
  entity.activatedAtStart = true;
  entity.initDomains = longitudinal && lateral ? "true" : longitudinal ? "longitudinal" : "lateral";
  translation.findings.note(reader.where(action),
                            fmt::format("'{}': the Ego's controller drives {}from t = 0, a scripted road user follows "
                                        "its script",
                                        entity.name,
                                        entity.initDomains == "true" ? "" : "its " + entity.initDomains + " domain "));
}

void readInitAction(Translation& translation, Entity& entity, const pugi::xml_node& private_action) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node action = reader.choice(private_action, {"TeleportAction", "LongitudinalAction",
                                                               "LateralAction", "ControllerAction",
                                                               "ActivateControllerAction"});
  const std::string kind = action.name();
  if (kind == "TeleportAction") {
    reader.requireSubset(action, {"Position"});
    entity.position = reader.only(action, "Position");
  } else if (kind == "LongitudinalAction" && action.child("LongitudinalDistanceAction")) {
    // In the Init, a distance action with no dynamic constraints is a place: it holds from t = 0.
    entity.distanceAction = reader.choice(action, {"LongitudinalDistanceAction"});
  } else if (kind == "LongitudinalAction") {
    const pugi::xml_node speed = reader.choice(action, {"SpeedAction"});
    const pugi::xml_node dynamics = reader.only(speed, "SpeedActionDynamics");
    // A change over no time is a step, whatever its shape (esmini's override_bb: linear over 0 s).
    const bool at_once = reader.text(dynamics, "dynamicsShape") == "step" ||
                         (reader.optionalText(dynamics, "dynamicsDimension") == std::optional<std::string>("time") &&
                          reader.optionalNumber(dynamics, "value") == std::optional<double>(0.0));
    if (at_once) {
      shapeOf(translation, dynamics, /*step_allowed=*/true);
      unusedPace(reader, dynamics);
      entity.speedTarget = reader.only(speed, "SpeedActionTarget");
      if (entity.gradualSpeed) {
        // Init actions run in file order: the step ends the gradual change before it at once.
        translation.findings.note(reader.where(entity.gradualSpeed),
                                  fmt::format("replaced by the step to a speed at line {} (Init actions run in "
                                              "their order): '{}' starts at that speed",
                                              reader.line(action), entity.name));
        reader.leaveAll(entity.gradualSpeed);  // never simulated
        entity.gradualSpeed = pugi::xml_node();
      }
    } else {
      entity.gradualSpeed = speed;  // the language's speed action at t = 0, once the Ego is known
    }
  } else if (kind == "ControllerAction") {
    reader.requireSubset(action, {"AssignControllerAction", "ActivateControllerAction"});
    bool activates = static_cast<bool>(action.child("ActivateControllerAction"));
    if (const pugi::xml_node assign = action.child("AssignControllerAction")) {
      // Defined in place or a controller catalog's entry, as an ObjectController.
      entity.controller = controllerName(translation, *translation.catalogs, assign, entity.controllerWhere,
                                         &entity.controllerDefinition);
      // OpenSCENARIO 1.2 may activate the assigned controller with the assignment.
      for (const char* domain : {"activateLateral", "activateLongitudinal"}) {
        activates = activates || reader.optionalBoolean(assign, domain).value_or(false);
      }
    }
    if (activates) noteActivation(translation, action, entity);
    return;
  } else if (kind == "ActivateControllerAction") {
    noteActivation(translation, action, entity);
    return;
  } else {
    reader.fail(action, "lateral actions in the Init: start the action at t = 0 in a Story instead");
  }
  translation.findings.mapped(reader.where(action), fmt::format("start of '{}'", entity.name));
}

}  // namespace

void addInitialSpeedActions(Translation& translation) {
  const xml::Reader& reader = translation.reader;
  for (Entity& entity : translation.entities) {
    translation.findings.attempt([&] {
      YAML::Node item;
      if (&entity == translation.ego && entity.gradualSpeed) {
        // Its controller takes the target as its set speed from t = 0 and gets there its own way.
        item["set_speed"] = egoSetSpeed(translation, entity.gradualSpeed);
      } else if (entity.gradualSpeed) {
        // A gradual change from the start.
        item["speed"] = speedAction(translation, entity, entity.gradualSpeed);
      } else if (const pugi::xml_node target = entity.speedTarget.child("RelativeTargetSpeed");
                 target && reader.boolean(target, "continuous")) {
        if (&entity == translation.ego) {
          reader.fail(target, "a continuous relative speed of the Ego: its controller drives it (the language sets "
                              "its set speed, an absolute one)");
        }
        // A step to a continuous relative speed: the initial speed, and tracking from t = 0.
        item["speed"] = continuousSpeed(translation, entity, target);
      } else {
        return;
      }
      item["trigger"]["time"] = "0";
      entity.actions.push_back(item);
    });
  }
}

void readInit(Translation& translation, const pugi::xml_node& storyboard) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node actions = reader.only(reader.only(storyboard, "Init"), "Actions");
  reader.requireSubset(actions, {"Private"});
  for (const pugi::xml_node& private_node : actions.children("Private")) {
    translation.findings.attempt([&] {
      Entity& entity = translation.entity(private_node, reader.text(private_node, "entityRef"));
      reader.requireSubset(private_node, {"PrivateAction"});
      for (const pugi::xml_node& action : private_node.children("PrivateAction")) {
        translation.findings.attempt([&] { readInitAction(translation, entity, action); });
      }
    });
  }
}

}  // namespace vsd::interop::osc
