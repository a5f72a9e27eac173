// Writes concrete scenarios as OpenSCENARIO 1.2 (see openscenario.hpp for the layout).

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include <cmath>
#include <ctime>

#include "openscenario_names.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/interop/opendrive.hpp"
#include "vsd/interop/openscenario.hpp"
#include "vsd/sim/vehicle_model.hpp"
#include "xml_support.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

// vsd-sumo's vehicles have no height and no axles, but the schema requires them:
// nominal values, documented in the README; readers of vsd-sumo ignore them.
constexpr double kNominalHeight = 1.5;          // m
constexpr double kNominalWheelbaseShare = 0.6;  // of the length
constexpr double kNominalWheelDiameter = 0.6;   // m
constexpr double kNominalAxleHeight = 0.3;      // m

/// Event times are multiples of the step; rounding to 1 ns keeps them readable ("0.6", not 0.6000000000000001).
std::string timeText(double seconds) { return xml::number(std::round(seconds * 1e9) / 1e9); }

void addProperty(pugi::xml_node properties, const std::string& name, const std::string& value) {
  xml::child(properties, "Property", {{"name", name}, {"value", value}});
}

std::string joinNumbers(const std::vector<double>& values) {
  std::string text;
  for (const double value : values) {
    if (!text.empty()) text += ' ';
    text += xml::number(value);
  }
  return text;
}

void addFileHeader(pugi::xml_node root, const scenario::ConcreteScenario& concrete, const ExportHeader& header) {
  const auto& logical = *concrete.logical;
  pugi::xml_node file_header =
      xml::child(root, "FileHeader",
                 {{"author", "vsd-sumo"},
                  {"date", header.date},
                  {"description", fmt::format("vsd-sumo concrete scenario: {} sample {} (seed {}) of {}", logical.name,
                                              concrete.index, concrete.seed, logical.sourceFile.filename().string())},
                  {"revMajor", std::to_string(names::kRevMajor)},
                  {"revMinor", std::to_string(names::kRevMinor)}});
  pugi::xml_node properties = file_header.append_child("Properties");
  addProperty(properties, names::kFunctionalScenario, logical.name);
  addProperty(properties, names::kScenarioFile, logical.sourceFile.string());
  if (!header.scenarioSha256.empty()) addProperty(properties, names::kScenarioSha256, header.scenarioSha256);
  addProperty(properties, names::kSeed, std::to_string(concrete.seed));
  addProperty(properties, names::kSample, std::to_string(concrete.index));
  addProperty(properties, names::kStep, xml::number(logical.step));
  addProperty(properties, names::kRegion, xml::number(logical.road.xMin) + " " + xml::number(logical.road.xMax));
  addProperty(properties, names::kExtension,
              xml::number(logical.road.extensionBefore) + " " + xml::number(logical.road.extensionAfter));
  addProperty(properties, names::kCollisionAction, logical.sumo.collisionAction);
  addProperty(properties, names::kSumoOptions, nlohmann::json(logical.sumo.sumoOptions).dump());
  addProperty(properties, names::kNetconvertOptions, nlohmann::json(logical.sumo.netconvertOptions).dump());
  addProperty(properties, names::kMetrics, nlohmann::json(logical.metrics).dump());
  nlohmann::json criteria = nlohmann::json::array();
  for (const auto& criterion : logical.criteria) criteria.push_back({{"name", criterion.name}, {"fail_if", criterion.expression}});
  addProperty(properties, names::kCriteria, criteria.dump());
  addProperty(properties, names::kToolVersion, toolVersion());
}

void addParameterDeclarations(pugi::xml_node root, const scenario::ConcreteScenario& concrete) {
  pugi::xml_node declarations = root.append_child("ParameterDeclarations");
  const auto& inputs = concrete.logical->inputs;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    xml::child(declarations, "ParameterDeclaration",
               {{"name", inputs[i].name}, {"parameterType", "double"}, {"value", xml::number(concrete.inputs[i])}});
  }
}

/// A vehicle entity. Scripted vehicles carry their per-step heading disturbance as a Property
/// (the Ego's travels with its controller).
void addVehicle(pugi::xml_node entities, const scenario::ConcreteVehicle& vehicle, double speed_limit, bool scripted) {
  pugi::xml_node object = xml::child(entities, "ScenarioObject", {{"name", vehicle.id}});
  pugi::xml_node node = xml::child(object, "Vehicle", {{"name", vehicle.id}, {"vehicleCategory", "car"}});
  pugi::xml_node box = node.append_child("BoundingBox");
  xml::child(box, "Center", {{"x", "0"}, {"y", "0"}, {"z", xml::number(0.5 * kNominalHeight)}});
  xml::child(box, "Dimensions",
             {{"height", xml::number(kNominalHeight)}, {"length", xml::number(vehicle.length)}, {"width", xml::number(vehicle.width)}});
  const sim::VehicleLimits limits;
  xml::child(node, "Performance",
             {{"maxAcceleration", xml::number(limits.maxAccel)},
              {"maxDeceleration", xml::number(limits.maxDecel)},
              {"maxSpeed", xml::number(speed_limit)}});
  const double wheelbase = kNominalWheelbaseShare * vehicle.length;
  const double max_steering = std::atan(wheelbase * limits.maxCurvature);
  pugi::xml_node axles = node.append_child("Axles");
  for (const auto& [name, x] : {std::pair{"FrontAxle", 0.5 * wheelbase}, std::pair{"RearAxle", -0.5 * wheelbase}}) {
    xml::child(axles, name,
               {{"maxSteering", xml::number(name == std::string("FrontAxle") ? max_steering : 0.0)},
                {"positionX", xml::number(x)},
                {"positionZ", xml::number(kNominalAxleHeight)},
                {"trackWidth", xml::number(vehicle.width)},
                {"wheelDiameter", xml::number(kNominalWheelDiameter)}});
  }
  pugi::xml_node properties = node.append_child("Properties");
  if (scripted) addProperty(properties, names::kHeadingDisturbance, joinNumbers(vehicle.headingNoise));
}

pugi::xml_node addPrivateAction(pugi::xml_node private_node) { return private_node.append_child("PrivateAction"); }

void addTeleport(pugi::xml_node private_node, const road::RoadGeometry& road, const scenario::ConcreteVehicle& vehicle) {
  const auto start = road::startPoseOnLane(road, vehicle.lane, vehicle.x, vehicle.id);
  const RoadCoordinate coordinate = toRoadCoordinate(road, start.position);
  const double offset = coordinate.t - road.laneOffset(vehicle.lane);
  pugi::xml_node position = addPrivateAction(private_node).append_child("TeleportAction").append_child("Position");
  xml::child(position, "LanePosition",
             {{"laneId", std::to_string(openDriveLaneId(vehicle.lane, road.lanes))},
              {"offset", xml::number(std::abs(offset) < 1e-9 ? 0.0 : offset)},
              {"roadId", names::kRoadId},
              {"s", xml::number(coordinate.s)}});
}

/// A SpeedAction that jumps to `speed` (dynamics: step).
void addSpeedAction(pugi::xml_node private_action, double speed) {
  pugi::xml_node action = private_action.append_child("LongitudinalAction").append_child("SpeedAction");
  xml::child(action, "SpeedActionDynamics", {{"dynamicsDimension", "time"}, {"dynamicsShape", "step"}, {"value", "0"}});
  xml::child(action.append_child("SpeedActionTarget"), "AbsoluteTargetSpeed", {{"value", xml::number(speed)}});
}

void addController(pugi::xml_node private_node, const scenario::ConcreteScenario& concrete) {
  const auto& spec = concrete.logical->ego.controller;
  pugi::xml_node assign = xml::child(addPrivateAction(private_node).append_child("ControllerAction"),
                                     "AssignControllerAction",
                                     {{"activateLateral", "true"}, {"activateLongitudinal", "true"}});
  pugi::xml_node controller = xml::child(assign, "Controller", {{"name", spec.name}});
  pugi::xml_node properties = controller.append_child("Properties");
  for (const auto& [name, value] : concrete.controllerParams) addProperty(properties, name, xml::number(value));
  addProperty(properties, names::kHeadingDisturbance, joinNumbers(concrete.ego.headingNoise));
  if (!spec.library.empty()) {
    // Relative library paths are relative to the scenario file; the export may live elsewhere.
    const fs::path library =
        spec.library.is_absolute() ? spec.library : fs::absolute(concrete.logical->sourceFile.parent_path() / spec.library);
    addProperty(properties, names::kLibrary, library.lexically_normal().string());
  }
}

void addInit(pugi::xml_node storyboard, const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road) {
  pugi::xml_node actions = storyboard.append_child("Init").append_child("Actions");
  auto add_vehicle = [&](const scenario::ConcreteVehicle& vehicle, bool is_ego) {
    pugi::xml_node private_node = xml::child(actions, "Private", {{"entityRef", vehicle.id}});
    addTeleport(private_node, road, vehicle);
    addSpeedAction(addPrivateAction(private_node), vehicle.speed);
    if (is_ego) addController(private_node, concrete);
  };
  add_vehicle(concrete.ego, true);
  for (const auto& other : concrete.others) add_vehicle(other, false);
}

/// <name> trigger that fires once the simulation time reaches `time`.
void addTimeTrigger(pugi::xml_node parent, const char* trigger_name, const std::string& condition_name, double time) {
  pugi::xml_node condition = xml::child(parent.append_child(trigger_name).append_child("ConditionGroup"), "Condition",
                                        {{"conditionEdge", "none"}, {"delay", "0"}, {"name", condition_name}});
  xml::child(condition.append_child("ByValueCondition"), "SimulationTimeCondition",
             {{"rule", "greaterOrEqual"}, {"value", timeText(time)}});
}

void addSpeedProfile(pugi::xml_node act, const scenario::ConcreteVehicle& vehicle, double step) {
  pugi::xml_node group = xml::child(act, "ManeuverGroup", {{"maximumExecutionCount", "1"}, {"name", vehicle.id + "_speed"}});
  xml::child(xml::child(group, "Actors", {{"selectTriggeringEntities", "false"}}), "EntityRef", {{"entityRef", vehicle.id}});
  pugi::xml_node maneuver = xml::child(group, "Maneuver", {{"name", vehicle.id + "_speed_profile"}});
  // Event k: from t_k on the vehicle drives with its scripted speed of t_k+1 (SUMO's Euler update).
  for (std::size_t k = 0; k + 1 < vehicle.scriptedSpeed.size(); ++k) {
    const std::string name = fmt::format("{}_speed_{}", vehicle.id, k);
    pugi::xml_node event =
        xml::child(maneuver, "Event", {{"maximumExecutionCount", "1"}, {"name", name}, {"priority", "override"}});
    addSpeedAction(xml::child(event, "Action", {{"name", name}}).append_child("PrivateAction"),
                   vehicle.scriptedSpeed[k + 1]);
    addTimeTrigger(event, "StartTrigger", name + "_time", static_cast<double>(k) * step);
  }
}

void addStory(pugi::xml_node storyboard, const scenario::ConcreteScenario& concrete) {
  if (concrete.others.empty()) return;
  pugi::xml_node story = xml::child(storyboard, "Story", {{"name", "scripted_vehicles"}});
  pugi::xml_node act = xml::child(story, "Act", {{"name", "speed_profiles"}});
  for (const auto& other : concrete.others) addSpeedProfile(act, other, concrete.step());
  addTimeTrigger(act, "StartTrigger", "start", 0.0);
}

}  // namespace

std::string openScenarioText(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road,
                             const std::string& xodr_name, const ExportHeader& header) {
  pugi::xml_document document;
  pugi::xml_node root = document.append_child("OpenSCENARIO");
  addFileHeader(root, concrete, header);
  addParameterDeclarations(root, concrete);
  xml::child(root.append_child("CatalogLocations").append_child("ControllerCatalog"), "Directory", {{"path", "."}});
  xml::child(root.append_child("RoadNetwork"), "LogicFile", {{"filepath", xodr_name}});
  pugi::xml_node entities = root.append_child("Entities");
  addVehicle(entities, concrete.ego, road.speedLimit, /*scripted=*/false);
  for (const auto& other : concrete.others) addVehicle(entities, other, road.speedLimit, /*scripted=*/true);
  pugi::xml_node storyboard = root.append_child("Storyboard");
  addInit(storyboard, concrete, road);
  addStory(storyboard, concrete);
  addTimeTrigger(storyboard, "StopTrigger", "duration", concrete.logical->duration);
  return xml::toText(document);
}

ExportedFiles exportConcreteScenario(const scenario::ConcreteScenario& concrete, const fs::path& dir,
                                     const std::string& stem, const ExportHeader& header) {
  const road::RoadGeometry road = road::buildRoadGeometry(concrete);
  ExportedFiles files{dir / (stem + ".xosc"), dir / (stem + ".xodr")};
  const std::string xosc = openScenarioText(concrete, road, files.xodr.filename().string(), header);
  writeOpenDrive(road, stem, files.xodr);
  writeTextFileAtomically(files.xosc, xosc);
  return files;
}

std::string controllerCatalogText(const std::map<std::string, std::string>& controllers, const std::string& date) {
  pugi::xml_document document;
  pugi::xml_node root = document.append_child("OpenSCENARIO");
  xml::child(root, "FileHeader",
             {{"author", "vsd-sumo"},
              {"date", date},
              {"description", "vsd-sumo's Ego controllers; a scenario names one and sets its parameters as Properties"},
              {"revMajor", std::to_string(names::kRevMajor)},
              {"revMinor", std::to_string(names::kRevMinor)}});
  pugi::xml_node catalog = xml::child(root, "Catalog", {{"name", "vsd_controllers"}});
  for (const auto& [name, description] : controllers) {
    pugi::xml_node controller = xml::child(catalog, "Controller", {{"name", name}});
    addProperty(controller.append_child("Properties"), names::kDescription, description);
  }
  return xml::toText(document);
}

std::string fileDate(const fs::path& file) {
  struct stat status {};
  if (::stat(file.c_str(), &status) != 0) {
    throw IoError(fmt::format("{}: cannot read its modification time", file.string()));
  }
  std::tm utc{};
  gmtime_r(&status.st_mtime, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  return text;
}

}  // namespace vsd::interop
