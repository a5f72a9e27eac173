#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/scenario/yaml_reader.hpp"

#include "parsing.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
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

bool LogicalScenario::hasLateralMotion() const {
  for (const auto& other : others) {
    if (!other.offset.isConstant() || other.offset.evaluate({}) != 0.0) return true;
    for (const auto& action : other.actions) {
      if (action.kind != ActionSpec::Kind::Speed) return true;
    }
  }
  return false;
}

namespace {

/// m: bound of the scenario region and of the road extensions (keeps net coordinates sane).
constexpr double kMaxRoadLength = 10'000.0;

using detail::isIdentifier;

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

/// x_range, points, centre, centre_noise: the paper's road.
void parsePolynomialRoad(const YamlReader& reader, const YAML::Node& node, const std::vector<std::string>& inputs,
                         RoadSpec& road) {
  for (const char* key : {"curvature", "length", "centre_line"}) {
    if (node[key]) reader.fail(node[key], std::string("road.") + key, "belongs to another road shape, not a polynomial");
  }
  auto with_x = inputs;
  with_x.emplace_back("x");
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
}

/// curvature, length: a straight road or a constant radius.
void parseArcRoad(const YamlReader& reader, const YAML::Node& node, const std::vector<std::string>& inputs,
                  RoadSpec& road) {
  for (const char* key : {"x_range", "points", "centre", "centre_noise", "centre_line"}) {
    if (node[key]) reader.fail(node[key], std::string("road.") + key, "belongs to another road shape, not an arc");
  }
  if (!node["length"]) reader.fail(node, "road", "an arc road needs 'length' (m of scenario region along the road)");
  road.length = reader.expression(node["length"], "road.length", inputs);
  road.curvature = node["curvature"] ? reader.expression(node["curvature"], "road.curvature", inputs)
                                     : Expression::constant(0.0);
  if (!road.length.isConstant()) {
    reader.fail(node["length"], "road.length",
                fmt::format("got '{}', expected a number: networks are laid out before sampling", road.length.text()));
  }
  if (!(road.length.evaluate({}) > 0.0 && road.length.evaluate({}) <= kMaxRoadLength)) {
    throw ConfigError::field(reader.where(node["length"], "road.length"), "road.length", road.length.text(),
                             fmt::format("a length in (0, {}] m", kMaxRoadLength));
  }
  if (road.length.isConstant() && road.curvature.isConstant() &&
      !(std::abs(road.curvature.evaluate({}) * road.length.evaluate({})) <= kMaxArcTurn)) {
    throw ConfigError::field(reader.where(node["curvature"], "road.curvature"), "road.curvature",
                             road.curvature.text(),
                             fmt::format("a turn |curvature| * length of at most {} rad over the region", kMaxArcTurn));
  }
}

/// points: a polyline road, its region's centre line as given.
void parsePolylineRoad(const YamlReader& reader, const YAML::Node& node, RoadSpec& road) {
  for (const char* key : {"x_range", "points", "centre", "centre_noise", "curvature", "length"}) {
    if (node[key]) reader.fail(node[key], std::string("road.") + key, "belongs to another road shape, not a polyline");
  }
  const YAML::Node points = node["centre_line"];
  if (!points || !points.IsSequence() || points.size() < 2 || points.size() > 100'000) {
    reader.fail(points ? points : node, "road.centre_line",
                "a polyline road needs 'centre_line': a list of 2 .. 100000 [x, y] in m");
  }
  double length = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string field = fmt::format("road.centre_line[{}]", i);
    if (!points[i].IsSequence() || points[i].size() != 2) reader.fail(points[i], field, "expected [x, y] in m");
    const double x = reader.number(points[i][0], field + "[0]");
    const double y = reader.number(points[i][1], field + "[1]");
    if (!(std::abs(x) <= kMaxRoadLength && std::abs(y) <= kMaxRoadLength)) {
      reader.fail(points[i], field, fmt::format("expected coordinates within -{0} .. {0} m", kMaxRoadLength));
    }
    if (i > 0) {
      const double dx = x - road.centreLine.back().first;
      const double dy = y - road.centreLine.back().second;
      const double step = std::hypot(dx, dy);
      if (!(step >= 1e-3) || !(std::abs(std::atan2(dy, dx)) <= kMaxArcTurn)) {
        reader.fail(points[i], field,
                    fmt::format("the segment from the point before is {:.3g} m long and heads {:.3g} rad from +x: "
                                "expected at least 1 mm, at most {} rad (scenes clip lanes by x, which must advance "
                                "along the region)", step, std::atan2(dy, dx), kMaxArcTurn));
      }
      length += step;
    }
    road.centreLine.emplace_back(x, y);
  }
  if (!(length <= kMaxRoadLength)) {
    reader.fail(points, "road.centre_line", fmt::format("a region of {:.1f} m: expected at most {} m", length, kMaxRoadLength));
  }
}

void parseShoulders(const YamlReader& reader, const YAML::Node& node, RoadSpec& road) {
  reader.checkKeys(node, "road.shoulders", {"left", "right"});
  road.shoulderLeft = reader.number(node, "left", "road.shoulders.left", 0.0);
  road.shoulderRight = reader.number(node, "right", "road.shoulders.right", 0.0);
  if (!(road.shoulderLeft >= 0.0 && road.shoulderLeft <= 50.0) || !(road.shoulderRight >= 0.0 && road.shoulderRight <= 50.0)) {
    reader.fail(node, "road.shoulders", "expected widths in 0 .. 50 m");
  }
}

/// `lane_widths: [w0, w1, ...]`: one width per lane, lane 0 (the rightmost) first.
void parseLaneWidths(const YamlReader& reader, const YAML::Node& node, const std::vector<std::string>& inputs,
                     RoadSpec& road) {
  const YAML::Node list = node["lane_widths"];
  if (node["lane_width"] || node["lane_width_noise"]) {
    reader.fail(list, "road.lane_widths", "either lane_widths or lane_width (with its noise), not both");
  }
  if (!list.IsSequence() || static_cast<int>(list.size()) != road.lanes) {
    reader.fail(list, "road.lane_widths", fmt::format("expected a list of {} widths (road.lanes), lane 0 first",
                                                      road.lanes));
  }
  for (std::size_t lane = 0; lane < list.size(); ++lane) {
    const std::string field = fmt::format("road.lane_widths[{}]", lane);
    road.laneWidths.push_back(reader.expression(list[lane], field, inputs));
    const Expression& width = road.laneWidths.back();
    if (width.isConstant() && !(width.evaluate({}) > 0.5 && width.evaluate({}) <= 50.0)) {
      throw ConfigError::field(reader.where(list[lane], field), field, width.text(), "a width in (0.5, 50] m");
    }
  }
}

void parseRoad(const YamlReader& reader, const YAML::Node& node, LogicalScenario& scenario) {
  if (!node) reader.fail(YAML::Node(), "road", "missing section 'road'");
  reader.checkKeys(node, "road", {"shape", "x_range", "points", "centre", "centre_noise", "centre_line", "curvature", "length", "lanes",
                                  "lane_width", "lane_widths", "lane_width_noise", "speed_limit", "extension",
                                  "shoulders"});
  const auto inputs = scenario.inputNames();
  RoadSpec& road = scenario.road;
  const std::string shape = node["shape"] ? reader.scalar(node["shape"], "road.shape") : "polynomial";
  if (shape == "polynomial") {
    parsePolynomialRoad(reader, node, inputs, road);
  } else if (shape == "arc") {
    road.shape = RoadSpec::Shape::Arc;
    parseArcRoad(reader, node, inputs, road);
  } else if (shape == "polyline") {
    road.shape = RoadSpec::Shape::Polyline;
    parsePolylineRoad(reader, node, road);
  } else {
    throw ConfigError::field(reader.where(node["shape"], "road.shape"), "road.shape", shape,
                             "polynomial, arc or polyline");
  }
  if (node["shoulders"]) parseShoulders(reader, node["shoulders"], road);
  road.lanes = reader.integer(node, "lanes", "road.lanes", road.lanes, 1, 16);
  if (node["lane_width"]) road.laneWidth = reader.expression(node["lane_width"], "road.lane_width", inputs);
  if (road.laneWidth.isConstant() && !(road.laneWidth.evaluate({}) > 0.0 && road.laneWidth.evaluate({}) <= 50.0)) {
    throw ConfigError::field(reader.where(node["lane_width"], "road.lane_width"), "road.lane_width",
                             road.laneWidth.text(), "a width in (0, 50] m");
  }
  if (node["lane_width_noise"]) {
    road.laneWidthNoise = reader.distribution(node["lane_width_noise"], "road.lane_width_noise", inputs);
  }
  if (node["lane_widths"]) parseLaneWidths(reader, node, inputs, road);
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
      if (!isCollisionAction(action)) {
        throw ConfigError::field(reader.where(sumo["collision_action"], "sumo.collision_action"),
                                 "sumo.collision_action", action, collisionActionsExpected());
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
  detail::parseRoadUsers(reader, root["vehicles"], *scenario);
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
