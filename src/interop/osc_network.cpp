// Network scenarios: an OpenSCENARIO file's Init on SUMO's network of its OpenDRIVE file.

#include "osc_network.hpp"

#include <fmt/format.h>

#include <pugixml.hpp>
#include <spdlog/spdlog.h>

#include <cmath>

#include "osc_catalogs.hpp"
#include "osc_parameters.hpp"
#include "osc_template.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/road/network.hpp"
#include "vsd/pipeline/map_export.hpp"

namespace fs = std::filesystem;

namespace vsd::interop::osc {

namespace {

/// a + b ds + c ds^2 + d ds^3 of an OpenDRIVE polynomial record.
double cubicAt(const xml::Reader& reader, const pugi::xml_node& record, double ds) {
  return reader.number(record, "a") + ds * (reader.number(record, "b") +
                                            ds * (reader.number(record, "c") + ds * reader.number(record, "d")));
}

/// The last record `name` under `parent` whose `key` (s or sOffset) is at most `at`, or none.
pugi::xml_node recordAt(const xml::Reader& reader, const pugi::xml_node& parent, const char* name, const char* key,
                        double at) {
  pugi::xml_node found;
  for (const pugi::xml_node& record : parent.children(name)) {
    if (reader.number(record, key) <= at + 1e-9) found = record;
  }
  return found;
}

}  // namespace

OpenDriveRoads::OpenDriveRoads(const fs::path& xodr) : reader_(xodr, read_limits::kRoadNetwork) {
  const pugi::xml_node root = reader_.root();
  if (std::string(root.name()) != "OpenDRIVE") reader_.fail(root, "expected the root element <OpenDRIVE>");
  for (const pugi::xml_node& node : root.children("road")) {
    Road road;
    road.node = node;
    road.leftHandTraffic = reader_.optionalText(node, "rule").value_or("RHT") == "LHT";
    for (const pugi::xml_node& geometry : reader_.only(node, "planView").children("geometry")) {
      road.geometries.push_back(readPlanGeometry(reader_, geometry, 0.0));
      road.length = std::max(road.length, road.geometries.back().s() + road.geometries.back().length());
    }
    if (road.geometries.empty()) reader_.fail(node, "a road without a <geometry> in its <planView>");
    for (const auto& lane : node.select_nodes(".//lane[border]")) {
      reader_.fail(lane.node(), "a lane given by its <border>: positions are evaluated on lane <width>s");
    }
    const std::string id = reader_.text(node, "id");
    if (!roads_.emplace(id, std::move(road)).second) reader_.fail(node, fmt::format("road id '{}' is given twice", id));
  }
}

const OpenDriveRoads::Road& OpenDriveRoads::road(const std::string& id, const std::string& where) const {
  const auto found = roads_.find(id);
  if (found == roads_.end()) {
    throw ConfigError(fmt::format("{}: roadId=\"{}\": {} has no road of that id", where, id, reader_.file().string()));
  }
  return found->second;
}

OpenDriveRoads::Pose OpenDriveRoads::roadPoint(const std::string& id, double s, double t,
                                               const std::string& where) const {
  const Road& road = this->road(id, where);
  if (!(s >= 0.0 && s <= road.length + 1e-9)) {
    throw ConfigError(fmt::format("{}: s = {} m is off road '{}' (0 .. {} m)", where, xml::number(s), id,
                                  xml::number(road.length)));
  }
  const PlanGeometry* geometry = &road.geometries.front();
  for (const auto& candidate : road.geometries) {
    if (candidate.s() <= s) geometry = &candidate;
  }
  const double ds = std::min(s - geometry->s(), geometry->length());
  const double heading = geometry->heading(ds);
  const Vec2 left(-std::sin(heading), std::cos(heading));
  return {geometry->point(ds) + t * left, heading};
}

double OpenDriveRoads::laneOffset(const Road& road, double s) const {
  const pugi::xml_node lanes = reader_.only(road.node, "lanes");
  const pugi::xml_node record = recordAt(reader_, lanes, "laneOffset", "s", s);
  return record ? cubicAt(reader_, record, s - reader_.number(record, "s")) : 0.0;
}

double OpenDriveRoads::laneCentreT(const std::string& id, long lane_id, double s, const std::string& where) const {
  const Road& road = this->road(id, where);
  const pugi::xml_node section = recordAt(reader_, reader_.only(road.node, "lanes"), "laneSection", "s", s);
  if (!section || lane_id == 0) {
    throw ConfigError(fmt::format("{}: laneId=\"{}\": road '{}' has no such lane at s = {} m", where, lane_id, id,
                                  xml::number(s)));
  }
  const double ds = s - reader_.number(section, "s");
  const pugi::xml_node side = section.child(lane_id > 0 ? "left" : "right");
  const auto width = [&](long lane) -> std::optional<double> {
    for (const pugi::xml_node& node : side.children("lane")) {
      if (reader_.integer(node, "id", -1000, 1000) != lane) continue;
      const pugi::xml_node record = recordAt(reader_, node, "width", "sOffset", ds);
      return record ? cubicAt(reader_, record, ds - reader_.number(record, "sOffset")) : 0.0;
    }
    return std::nullopt;
  };
  const long sign = lane_id > 0 ? 1 : -1;
  double inner = 0.0;  // m from the reference line (shifted by the lane offset) to the lane's inner edge
  for (long lane = sign; lane != lane_id; lane += sign) {
    const auto w = width(lane);
    if (!w) break;
    inner += *w;
  }
  const auto own = width(lane_id);
  if (!own) {
    throw ConfigError(fmt::format("{}: laneId=\"{}\": road '{}' has no such lane at s = {} m (its lane section from s "
                                  "= {} m)",
                                  where, lane_id, id, xml::number(s), xml::number(reader_.number(section, "s"))));
  }
  return laneOffset(road, s) + static_cast<double>(sign) * (inner + 0.5 * *own);
}

double OpenDriveRoads::laneDirection(const std::string& id, long lane_id) const {
  const auto found = roads_.find(id);
  const bool left_hand = found != roads_.end() && found->second.leftHandTraffic;
  return (lane_id > 0) != left_hand ? kPi : 0.0;
}

void OpenDriveRoads::noteElevations(Findings& findings) const {
  for (const auto& [id, road] : roads_) noteElevation(reader_, road.node, findings);
}

namespace {

/// The network scenario's reading of one file (after the parts it shares with the language's).
struct NetworkReading {
  Translation& translation;
  const OpenDriveRoads& roads;
  NetworkScenario& scenario;
};


/// Where an entity's bounding-box centre starts (file frame) and which way it faces: a world
/// position's point moved along its heading; on a road, where it faces along its lane (or the
/// reference line), the centre lies that far along the road (on a bend too), else along its heading.
OpenDriveRoads::Pose startPose(const NetworkReading& reading, const Entity& entity) {
  const xml::Reader& reader = reading.translation.reader;
  if (!entity.position) {
    reader.fail(reader.root(), fmt::format("entity '{}' has no TeleportAction in the Init", entity.name));
  }
  const pugi::xml_node position = reader.choice(entity.position, {"WorldPosition", "LanePosition", "RoadPosition"});
  const std::string kind = position.name();
  const std::string where = reader.where(position);
  const auto ahead = [&](const OpenDriveRoads::Pose& pose) {
    return OpenDriveRoads::Pose{pose.point + entity.centreAhead * headingVector(pose.heading), pose.heading};
  };
  if (kind == "WorldPosition") {
    reader.requireSubset(position, {});
    requirePlanar(reader, position);
    if (const auto z = reader.optionalNumber(position, "z"); z && *z != 0.0) {
      reading.translation.findings.note(where, fmt::format("{} m of height: vsd-sumo is planar, not simulated",
                                                           xml::number(*z)));
    }
    return ahead({Vec2(reader.number(position, "x"), reader.number(position, "y")), reader.number(position, "h")});
  }
  reader.requireSubset(position, {"Orientation"});
  const std::string road = reader.text(position, "roadId");
  const double s = reader.number(position, "s");
  const bool lane_position = kind == "LanePosition";
  const long lane = lane_position ? static_cast<long>(reader.integer(position, "laneId", -1000, 1000)) : 0;
  // rad from the reference line: the way the lane drives (a road position faces along the line).
  const double direction = lane_position ? reading.roads.laneDirection(road, lane) : 0.0;
  const auto orientation = readOrientation(reader, position);
  const double offset = lane_position ? reader.optionalNumber(position, "offset").value_or(0.0)
                                      : reader.number(position, "t");
  // t (m) of the reference point at s: on a lane, its centre (its width where it stands) plus the offset.
  const auto t_at = [&](double at) {
    return lane_position ? reading.roads.laneCentreT(road, lane, at, where) + offset : offset;
  };
  if (!orientation || (!orientation->absolute && orientation->h == 0.0)) {
    const double centre_s = s + (direction == 0.0 ? 1.0 : -1.0) * entity.centreAhead;
    const auto pose = reading.roads.roadPoint(road, centre_s, t_at(centre_s), where);
    reading.roads.roadPoint(road, s, t_at(s), where);  // the reference point must lie on the road too
    return {pose.point, pose.heading + direction};
  }
  const auto pose = reading.roads.roadPoint(road, s, t_at(s), where);
  // A relative <Orientation> counts from the lane's driving direction (as the language's import reads it).
  return ahead({pose.point, orientation->absolute ? orientation->h : pose.heading + direction + orientation->h});
}

/// m/s: the entity's Init speed (an absolute step), 0 without one.
double startSpeed(const NetworkReading& reading, const Entity& entity) {
  const xml::Reader& reader = reading.translation.reader;
  if (entity.gradualSpeed) {
    reader.fail(entity.gradualSpeed,
                "a network scenario starts road users at a speed (a step), not with a change of it");
  }
  if (entity.distanceAction) reader.fail(entity.distanceAction, "a network scenario places road users by positions");
  if (!entity.speedTarget) return 0.0;
  const pugi::xml_node target = reader.choice(entity.speedTarget, {"AbsoluteTargetSpeed"});
  return reader.number(target, "value", NumberRange::atLeast(0.0));
}

/// The road user `entity` is on the network (file frame).
sim::PlacedRoadUser placedRoadUser(const NetworkReading& reading, const Entity& entity) {
  const RoadUserKind& kind = roadUserKind(entity.type);
  if (!kind.drivesInLanes) {
    throw ConfigError(fmt::format("{}: '{}' is a {}: a network scenario places vehicles only", entity.where,
                                  entity.name, kind.name));
  }
  const auto pose = startPose(reading, entity);
  sim::PlacedRoadUser user;
  user.id = entity.name;
  user.heading = pose.heading;
  user.centre = pose.point;
  user.speed = startSpeed(reading, entity);
  user.length = entity.length;
  user.width = entity.width;
  user.vehicleClass = kind.sumoClass;
  user.where = entity.where;
  return user;
}

/// The .sumocfg a controller's <Properties> name in a <File> (esmini's SumoController), if any;
/// its other properties are noted as not used.
std::optional<fs::path> sumoConfiguration(const NetworkReading& reading, const Entity& entity, const fs::path& xosc) {
  const ControllerDefinition& definition = entity.controllerDefinition;
  if (!definition.reader) return std::nullopt;
  const xml::Reader& reader = *definition.reader;
  const pugi::xml_node properties = definition.node.child("Properties");
  if (!properties) return std::nullopt;
  reader.requireSubset(properties, {"Property", "File"});
  std::optional<fs::path> config;
  for (const pugi::xml_node& file : properties.children("File")) {
    // Looked at without reading it: another file is left to the check that every attribute is read.
    const std::string looked_at = resolveValue(file.attribute("filepath").value(), reader.parameters(),
                                               reader.where(file) + ": attribute filepath");
    if (fs::path(looked_at).extension() != ".sumocfg") continue;
    const std::string path = reader.text(file, "filepath");
    config = referencedFile(reading.translation.options, xosc, path, reader.where(file), "filepath");
    if (!fs::is_regular_file(*config)) reader.fail(file, fmt::format("{} does not exist", config->string()));
  }
  if (!config) return std::nullopt;
  for (const pugi::xml_node& property : properties.children("Property")) {
    const std::string name = reader.text(property, "name");
    reading.translation.findings.note(reader.where(property),
                                      fmt::format("property '{}' of the SUMO controller: not used", name));
    reader.leave(property, {"value"});
  }
  return config;
}

/// Takes the entities that a SUMO configuration controls out of the road users: their traffic
/// comes from its route files. At most one configuration.
void readSumoControllers(NetworkReading& reading, const fs::path& xosc) {
  auto& entities = reading.translation.entities;
  for (auto it = entities.begin(); it != entities.end();) {
    const auto config = sumoConfiguration(reading, *it, xosc);
    if (!config) {
      ++it;
      continue;
    }
    if (!reading.scenario.sumoConfig.empty() && reading.scenario.sumoConfig != *config) {
      throw ConfigError(fmt::format("{}: a second SUMO configuration ({}; the first: {}): a network scenario runs one",
                                    it->controllerWhere, config->string(), reading.scenario.sumoConfig.string()));
    }
    reading.scenario.sumoConfig = *config;
    reading.translation.findings.mapped(
        it->controllerWhere, fmt::format("'{}' is SUMO's traffic of {} (its network and route files; its vehicles "
                                         "look like '{}' in the file only)",
                                         it->name, config->filename().string(), it->name));
    // SUMO's traffic starts where its route files say: an Init for the entity is not followed.
    for (const pugi::xml_node& init : {it->position, it->speedTarget, it->gradualSpeed, it->distanceAction}) {
      if (!init) continue;
      reading.translation.findings.note(reading.translation.reader.where(init),
                                        fmt::format("'{}' is SUMO's traffic: its Init is not simulated", it->name));
      reading.translation.reader.leaveAll(init);
    }
    it = entities.erase(it);
  }
}

/// The Ego's controller as the export's closed loop takes it.
void readController(NetworkReading& reading, const ControllerChoice& choice) {
  NetworkScenario& scenario = reading.scenario;
  scenario.controller = choice.name;
  scenario.controllerLibrary = choice.library;
  if (!choice.params.IsMap()) return;
  // The map file gave them (the defaults give none).
  const std::string where = reading.translation.options.controllerMap.string();
  for (const auto& param : choice.params) {
    const std::string name = param.first.as<std::string>();
    const std::string field = fmt::format("controller '{}' parameter '{}'", choice.name, name);
    if (!param.second.IsScalar()) throw ConfigError::field(where, field, "a list or map", "a number");
    const double value = parseReal(param.second.as<std::string>(), NumberRange::any(), where, field);
    scenario.controllerParams.emplace_back(name, value);
  }
}

void refuseStories(const Translation& translation, const pugi::xml_node& storyboard) {
  for (const pugi::xml_node& story : storyboard.children("Story")) {
    translation.findings.refuse(fmt::format(
        "{}: a network scenario (--network) simulates the Init only: its road users keep their lane and "
        "speed, the Ego is driven by its controller",
        translation.reader.where(story)));
  }
}

}  // namespace

std::optional<NetworkScenario> translateNetwork(const fs::path& xosc, const OscImportOptions& options,
                                                Findings& findings) {
  checkCommandLine(options);
  xml::Reader reader(xosc, read_limits::kScenario);
  const pugi::xml_node root = reader.root();
  const Parameters parameters = readScenarioHead(reader, {}, "", findings);
  if (const auto violated = violatedConstraint(reader, root, parameters.values)) {
    reader.fail(root, fmt::format("OpenSCENARIO: not executed: {}", *violated));
  }
  Translation translation{reader, findings, options};
  Catalogs catalogs(reader, root, options, findings);
  translation.catalogs = &catalogs;
  NetworkScenario scenario;
  scenario.name = xosc.stem().string();
  scenario.openDrive = roadNetworkFile(translation, root, xosc);
  const OpenDriveRoads roads(scenario.openDrive);
  roads.noteElevations(findings);
  NetworkReading reading{translation, roads, scenario};
  readEntities(translation, root, catalogs);
  const pugi::xml_node storyboard = reader.only(root, "Storyboard");
  reader.requireSubset(storyboard, {"Init", "Story", "StopTrigger"});
  readInit(translation, storyboard);
  findings.attempt([&] { readSumoControllers(reading, xosc); });
  findings.attempt([&] {
    ControllerChoice choice;
    const Entity& ego = findEgo(translation, choice);
    // The export chooses its Ego by this name: one that reads as another selection is refused (in check too).
    const auto selection = pipeline::EgoSelection::parse(ego.name);
    if (selection.kind != pipeline::EgoSelection::Kind::Ids || selection.ids != std::vector<std::string>{ego.name}) {
      throw ConfigError(fmt::format("{}: the Ego's name '{}' reads as an Ego selection of `export` (all, random:K, "
                                    "vtype:NAME or a list): rename the entity",
                                    ego.where, ego.name));
    }
    scenario.ego = ego.name;
    readController(reading, choice);
  });
  for (const Entity& entity : translation.entities) {
    if (translation.refusedEntities.count(entity.name)) continue;
    findings.attempt([&] {
      sim::PlacedRoadUser user = placedRoadUser(reading, entity);
      user.holdsSpeed = entity.name != scenario.ego;
      findings.mapped(entity.where, fmt::format("'{}' starts at ({:.2f}, {:.2f}) m heading {:.1f} deg at {} m/s{}",
                                                entity.name, user.centre.x(), user.centre.y(),
                                                user.heading * 180.0 / kPi, xml::number(user.speed),
                                                user.holdsSpeed ? ", keeping its lane and speed" : ""));
      scenario.roadUsers.push_back(std::move(user));
    });
  }
  refuseStories(translation, storyboard);
  findings.attempt([&] {
    readStopTrigger(translation, storyboard, /*window_bound=*/false);
    if (!(translation.duration > 0.0)) {
      throw ConfigError(fmt::format("{}: the scenario ends at t = 0: nothing to simulate (pass --duration)",
                                    reader.where(storyboard.child("StopTrigger"))));
    }
  });
  scenario.duration = translation.duration;
  if (!findings.anyRefused()) {
    for (const std::string& unread : reader.unreadAttributes()) findings.refuse(unread);
    for (const std::string& unread : catalogs.unreadAttributes()) findings.refuse(unread);
  }
  if (findings.anyRefused()) return std::nullopt;
  return scenario;
}

namespace {

/// m: the net's <location netOffset>: what netconvert added to the OpenDRIVE file's coordinates.
Vec2 netOffsetOf(const fs::path& net) {
  pugi::xml_document document;
  if (!document.load_file(net.c_str())) throw ConfigError(fmt::format("{}: not a readable SUMO network", net.string()));
  const std::string offset = document.child("net").child("location").attribute("netOffset").as_string("0,0");
  const auto comma = offset.find(',');
  const std::string where = net.string() + ": <location>";
  return {parseReal(offset.substr(0, comma), NumberRange::any(), where, "netOffset"),
          parseReal(comma == std::string::npos ? "" : offset.substr(comma + 1), NumberRange::any(), where,
                    "netOffset")};
}

/// The network file a SUMO configuration names (<input><net-file value>), relative to it.
fs::path configuredNet(const fs::path& config) {
  pugi::xml_document document;
  if (!document.load_file(config.c_str())) {
    throw ConfigError(fmt::format("{}: not a readable SUMO configuration", config.string()));
  }
  const std::string net = document.document_element().child("input").child("net-file").attribute("value").as_string();
  if (net.empty()) {
    throw ConfigError(fmt::format("{}: <input><net-file>: expected the network's file", config.string()));
  }
  return config.parent_path() / net;
}

}  // namespace

PreparedNetwork prepareNetwork(const NetworkScenario& scenario, const fs::path& work) {
  PreparedNetwork prepared;
  fs::path net;
  if (!scenario.sumoConfig.empty()) {
    prepared.source.config = scenario.sumoConfig;
    net = configuredNet(scenario.sumoConfig);
  } else {
    net = work / "network.net.xml";
    // Planar, as vsd-sumo is: with elevation SUMO measures lanes in 3D but places points on them in 2D.
    road::convertOpenDrive(scenario.openDrive, net, road::OpenDriveOrigin::AsWritten, {"--flatten", "true"});
    prepared.source.net = net;
  }
  const Vec2 offset = netOffsetOf(net);
  prepared.placed = scenario.roadUsers;
  for (auto& user : prepared.placed) user.centre += offset;
  return prepared;
}

void checkNetworkStart(const NetworkScenario& scenario, double step, Findings& findings) {
  TemporaryDirectory work("vsd-network-check");
  const PreparedNetwork prepared = prepareNetwork(scenario, work.path());
  sim::MapSimulationOptions options;
  options.source = prepared.source;
  options.step = step;
  options.begin = 0.0;
  options.end = 2.0 * step;
  options.placed = prepared.placed;
  sim::MapSimulation simulation(options);
  simulation.step();
  findings.mapped(scenario.openDrive.string(),
                  fmt::format("every road user starts on {} ({} road users)",
                              scenario.sumoConfig.empty() ? "netconvert's network of it" : scenario.sumoConfig.string(),
                              prepared.placed.size()));
}

std::string runNetworkScenario(const pipeline::RunOptions& run, const OscImportOptions& import) {
  Findings findings(/*collect=*/false);
  const NetworkScenario scenario = *translateNetwork(run.scenarioFile, import, findings);
  for (const auto& line : findings.lines()) {
    if (line.warn) spdlog::warn("{}", line.text);
    else if (line.kind == Findings::Kind::Note) spdlog::debug("{}", line.text);
  }
  pipeline::ExportOptions options;
  options.output = run.outputDir.empty() ? fs::path("out") / (scenario.name + ".h5") : run.outputDir;
  options.label = scenario.name;
  options.sourceFile = run.scenarioFile;
  checkOutput({options.output, &output_kinds::datasetFile(), options.label, run.force, "--out", "--force",
               {{"scenario", run.scenarioFile},
                {"road network", scenario.openDrive},
                {"SUMO configuration", scenario.sumoConfig}}});
  TemporaryDirectory work("vsd-network");
  PreparedNetwork prepared = prepareNetwork(scenario, work.path());
  options.source = prepared.source;
  options.placed = std::move(prepared.placed);
  options.egos = scenario.ego;  // a name that is no other selection (translateNetwork)
  options.closedLoop = true;
  options.controller = scenario.controller;
  options.controllerLibrary = scenario.controllerLibrary;
  options.controllerParams = scenario.controllerParams;
  options.step = import.step.value_or(kDefaultStep);
  options.begin = 0.0;
  options.end = scenario.duration;
  options.seed = run.seed;
  options.watchdog = run.watchdog;
  options.compression = run.compression;
  options.validate();
  return pipeline::exportMap(options).report();
}

}  // namespace vsd::interop::osc
