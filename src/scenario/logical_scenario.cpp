#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/scenario/yaml_reader.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <regex>
#include <set>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/tool_options.hpp"
#include "vsd/core/trace.hpp"

namespace vsd::scenario {

int LogicalScenario::steps() const { return static_cast<int>(std::lround(duration / step)); }

std::vector<std::string> LogicalScenario::inputNames() const {
  std::vector<std::string> names;
  names.reserve(inputs.size());
  for (const auto& input : inputs) names.push_back(input.name);
  return names;
}

std::optional<std::size_t> LogicalScenario::inputIndex(const std::string& input_name) const {
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].name == input_name) return i;
  }
  return std::nullopt;
}

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
/// m: bound of the scenario region and of the road extensions (keeps net coordinates sane).
constexpr double kMaxRoadLength = 10'000.0;

bool isIdentifier(const std::string& name) {
  static const std::regex pattern("[A-Za-z][A-Za-z0-9_]*");
  return std::regex_match(name, pattern);
}

void parseTime(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) return;
  reader.checkKeys(node, "time", {"step", "duration"});
  scenario.step = reader.number(node, "step", "time.step", scenario.step);
  scenario.duration = reader.number(node, "duration", "time.duration", scenario.duration);
  // SUMO counts milliseconds; the step count sizes every trace and dataset array.
  const double milliseconds = scenario.step / kMinStep;
  if (!(scenario.step >= kMinStep && scenario.step <= kMaxStep) ||
      std::abs(milliseconds - std::round(milliseconds)) > 1e-6) {
    throw ConfigError::field(reader.where(node["step"], "time.step"), "time.step", formatValue(scenario.step),
                             fmt::format("a multiple of {0} s in {0} .. {1} s", kMinStep, kMaxStep));
  }
  if (!(scenario.duration > 0.0)) {
    throw ConfigError::field(reader.where(node["duration"], "time.duration"), "time.duration",
                             formatValue(scenario.duration), "a duration > 0 s");
  }
  const double steps = scenario.duration / scenario.step;
  if (std::abs(steps - std::round(steps)) > 1e-6 || steps > kMaxWindowSteps + 0.5) {
    throw ConfigError::field(reader.where(node["duration"], "time.duration"), "time.duration",
                             formatValue(scenario.duration),
                             fmt::format("a whole multiple of time.step, at most {} steps", kMaxWindowSteps));
  }
}

void parseInputs(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) return;
  if (!node.IsSequence()) reader.fail(node, "inputs", "expected a list of inputs");
  std::vector<std::string> earlier;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const auto item = node[i];
    const std::string field = fmt::format("inputs[{}]", i);
    reader.checkKeys(item, field, {"name", "unit", "description", "distribution", "min", "max", "mean", "std", "value",
                                   "choices"});
    if (!item["name"]) reader.fail(item, field, "missing 'name'");
    InputSpec input;
    input.name = reader.scalar(item["name"], field + ".name");
    if (!isIdentifier(input.name) || input.name == "x") {
      throw ConfigError::field(reader.where(item["name"], field + ".name"), field + ".name", input.name,
                               "an identifier (letter first, then letters, digits, _), not 'x'");
    }
    if (std::find(earlier.begin(), earlier.end(), input.name) != earlier.end()) {
      reader.fail(item["name"], field + ".name", fmt::format("input '{}' is defined twice", input.name));
    }
    if (item["unit"]) input.unit = reader.scalar(item["unit"], field + ".unit");
    if (item["description"]) input.description = reader.scalar(item["description"], field + ".description");
    // Bounds may only use inputs defined above: sampling happens in file order.
    input.distribution = reader.distribution(item, field, earlier, {"name", "unit", "description"});
    scenario.inputs.push_back(std::move(input));
    earlier.push_back(scenario.inputs.back().name);
  }
}

void parseRoad(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) reader.fail(YAML::Node(), "road", "missing section 'road'");
  reader.checkKeys(node, "road", {"x_range", "points", "centre", "centre_noise", "lanes", "lane_width",
                                  "lane_width_noise", "speed_limit", "extension"});
  const auto inputs = scenario.inputNames();
  auto with_x = inputs;
  with_x.emplace_back("x");
  RoadSpec& road = scenario.road;
  if (const auto range = node["x_range"]) {
    if (!range.IsSequence() || range.size() != 2) reader.fail(range, "road.x_range", "expected [x_min, x_max] in m");
    road.xMin = reader.number(range[0], "road.x_range[0]");
    road.xMax = reader.number(range[1], "road.x_range[1]");
    if (!(road.xMin < road.xMax)) {
      reader.fail(range, "road.x_range", fmt::format("x_min {} >= x_max {} (expected x_min < x_max)", road.xMin, road.xMax));
    }
    // Roads are laid out in cells of a shared network sized by the region.
    if (road.xMax - road.xMin > kMaxRoadLength || std::abs(road.xMin) > kMaxRoadLength ||
        std::abs(road.xMax) > kMaxRoadLength) {
      reader.fail(range, "road.x_range",
                  fmt::format("[{}, {}]: expected a region within -{} .. {} m", road.xMin, road.xMax, kMaxRoadLength,
                              kMaxRoadLength));
    }
  }
  road.points = reader.integer(node, "points", "road.points", road.points, 2, 10'000);
  road.centre = node["centre"] ? reader.expression(node["centre"], "road.centre", with_x) : Expression::constant(0.0);
  if (node["centre_noise"]) road.centreNoise = reader.distribution(node["centre_noise"], "road.centre_noise", inputs);
  road.lanes = reader.integer(node, "lanes", "road.lanes", road.lanes, 1, 16);
  if (node["lane_width"]) road.laneWidth = reader.expression(node["lane_width"], "road.lane_width", inputs);
  if (road.laneWidth.isConstant() && !(road.laneWidth.evaluate({}) > 0.0 && road.laneWidth.evaluate({}) <= 50.0)) {
    throw ConfigError::field(reader.where(node["lane_width"], "road.lane_width"), "road.lane_width",
                             road.laneWidth.text(), "a width in (0, 50] m");
  }
  if (node["lane_width_noise"]) {
    road.laneWidthNoise = reader.distribution(node["lane_width_noise"], "road.lane_width_noise", inputs);
  }
  road.speedLimit = reader.number(node, "speed_limit", "road.speed_limit", road.speedLimit);
  if (!(road.speedLimit > 0.0)) {
    throw ConfigError::field(reader.where(node["speed_limit"], "road.speed_limit"), "road.speed_limit",
                             formatValue(road.speedLimit), "a speed > 0 m/s");
  }
  if (const auto extension = node["extension"]) {
    reader.checkKeys(extension, "road.extension", {"before", "after"});
    road.extensionBefore = reader.number(extension, "before", "road.extension.before", road.extensionBefore);
    road.extensionAfter = reader.number(extension, "after", "road.extension.after", road.extensionAfter);
    if (!(road.extensionBefore >= 0.0 && road.extensionBefore <= kMaxRoadLength) ||
        !(road.extensionAfter >= 0.0 && road.extensionAfter <= kMaxRoadLength)) {
      reader.fail(extension, "road.extension", fmt::format("expected lengths in 0 .. {} m", kMaxRoadLength));
    }
  }
}

void parseCommonVehicle(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                        const std::vector<std::string>& inputs, const LogicalScenario& scenario, VehicleSpec& vehicle) {
  vehicle.where = reader.where(node, field);
  if (!node["x"]) reader.fail(node, field, "missing 'x' (initial x of the vehicle's centre, m)");
  vehicle.x = reader.expression(node["x"], field + ".x", inputs);
  vehicle.lane = reader.integer(node, "lane", field + ".lane", 0, 0);
  if (vehicle.lane >= scenario.road.lanes) {
    throw ConfigError::field(reader.where(node["lane"], field + ".lane"), field + ".lane", std::to_string(vehicle.lane),
                             fmt::format("a lane index below road.lanes = {}", scenario.road.lanes));
  }
  vehicle.length = reader.number(node, "length", field + ".length", vehicle.length);
  vehicle.width = reader.number(node, "width", field + ".width", vehicle.width);
  if (!(vehicle.length > 0.0 && vehicle.length <= 100.0) || !(vehicle.width > 0.0 && vehicle.width <= 20.0)) {
    reader.fail(node, field, "expected a length in (0, 100] m and a width in (0, 20] m");
  }
}

void parseController(const YamlReader& reader, const YAML::Node& node, const std::string& field,
                     const std::vector<std::string>& inputs, ControllerSpec& controller) {
  controller.where = reader.where(node, field);
  reader.checkKeys(node, field, {"name", "library", "params"});
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
}

void parseVehicles(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) reader.fail(YAML::Node(), "vehicles", "missing section 'vehicles' (at least 'ego')");
  reader.checkKeys(node, "vehicles", {"ego", "others"});
  const auto inputs = scenario.inputNames();
  const auto ego = node["ego"];
  if (!ego) reader.fail(node, "vehicles.ego", "missing: every scenario needs an Ego (the vehicle under test)");
  reader.checkKeys(ego, "vehicles.ego", {"x", "lane", "speed", "length", "width", "heading_noise_deg", "controller"});
  VehicleSpec& spec = scenario.ego;
  spec.id = "ego";
  parseCommonVehicle(reader, ego, "vehicles.ego", inputs, scenario, spec);
  if (!ego["speed"]) reader.fail(ego, "vehicles.ego", "missing 'speed' (initial speed, m/s)");
  spec.speed = reader.expression(ego["speed"], "vehicles.ego.speed", inputs);
  parseHeadingNoise(reader, ego, "vehicles.ego", inputs, spec);
  if (!ego["controller"]) reader.fail(ego, "vehicles.ego", "missing 'controller'");
  parseController(reader, ego["controller"], "vehicles.ego.controller", inputs, spec.controller);

  std::set<std::string> ids = {"ego"};
  if (const auto others = node["others"]) {
    if (!others.IsSequence()) reader.fail(others, "vehicles.others", "expected a list of vehicles");
    for (std::size_t i = 0; i < others.size(); ++i) {
      const auto item = others[i];
      const std::string field = fmt::format("vehicles.others[{}]", i);
      reader.checkKeys(item, field,
                       {"id", "x", "lane", "length", "width", "speed_profile", "speed_noise", "heading_noise_deg"});
      VehicleSpec other;
      other.id = item["id"] ? reader.scalar(item["id"], field + ".id") : fmt::format("other{}", i);
      if (!isIdentifier(other.id) || !ids.insert(other.id).second) {
        throw ConfigError::field(reader.where(item["id"], field + ".id"), field + ".id", other.id,
                                 "a unique identifier (letters, digits, _)");
      }
      parseCommonVehicle(reader, item, field, inputs, scenario, other);
      const auto profile = item["speed_profile"];
      if (!profile) reader.fail(item, field, "missing 'speed_profile' (initial speed and phases)");
      reader.checkKeys(profile, field + ".speed_profile", {"initial", "phases"});
      if (!profile["initial"]) reader.fail(profile, field + ".speed_profile", "missing 'initial' (m/s)");
      other.speedProfile.initial = reader.expression(profile["initial"], field + ".speed_profile.initial", inputs);
      if (const auto phases = profile["phases"]) {
        if (!phases.IsSequence()) reader.fail(phases, field + ".speed_profile.phases", "expected a list of phases");
        for (std::size_t p = 0; p < phases.size(); ++p) {
          const std::string phase_field = fmt::format("{}.speed_profile.phases[{}]", field, p);
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
      if (item["speed_noise"]) other.speedNoise = reader.distribution(item["speed_noise"], field + ".speed_noise", inputs);
      parseHeadingNoise(reader, item, field, inputs, other);
      scenario.others.push_back(std::move(other));
    }
  }
}

void parseRest(const YamlReader& reader, const YAML::Node& root, LogicalScenario& scenario) {
  if (const auto metrics = root["metrics"]) {
    if (!metrics.IsSequence()) reader.fail(metrics, "metrics", "expected a list of metric names");
    for (std::size_t i = 0; i < metrics.size(); ++i) {
      scenario.metrics.push_back(reader.scalar(metrics[i], fmt::format("metrics[{}]", i)));
    }
  }
  if (const auto criteria = root["criteria"]) {
    if (!criteria.IsSequence()) reader.fail(criteria, "criteria", "expected a list of {name, fail_if}");
    for (std::size_t i = 0; i < criteria.size(); ++i) {
      const std::string field = fmt::format("criteria[{}]", i);
      reader.checkKeys(criteria[i], field, {"name", "fail_if"});
      if (!criteria[i]["name"] || !criteria[i]["fail_if"]) reader.fail(criteria[i], field, "needs 'name' and 'fail_if'");
      scenario.criteria.push_back({reader.scalar(criteria[i]["name"], field + ".name"),
                                   reader.scalar(criteria[i]["fail_if"], field + ".fail_if"),
                                   reader.where(criteria[i]["fail_if"], field + ".fail_if")});
    }
  }
  if (const auto sumo = root["sumo"]) {
    reader.checkKeys(sumo, "sumo", {"collision_action", "netconvert_options", "sumo_options"});
    if (sumo["collision_action"]) {
      const auto action = reader.scalar(sumo["collision_action"], "sumo.collision_action");
      static const std::set<std::string> kActions = {"none", "warn", "teleport", "remove"};
      if (kActions.count(action) == 0) {
        throw ConfigError::field(reader.where(sumo["collision_action"], "sumo.collision_action"),
                                 "sumo.collision_action", action, "one of none, warn, teleport, remove");
      }
      scenario.sumo.collisionAction = action;
    }
    auto strings = [&](const char* key, std::vector<std::string>& out, SumoTool tool) {
      const auto list = sumo[key];
      if (!list) return;
      if (!list.IsSequence()) reader.fail(list, std::string("sumo.") + key, "expected a list of command-line options");
      for (std::size_t i = 0; i < list.size(); ++i) out.push_back(reader.scalar(list[i], fmt::format("sumo.{}[{}]", key, i)));
      checkScenarioToolOptions(tool, out, reader.where(list, "sumo"), key);
    };
    strings("netconvert_options", scenario.sumo.netconvertOptions, SumoTool::Netconvert);
    strings("sumo_options", scenario.sumo.sumoOptions, SumoTool::Sumo);
  }
}

}  // namespace

std::shared_ptr<const LogicalScenario> parseLogicalScenario(const std::string& yaml_text,
                                                            const std::filesystem::path& source_name) {
  const YamlReader reader(source_name.string());
  const YAML::Node root = loadYaml(yaml_text, source_name.string());
  if (!root.IsMap()) throw ConfigError(source_name.string() + ": expected a YAML mapping at the top level");
  reader.checkKeys(root, "", {"schema", "name", "description", "time", "inputs", "road", "vehicles", "metrics",
                              "criteria", "sumo"});
  auto scenario = std::make_shared<LogicalScenario>();
  scenario->sourceFile = source_name;
  if (const auto schema = root["schema"]) {
    const auto value = reader.scalar(schema, "schema");
    if (value != "vsd-scenario/1") throw ConfigError::field(reader.where(schema, "schema"), "schema", value, "vsd-scenario/1");
  }
  if (!root["name"]) throw ConfigError(source_name.string() + ": missing 'name' (the functional scenario's label)");
  scenario->name = reader.scalar(root["name"], "name");
  if (!isIdentifier(scenario->name)) {
    throw ConfigError::field(reader.where(root["name"], "name"), "name", scenario->name,
                             "an identifier (letters, digits, _)");
  }
  if (root["description"]) scenario->description = reader.scalar(root["description"], "description");
  parseTime(reader, root["time"], *scenario);
  parseInputs(reader, root["inputs"], *scenario);
  parseRoad(reader, root["road"], *scenario);
  parseVehicles(reader, root["vehicles"], *scenario);
  parseRest(reader, root, *scenario);
  return scenario;
}

std::shared_ptr<const LogicalScenario> loadLogicalScenario(const std::filesystem::path& file) {
  std::string text;
  try {
    text = readTextFile(file, read_limits::kScenario);
  } catch (const IoError& error) {
    throw ConfigError(error.what());
  }
  return parseLogicalScenario(text, file);
}

}  // namespace vsd::scenario
