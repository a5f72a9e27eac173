// An OpenSCENARIO scenario file translated into the scenario language (YAML text),
// loaded by the language's reader; `scenario check` and `run TEMPLATE.xosc`.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include <cctype>
#include <cmath>
#include <numeric>

#include "osc_template.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/yaml_reader.hpp"
#include "vsd/sim/controller.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

const std::map<std::string, std::string>& defaultControllerMap() {
  // Controller names of published files (ASAM's ALKS set, esmini's examples).
  static const std::map<std::string, std::string> kDefaults = {
      {"ALKSController", "alks"},
      {"ALKS_R157SM_Controller", "r157_reference_driver"},
      {"ECE_ALKS_RefDriverController", "r157_reference_driver"},
      {"ACCController", "paper_ego"},
  };
  return kDefaults;
}

namespace osc {

namespace {

std::string num(double value) { return xml::number(value); }

/// Region of the language's road (m along its centre line): the whole OpenDRIVE road
/// where the language allows it; beyond, the road goes on straight (said in a note).
constexpr double kMaxRegion = 1000.0;
constexpr double kMaxExtension = 10'000.0;

}  // namespace

YAML::Node ControllerChoice::languageNode() const {
  YAML::Node node;
  node["name"] = name;
  if (params && params.IsMap()) node["params"] = params;
  if (!library.empty()) node["library"] = library.string();
  return node;
}

namespace {

/// A map file's entry: a controller name, or {controller: NAME, params: {...}, library: PATH}
/// (PATH relative to the map file); throws ConfigError naming the file and the entry otherwise.
ControllerChoice mapEntry(const YAML::Node& entry, const fs::path& file, const std::string& name) {
  const std::string expected = fmt::format("{}: {}: expected a controller name or {{controller: NAME, params: {{...}}, "
                                           "library: PLUGIN.so}}", file.string(), name);
  if (entry.IsScalar()) return {entry.as<std::string>(), {}, {}};
  if (!entry.IsMap()) throw ConfigError(expected);
  for (const auto& key_value : entry) {
    const std::string key = key_value.first.as<std::string>();
    if (key != "controller" && key != "params" && key != "library") throw ConfigError(expected);
  }
  const YAML::Node params = entry["params"];
  const YAML::Node library = entry["library"];
  if (!entry["controller"] || !entry["controller"].IsScalar() || (params && !params.IsMap()) ||
      (library && !library.IsScalar())) {
    throw ConfigError(expected);
  }
  ControllerChoice choice{entry["controller"].as<std::string>(), params ? params : YAML::Node(), {}};
  if (!library) return choice;
  choice.library = fs::absolute(file.parent_path() / library.as<std::string>()).lexically_normal();
  if (!fs::is_regular_file(choice.library)) {
    throw ConfigError(fmt::format("{}: {}: library: got '{}', expected a controller plugin's shared library (relative "
                                  "to the map file): {} does not exist",
                                  file.string(), name, library.as<std::string>(), choice.library.string()));
  }
  return choice;
}

/// A choice without a library names a built-in controller (or `script`, where `script_allowed`);
/// a plugin is loaded by `run`. Throws ConfigError starting with `where`.
void requireKnownController(const ControllerChoice& choice, const std::string& where, bool script_allowed) {
  const auto builtins = sim::ControllerRegistry::withBuiltins();
  if (!choice.library.empty() || (script_allowed && choice.name == kFollowsItsScript) ||
      builtins.contains(choice.name)) {
    return;
  }
  std::vector<std::string> known;
  for (const auto& [known_name, description] : builtins.available()) known.push_back(known_name);
  throw ConfigError(fmt::format("{}: controller '{}' is not built in (built-in: {}{}){}", where, choice.name,
                                fmt::join(known, ", "),
                                script_allowed ? fmt::format("; or {} to leave the entity scripted", kFollowsItsScript)
                                               : "",
                                script_allowed ? "; a plugin needs library: PLUGIN.so" : ""));
}

}  // namespace

ControllerChoice ControllerMap::choice(const std::string& name, const std::string& where) const {
  if (given()) {
    const std::string file = file_.string();
    if (!map_) map_ = scenario::loadYaml(readTextFile(file_, read_limits::kSpec), file);
    const YAML::Node& map = *map_;
    if (!map.IsMap()) throw ConfigError(fmt::format("{}: expected a map from controller names to vsd-sumo controllers", file));
    if (const YAML::Node entry = map[name]) {
      ControllerChoice choice = mapEntry(entry, file_, name);
      requireKnownController(choice, fmt::format("{}: {}", file, name), /*script_allowed=*/true);
      return choice;
    }
  }
  const auto& defaults = defaultControllerMap();
  const auto found = defaults.find(name);
  if (found == defaults.end()) {
    throw ConfigError(fmt::format("{}: controller '{}' maps onto no vsd-sumo controller: name it in a --controller-map "
                                  "file (defaults: ALKSController, ALKS_R157SM_Controller, "
                                  "ECE_ALKS_RefDriverController, ACCController)",
                                  where, name));
  }
  return {found->second, {}, {}};
}

namespace {

/// Whether an entity's controller is mapped onto its script (noted): it is no Ego candidate.
bool followsItsScript(Translation& translation, const Entity& entity) {
  if (translation.controllerMap.given() &&
      translation.controllerMap.choice(*entity.controller, entity.controllerWhere).name == kFollowsItsScript) {
    translation.findings.note(entity.controllerWhere,
                              fmt::format("'{}' follows its script: its controller '{}' is mapped to '{}' (the "
                                          "controller's own behaviour is not simulated)",
                                          entity.name, *entity.controller, kFollowsItsScript));
    return true;
  }
  return false;
}

}  // namespace

Entity& findEgo(Translation& translation, ControllerChoice& controller) {
  Entity* ego = nullptr;
  for (auto& entity : translation.entities) {
    if (!entity.controller || followsItsScript(translation, entity)) continue;
    if (ego) {
      throw ConfigError(fmt::format("{}: '{}' and '{}' both have a controller: the language has one controller-driven "
                                    "road user (the Ego)", entity.controllerWhere, ego->name, entity.name));
    }
    ego = &entity;
  }
  if (ego) {
    // The file says who the Ego is and how it is driven: a flag that would say otherwise is not ignored.
    for (const auto& [flag, value] : {std::pair{"--ego", translation.options.ego},
                                      std::pair{"--controller", translation.options.controller}}) {
      if (value) {
        throw ConfigError::field("command line", flag, *value,
                                 fmt::format("none for {}: it assigns '{}' the controller '{}' ({}), which makes it "
                                             "the Ego, driven by what --controller-map maps that name onto",
                                             translation.reader.file().string(), ego->name, *ego->controller,
                                             ego->controllerWhere));
      }
    }
    controller = translation.controllerMap.choice(*ego->controller, ego->controllerWhere);
    translation.findings.mapped(ego->controllerWhere, fmt::format("the Ego '{}' is driven by vsd-sumo's '{}' (the file's "
                                                                  "controller '{}'; its properties are not passed on)",
                                                                  ego->name, controller.name, *ego->controller));
    return *ego;
  }
  const std::string ego_name = translation.options.ego.value_or(kDefaultEgo);
  for (auto& entity : translation.entities) {
    if (entity.name == ego_name) ego = &entity;
  }
  if (!ego && !translation.refusedEntities.empty()) {
    // The Ego may be among them (its controller unread): which one it is stays open.
    throw FollowsARefusal(fmt::format("{}: no Ego among the entities read", translation.reader.file().string()));
  }
  if (!ego) {
    throw ConfigError(fmt::format("{}: no entity has a controller and none is named '{}' (--ego NAME: which is the Ego?)",
                                  translation.reader.file().string(), ego_name));
  }
  controller = {translation.options.controller.value_or(kDefaultEgoController), {}, {}};
  translation.findings.note(ego->where, fmt::format("no controller in the file: '{}' is the Ego, driven by '{}' "
                                                    "(--ego, --controller)", ego->name, controller.name));
  return *ego;
}

LanguagePlace languagePlace(const CarriagewayRoad& road, const Placement& p, double centre_ahead, bool keep_lane) {
  const double stretch = 1.0 - road.curvatureAt(p.s) * p.t;  // reference-line s per m along the entity's line
  const double s = p.s + centre_ahead * std::cos(p.heading) / stretch;
  const double t = p.t + centre_ahead * std::sin(p.heading);
  const int lane = keep_lane ? p.lane : road.nearestLane(t);
  return {road.languageS(s), lane, t - road.laneCentreT(lane)};
}

namespace {

/// rad: the largest angle between the language's +x and a polyline road's segment, less 0.1 mrad
/// of margin that keeps the chords inside.
constexpr double kMaxSegmentTurn = scenario::kMaxArcTurn - 1e-4;

/// Whether the language gets the road as its arc road: lines, or arcs of one curvature, that
/// end (or reach kMaxRegion) before they turn kMaxArcTurn. An arc that turns further becomes a
/// polyline road, whose headings may span twice that (frameTurn).
bool asArc(const CarriagewayRoad& road) {
  if (!road.oneCurvature) return false;
  const double curvature = std::abs(road.languageCurvature());
  return curvature == 0.0 || scenario::kMaxArcTurn / curvature >= std::min(road.languageS(road.length), kMaxRegion);
}

/// The language's region of a polyline road: the reference-line s where it ends, and the
/// smallest and largest turn (rad) from the road's start heading over it.
struct RegionWindow {
  double end = 0.0;
  double low = 0.0;
  double high = 0.0;
};

/// The region of a polyline road: up to kMaxRegion along the driving lanes' centre, the road's
/// end, or where its headings stop fitting in a window of twice kMaxSegmentTurn (the language's
/// frame turned into the window puts every segment within kMaxSegmentTurn of +x: frameTurn).
/// One pass over the road's samples, as far as the region goes.
RegionWindow regionWindow(const CarriagewayRoad& road) {
  // Bisects [lo, hi] for the last s where `beyond` is false (beyond(lo) false, beyond(hi) true).
  const auto bisect = [](double lo, double hi, const auto& beyond) {
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (beyond(mid) ? hi : lo) = mid;
    }
    return lo;
  };
  // An arc turns in proportion to s; any other road is followed through its samples.
  const bool arc = road.oneCurvature && road.curvature != 0.0;
  RegionWindow window{arc ? std::min(road.length, 2.0 * kMaxSegmentTurn / std::abs(road.curvature)) : road.length};
  // languageS grows with s wherever 1 - k t > 0, which a road whose lanes do not fold ensures.
  const auto beyond = [&](double at) {
    const double turn = road.turnAt(at);
    return std::max(window.high, turn) - std::min(window.low, turn) > 2.0 * kMaxSegmentTurn ||
           road.languageS(at) > kMaxRegion;
  };
  double before = 0.0;
  for (const double s : road.sampleS) {
    if (beyond(s)) {
      window.end = bisect(before, s, beyond);
      break;
    }
    window.low = std::min(window.low, road.turnAt(s));
    window.high = std::max(window.high, road.turnAt(s));
    before = s;
  }
  if (road.languageS(window.end) > kMaxRegion) {
    window.end = bisect(0.0, window.end, [&](double at) { return road.languageS(at) > kMaxRegion; });
  }
  window.low = std::min(window.low, road.turnAt(window.end));
  window.high = std::max(window.high, road.turnAt(window.end));
  return window;
}

/// rad: how far the language's +x is turned from the road's start heading: 0 where the
/// region's headings all lie within kMaxSegmentTurn of it (an arc road, or a road that turns
/// less), else the least turn that puts them there — a road that turns further starts heading
/// away from +x, so that x still advances along all of its region.
double frameTurn(const CarriagewayRoad& road, const RegionWindow& window) {
  if (asArc(road)) return 0.0;
  return std::min(std::max(0.0, window.high - kMaxSegmentTurn), window.low + kMaxSegmentTurn);
}

}  // namespace

double frameHeading(const CarriagewayRoad& road) { return road.heading + frameTurn(road, regionWindow(road)); }

double regionLength(const CarriagewayRoad& road) {
  if (!asArc(road)) return road.languageS(regionWindow(road).end);
  const double curvature = road.languageCurvature();
  double region = std::min(road.languageS(road.length), kMaxRegion);
  if (curvature != 0.0) region = std::min(region, scenario::kMaxArcTurn / std::abs(curvature));
  return region;
}

namespace {

/// The driving lanes' centre line over the region, within 1 cm (as the language samples its
/// arcs), in the language's frame: starting at the origin, its +x along frameHeading.
YAML::Node centreLineNode(const CarriagewayRoad& road) {
  const RegionWindow window = regionWindow(road);
  const double end = window.end;
  const double t = road.centreT();
  const Vec2 origin = road.point(0.0, t);
  const double heading = road.heading + frameTurn(road, window);
  const double cos_h = std::cos(heading);
  const double sin_h = std::sin(heading);
  YAML::Node points;
  auto add = [&](double s) {
    const Vec2 d = road.point(s, t) - origin;
    YAML::Node point;
    point.push_back(num(cos_h * d.x() + sin_h * d.y()));
    point.push_back(num(-sin_h * d.x() + cos_h * d.y()));
    point.SetStyle(YAML::EmitterStyle::Flow);
    points.push_back(point);
  };
  // Reference-line s of the points: each geometry sampled within 1 cm of its curve, points
  // closer than 1 cm dropped (a geometry of a millimetre is no segment), the region's end kept.
  constexpr double kMinStep = 0.01;  // m of reference line
  std::vector<double> along = {0.0};
  for (const PlanGeometry& geometry : road.geometries) {
    if (geometry.s() >= end) break;
    const double k = geometry.largestCurvature();
    const double k_centre = k / std::max(1.0 - k * std::abs(t), 0.1);
    const double spacing = vsd::road::chordSpacing(k_centre);
    const double until = std::min(end, geometry.s() + geometry.length());
    const auto steps = static_cast<int>(std::ceil((until - geometry.s()) / spacing));
    for (int i = 1; i <= steps; ++i) {
      const double s_i = geometry.s() + (until - geometry.s()) * i / steps;
      if (s_i - along.back() >= kMinStep) along.push_back(s_i);
    }
  }
  if (along.back() < end) {
    if (along.size() > 1 && end - along.back() < kMinStep) along.back() = end;
    else along.push_back(end);
  }
  for (const double s : along) add(s);
  return points;
}

/// m of straight road before the region: where vehicles drive against the road, they leave the
/// file's road at its start; vsd-sumo's goes on straight there for as far as each of them
/// drives over the simulated duration at its initial speed, plus 10 % (at least 150 m, as
/// after the road's end). 0 where none does.
double extensionBefore(Translation& translation, double duration) {
  std::optional<double> needed;
  for (const Entity& entity : translation.entities) {
    if (&entity == translation.ego || !entity.drivesAgainstRoad()) continue;
    const double s = languagePlace(translation.road, *entity.placement, entity.centreAhead, true).s;
    const double reach = 1.1 * entity.speed.value_or(0.0) * duration + 0.5 * entity.length - s;
    needed = std::max(needed.value_or(reach), reach);
  }
  if (!needed) return 0.0;
  const double before = std::clamp(std::ceil(*needed), 150.0, kMaxExtension);
  translation.findings.note(translation.road.file.string(),
                            fmt::format("vehicles drive against the road: vsd-sumo's road starts {} m before the "
                                        "file's, straight, where they leave it",
                                        num(before)));
  return before;
}

YAML::Node roadNode(Translation& translation, double duration) {
  const CarriagewayRoad& road = translation.road;
  const double length = road.languageS(road.length);
  const double region = regionLength(road);
  YAML::Node node;
  if (asArc(road)) {
    node["shape"] = "arc";
    node["curvature"] = num(road.languageCurvature());
    node["length"] = num(region);
  } else {
    node["shape"] = "polyline";
    node["centre_line"] = centreLineNode(road);
  }
  node["lanes"] = std::to_string(road.lanes);
  if (road.oneLaneWidth()) {
    node["lane_width"] = num(road.laneWidths.front());
  } else {
    for (const double width : road.laneWidths) node["lane_widths"].push_back(num(width));
  }
  node["shoulders"]["left"] = num(road.shoulderLeft);
  node["shoulders"]["right"] = num(road.shoulderRight);
  node["extension"]["before"] = num(extensionBefore(translation, duration));
  node["extension"]["after"] = num(std::clamp(length - region, 150.0, kMaxExtension));
  if ((!road.oneCurvature || road.curvature != 0.0) && length > region + 1e-6) {
    const std::string turn = asArc(road)
                                 ? fmt::format("{} rad of turn", scenario::kMaxArcTurn)
                                 : fmt::format("headings within {} rad of each other", 2.0 * scenario::kMaxArcTurn);
    translation.findings.note(fmt::format("{}", road.file.string()),
                              fmt::format("the road curves for {} m; vsd-sumo's road has its first {} m (at most {} m "
                                          "and {}) and goes on straight",
                                          num(length), num(region), kMaxRegion, turn));
  }
  return node;
}

YAML::Node roadUserNode(Translation& translation, const Entity& entity, bool ego) {
  const CarriagewayRoad& road = translation.road;
  const LanguagePlace place = languagePlace(road, *entity.placement, entity.centreAhead, true);
  YAML::Node node;
  if (!ego) node["id"] = entity.id;
  node["type"] = roadUserKind(entity.type).name;
  node["length"] = num(entity.length);
  node["width"] = num(entity.width);
  if (translation.measuresReferencePoints && entity.centreAhead != 0.0) {
    node["reference_point"] = num(-entity.centreAhead);
  }
  node["s"] = num(place.s);
  node["lane"] = std::to_string(place.lane);
  // OpenSCENARIO sets no rule against bodies that overlap (esmini places them as written): ASAM's
  // 4.2.4 and 4.5.2 put their second blocking target 15 m beyond the first, which may be an 18.75 m truck.
  if (!ego) node["may_start_overlapping"] = "true";
  const double heading_deg = entity.placement->heading * 180.0 / kPi;
  if (!ego && entity.drivesAgainstRoad()) {
    node["direction"] = "against";
    translation.findings.mapped(entity.where, fmt::format("'{}' faces back along the road ({} deg): it drives against "
                                                          "it, as oncoming traffic (direction: against)",
                                                          entity.name, num(std::abs(heading_deg))));
  } else if (ego || entity.isVehicle()) {
    if (std::abs(heading_deg) > 0.01) {
      throw ConfigError(fmt::format("{}: '{}' starts {} deg off the road's direction: the language's {} along it{}",
                                    entity.where, entity.name, num(heading_deg),
                                    ego ? "Ego drives" : "vehicles drive", ego ? "" : " or against it (180 deg)"));
    }
  } else if (heading_deg != 0.0) {
    node["heading_deg"] = num(heading_deg);
  }
  if (ego && std::abs(place.offset) > 0.01) {
    throw ConfigError(fmt::format("{}: the Ego '{}' starts {} m off its lane's centre: the language's Ego starts on it",
                                  entity.where, entity.name, num(place.offset)));
  }
  if (!ego && place.offset != 0.0) node["offset"] = num(place.offset);
  const double speed = entity.speed.value_or(0.0);
  if (entity.type == RoadUserType::StationaryObject && speed != 0.0) {
    // A MiscObject given a speed in the Init: the language's objects stand (refused, not dropped).
    const std::string where = entity.speedTarget ? translation.reader.where(entity.speedTarget) : entity.where;
    throw ConfigError(fmt::format("{}: '{}' is a stationary object (a MiscObject) given a speed of {} m/s: stationary "
                                  "objects never move (the language's rule)",
                                  where, entity.name, num(speed)));
  }
  if (!ego && !entity.isVehicle() && std::abs(std::remainder(heading_deg, 360.0)) > 1e-6 && speed != 0.0) {
    // The language moves road users along the road: one facing off it stands until it crosses.
    const std::string where = entity.speedTarget ? translation.reader.where(entity.speedTarget) : entity.where;
    throw ConfigError(fmt::format("{}: '{}' faces {} deg off the road and is given a speed of {} m/s: the language's "
                                  "road users move along the road, so one facing off it stands (a crossing: a "
                                  "FollowTrajectoryAction)",
                                  where, entity.name, num(heading_deg), num(speed)));
  }
  if (entity.type != RoadUserType::StationaryObject && (ego || entity.isVehicle() || speed != 0.0)) {
    node["speed"] = num(speed);
  }
  if (entity.actions.size() > 0) node["actions"] = entity.actions;  // the Ego's: set_speed only
  return node;
}

std::string scenarioName(const fs::path& file) {
  std::set<std::string> used;
  return identifier(file.stem().string(), used);
}

/// The language YAML of the translation (after every element was read).
std::string languageYaml(Translation& translation, const Parameters& parameters, const StringCodes& codes) {
  const Entity& ego = *translation.ego;
  const ControllerChoice& controller = translation.controller;
  YAML::Node root;
  root["schema"] = "vsd-scenario/1";
  root["name"] = scenarioName(translation.reader.file());
  root["description"] = "imported from " + translation.reader.file().filename().string();
  const double step = translation.options.step.value_or(scenario::LogicalScenario{}.step);
  root["time"]["step"] = num(step);
  const double duration = std::ceil(translation.duration / step - 1e-9) * step;  // s, whole steps
  root["time"]["duration"] = num(duration);
  YAML::Node inputs(YAML::NodeType::Sequence);
  std::set<std::string> input_names;
  for (const auto& [name, value] : parameters.numeric) {
    YAML::Node input;
    input["name"] = identifier(name, input_names);
    input["value"] = num(value);
    inputs.push_back(input);
  }
  for (const auto& [name, value] : parameters.strings) {
    // A string parameter a sweep varies: its value's position in the sweep's list (concrete.csv is numeric).
    const auto coded = codes.find(name);
    if (coded == codes.end()) continue;
    const auto at = std::find(coded->second.begin(), coded->second.end(), value);
    YAML::Node input;
    input["name"] = identifier(name, input_names);
    input["value"] = std::to_string(at - coded->second.begin());
    input["description"] = fmt::format("code of the value in {}", fmt::join(coded->second, ", "));
    inputs.push_back(input);
  }
  if (inputs.size() > 0) root["inputs"] = inputs;
  root["road"] = roadNode(translation, duration);
  root["vehicles"]["ego"] = roadUserNode(translation, ego, true);
  root["vehicles"]["ego"]["controller"] = controller.languageNode();
  if (translation.egoActiveFrom && *translation.egoActiveFrom > 0.0) {
    root["vehicles"]["ego"]["controller"]["active_from"] = num(*translation.egoActiveFrom);
  }
  YAML::Node others(YAML::NodeType::Sequence);
  for (const auto& entity : translation.entities) {
    if (&entity != &ego) others.push_back(roadUserNode(translation, entity, false));
  }
  if (others.size() > 0) root["vehicles"]["others"] = others;
  root["sumo"]["collision_action"] = "warn";
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace

std::string identifier(const std::string& name, std::set<std::string>& used) {
  std::string id;
  for (const char c : name) id += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  if (id.empty() || !std::isalpha(static_cast<unsigned char>(id[0]))) id = "n" + id;
  if (id == "x") id = "x_";
  std::string unique = id;
  for (int k = 2; used.count(unique) > 0; ++k) unique = fmt::format("{}_{}", id, k);
  used.insert(unique);
  return unique;
}

namespace {

/// Whether the file drives road users on the road's left side: a LanePosition or an
/// AbsoluteTargetLane naming a positive lane id, or (on a road with one driving lane on its
/// right side, where a move left can go nowhere else) a RelativeTargetLane or a
/// RelativeLanePosition moving left. A value that does not resolve counts as not; reading
/// the element later reports it.
bool drivesLeftLanes(const xml::Reader& reader, const pugi::xml_node& root, const CarriagewayRoad& road) {
  const auto any_positive = [&](const char* xpath, const char* attribute) {
    for (const pugi::xpath_node& hit : root.select_nodes(xpath)) {
      try {
        if (reader.integer(hit.node(), attribute, -100, 100) > 0) return true;
      } catch (const ConfigError&) {
      }
    }
    return false;
  };
  if (any_positive(".//LanePosition", "laneId") || any_positive(".//AbsoluteTargetLane", "value")) return true;
  return road.lanes == 1 && (any_positive(".//RelativeTargetLane", "value") ||
                             any_positive(".//RelativeLanePosition", "dLane"));
}

/// Whether the Init places a road user on the road's adjoining left lanes, as a relative
/// position does without naming a lane (esmini's cut-in_simple: `dt` from the Ego): placed
/// on a trial copy, whose findings are dropped (placing for real reports them).
bool placesOnLeftLanes(const Translation& translation) {
  const CarriagewayRoad& road = translation.road;
  Findings dropped(/*collect=*/true);
  Translation trial{translation.reader, dropped, translation.options};
  trial.road = road;
  trial.entities = translation.entities;
  placeEntities(trial);
  const double left_edge =
      road.innerT + std::accumulate(road.adjoiningLeftWidths.begin(), road.adjoiningLeftWidths.end(), 0.0);
  return std::any_of(trial.entities.begin(), trial.entities.end(), [&](const Entity& entity) {
    return entity.placement && entity.placement->t > road.innerT && entity.placement->t < left_edge;
  });
}

/// In right-hand traffic, a file whose Init drives only the left side has the left side's run
/// as its road: along the reference line (esmini's left-hand traffic "by heading"), or against
/// it, the reference line reversed (the other carriageway, as ASAM's 4.2.3 varies the Ego's
/// lane over both). Returns whether it has.
bool takeLeftCarriageway(Translation& translation) {
  CarriagewayRoad& road = translation.road;
  if (road.leftHandTraffic) return false;
  const InitCarriageway side = initCarriageway(translation);
  if (side == InitCarriageway::Right) return false;
  const char* direction = side == InitCarriageway::LeftAlong ? "along" : "against";
  if (!road.leftRun) {
    throw ConfigError(fmt::format("{}: the Init drives the left side {} the reference line, which does not map onto "
                                  "the language's lanes: {}",
                                  road.otherSide, direction, road.leftRunProblem));
  }
  if (side == InitCarriageway::LeftAlong) {
    road.useLeftCarriageway();
  } else {
    road.useReversedLeftCarriageway();
  }
  // Lane 0 is the innermost along the reference line, the outermost against it.
  const long innermost = side == InitCarriageway::LeftAlong ? road.innermostLaneId : -road.innermostLaneId;
  const long outermost = innermost + road.lanes - 1;
  const bool along = side == InitCarriageway::LeftAlong;
  translation.findings.mapped(
      road.otherSide,
      fmt::format("lanes {} .. {} (left of the reference line) are the language's lanes 0 .. {}, driven {} the "
                  "reference line as the Init places road users there; the right side is not part of vsd-sumo's road",
                  along ? innermost : outermost, along ? outermost : innermost, road.lanes - 1, direction));
  return true;
}

/// Which of the road's sides the language's road is. Left-hand traffic: the left side. Right-
/// hand traffic: the left side where the Init drives it alone along the reference line;
/// otherwise the right side, and esmini's two-lane roads (one lane each way, no median) carry
/// cut-ins from the left lane driven along the reference line: where the file places or
/// drives road users there, the adjoining left lanes join the language's road; otherwise the
/// left side stays outside it. After the Init is read (its positions decide), before anything
/// is placed for real.
void chooseCarriageway(Translation& translation, const pugi::xml_node& root) {
  CarriagewayRoad& road = translation.road;
  if (road.otherSide.empty()) return;
  if (road.leftHandTraffic) {
    translation.findings.note(road.otherSide, "the right side (lanes driven against the reference line in left-hand "
                                              "traffic) is not part of vsd-sumo's road");
    return;
  }
  if (takeLeftCarriageway(translation)) return;
  if (road.adjoiningLeftLanes > 0 &&
      (drivesLeftLanes(translation.reader, root, road) || placesOnLeftLanes(translation))) {
    road.joinLeftLanes();
    const std::string which =
        road.adjoiningLeftLanes == 1
            ? fmt::format("lane 1 (left of the reference line, no median) is the language's lane {}", road.rightLanes())
            : fmt::format("lanes 1 .. {} (left of the reference line, no median) are the language's lanes {} .. {}",
                          road.adjoiningLeftLanes, road.rightLanes(), road.lanes - 1);
    translation.findings.mapped(road.otherSide,
                                which + ": the scenario places or moves road users there (each drives as the file "
                                        "heads it: along the reference line, or against it as oncoming traffic)");
    return;
  }
  translation.findings.note(road.otherSide,
                            "the left side (lanes driven against the reference line) is not part of vsd-sumo's road");
}

}  // namespace

void checkCommandLine(const OscImportOptions& options) {
  if (options.controller) {
    requireKnownController({*options.controller, {}, {}}, "command line: --controller", /*script_allowed=*/false);
  }
  if (options.step) checkStep(*options.step, "command line", "--step");
  if (options.duration) {
    checkDurationSteps(*options.duration, options.step.value_or(scenario::LogicalScenario{}.step), "command line",
                       "--duration");
  }
}

fs::path roadNetworkFile(Translation& translation, const pugi::xml_node& root, const fs::path& xosc) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node network = reader.only(root, "RoadNetwork");
  reader.requireSubset(network, {"LogicFile", "SceneGraphFile"});
  if (network.child("SceneGraphFile")) {
    translation.findings.note(reader.where(network.child("SceneGraphFile")), "3D models are not used");
  }
  const pugi::xml_node logic = reader.only(network, "LogicFile");
  // The road network must lie next to the scenario file or below it (or inside --data-root).
  const fs::path xodr =
      referencedFile(translation.options, xosc, reader.text(logic, "filepath"), reader.where(logic), "filepath");
  if (!fs::exists(xodr)) reader.fail(logic, fmt::format("the road network {} does not exist", xodr.string()));
  return xodr;
}

Parameters readScenarioHead(xml::Reader& reader, const ParameterValues& assigned, const std::string& assigned_where,
                            Findings& findings) {
  const pugi::xml_node root = reader.root();
  if (std::string(root.name()) != "OpenSCENARIO") reader.fail(root, "expected the root element <OpenSCENARIO>");
  reader.requireSubset(root, {"FileHeader", "ParameterDeclarations", "CatalogLocations", "RoadNetwork", "Entities",
                              "Storyboard"});
  const pugi::xml_node header = reader.only(root, "FileHeader");
  if (reader.number(header, "revMajor") != 1.0) reader.fail(header, "revMajor: expected OpenSCENARIO 1.x");
  reader.leave(header, {"revMinor", "date", "description", "author"});  // 1.x are read alike
  Parameters parameters = readParameters(reader, root, {}, assigned, assigned_where);
  for (const auto& [where, what] : parameters.notes) findings.note(where, what);
  return parameters;
}

/// Reads the whole file into the language. Refusals go to `findings` (and throw unless it collects).
TranslationResult translate(const fs::path& xosc, const OscImportOptions& options, const ParameterValues& assigned,
                            const std::string& assigned_where, Findings& findings, const StringCodes& codes) {
  checkCommandLine(options);  // before anything counts steps (the longest window a StopTrigger may ask for)
  xml::Reader reader(xosc, read_limits::kScenario);
  const pugi::xml_node root = reader.root();
  const Parameters parameters = readScenarioHead(reader, assigned, assigned_where, findings);
  TranslationResult result;
  result.inputs = parameters.numeric;
  result.violated = violatedConstraint(reader, root, parameters.values);
  // A violated constraint is the caller's to report: a run refuses, a sweep skips and counts.
  if (result.violated) return result;
  Translation translation{reader, findings, options};
  Catalogs catalogs(reader, root, options, findings);
  translation.catalogs = &catalogs;
  const fs::path xodr = roadNetworkFile(translation, root, xosc);
  const pugi::xml_node logic = root.child("RoadNetwork").child("LogicFile");
  // In a network of several roads, the scenario's road is the first one a position names (the
  // Init's first), else the one under its first world position.
  pugi::xml_node named = root.select_node("Storyboard/Init//*[@roadId]").node();
  if (!named) named = root.select_node("//*[@roadId]").node();
  pugi::xml_node world = root.select_node("Storyboard/Init//WorldPosition").node();
  if (!world) world = root.select_node("//WorldPosition").node();
  try {
    if (named) {
      const std::string road_id = reader.text(named, "roadId");
      translation.road = readCarriagewayRoad(xodr, findings, road_id, "the roadId at " + reader.where(named));
    } else if (world) {
      const WorldPlace place{Vec2(reader.number(world, "x"), reader.number(world, "y")),
                             reader.optionalNumber(world, "h")};
      translation.road = readCarriagewayRoad(xodr, findings, "", reader.where(world), place);
    } else {
      translation.road = readCarriagewayRoad(xodr, findings);
    }
  } catch (const ConfigError& error) {
    // The language has one road; SUMO's network of the file has them all.
    throw ConfigError(std::string(error.what()) + kTryTheNetwork);
  }
  readEntities(translation, root, catalogs);
  for (auto& entity : translation.entities) entity.id = identifier(entity.name, translation.usedIds);
  const pugi::xml_node storyboard = reader.only(root, "Storyboard");
  reader.requireSubset(storyboard, {"Init", "Story", "StopTrigger"});
  readInit(translation, storyboard);
  chooseCarriageway(translation, root);
  const CarriagewayRoad& road = translation.road;
  std::vector<std::string> widths;
  for (const double width : road.laneWidths) widths.push_back(num(width));
  const std::string lanes =
      road.oneLaneWidth() ? fmt::format("{} driving lanes of {} m", road.lanes, widths.front())
                          : fmt::format("{} driving lanes of {} m (lane 0 first)", road.lanes, fmt::join(widths, ", "));
  const std::string shape = road.oneCurvature
                                ? fmt::format("curvature {} 1/m", num(road.curvature))
                                : fmt::format("{} geometries of varying curvature", road.geometries.size());
  std::string side;
  if (road.leftCarriageway) {
    side = fmt::format(" (laneId {} .. {}, left of the reference line{})", road.innermostLaneId,
                       road.innermostLaneId + road.lanes - 1, road.leftHandTraffic ? ", rule LHT" : "");
  } else if (road.reversed) {
    side = fmt::format(" (laneId {} .. {}, left of the reference line, driven against it: vsd-sumo's road starts at "
                       "the file's s = {} m)",
                       -road.innermostLaneId, -road.innermostLaneId + road.lanes - 1, num(road.length));
  }
  findings.mapped(reader.where(logic), fmt::format("{}: {}{}, {}", road.name(), lanes, side, shape));
  placeEntities(translation);
  findings.attempt([&] {
    translation.ego = &findEgo(translation, translation.controller);
    translation.ego->id = "ego";
  });
  if (!translation.ego) return result;
  addInitialSpeedActions(translation);
  readStories(translation, storyboard);
  findings.attempt([&] { readStopTrigger(translation, storyboard); });
  // Checked once the rest is: an element a refusal cut short has attributes nothing read yet.
  if (!findings.anyRefused()) {
    for (const std::string& unread : reader.unreadAttributes()) findings.refuse(unread);
    for (const std::string& unread : catalogs.unreadAttributes()) findings.refuse(unread);
  }
  if (findings.anyRefused()) return result;
  result.yaml = languageYaml(translation, parameters, codes);
  return result;
}

std::shared_ptr<const scenario::LogicalScenario> loadLanguage(const fs::path& file, const std::string& yaml) {
  // Messages about the translation name it ("F.xosc as the scenario language:LINE: field"; `scenario
  // check --yaml` shows those lines); the run records the file itself.
  const auto parsed = scenario::parseLogicalScenario(yaml, file.string() + " as the scenario language");
  auto logical = std::make_shared<scenario::LogicalScenario>(*parsed);
  logical->sourceFile = file;
  return logical;
}

}  // namespace osc

}  // namespace vsd::interop
