// ParameterValueDistribution files: the parameter grid, and `vsd-sumo run VARIATION.xosc`
// (the template once per parameter set that satisfies its ConstraintGroups).

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include "osc_template.hpp"
#include "vsd/interop/scenario_formats.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/scripted_vehicle.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

/// Parameter sets a grid may hold: the product of its distributions is checked before it is built.
constexpr double kMaxSets = 10'000'000.0;
/// Range points per distribution (a step width of 1e-300 is no grid).
constexpr double kMaxPoints = 1'000'000.0;

using Axis = std::vector<std::map<std::string, std::string>>;  ///< the alternatives one distribution offers

Axis singleDistribution(const xml::Reader& reader, const pugi::xml_node& single) {
  reader.requireSubset(single, {"DistributionSet", "DistributionRange"});
  const std::string name = reader.text(single, "parameterName");
  const pugi::xml_node choice = reader.choice(single, {"DistributionSet", "DistributionRange"});
  Axis axis;
  if (std::string(choice.name()) == "DistributionSet") {
    reader.requireSubset(choice, {"Element"});
    for (const pugi::xml_node& element : choice.children("Element")) axis.push_back({{name, reader.text(element, "value")}});
    if (axis.empty()) reader.fail(choice, "expected at least one <Element>");
    return axis;
  }
  reader.requireSubset(choice, {"Range"});
  const double step = reader.number(choice, "stepWidth", NumberRange::above(0.0));
  const pugi::xml_node range = reader.only(choice, "Range");
  const double low = reader.number(range, "lowerLimit");
  const double high = reader.number(range, "upperLimit");
  const double points = std::floor((high - low) / step + 1e-9) + 1.0;
  if (!(points >= 1.0 && points <= kMaxPoints)) {
    reader.fail(range, fmt::format("[{}, {}] in steps of {}: expected 1 .. {} points", xml::number(low),
                                   xml::number(high), xml::number(step), kMaxPoints));
  }
  for (double k = 0; k < points; ++k) {
    // Computed, not accumulated; rounded to 1e-9 so that 1.1 + 2 * 0.2 is the 1.5 the file means.
    axis.push_back({{name, xml::number(std::round((low + k * step) * 1e9) / 1e9)}});
  }
  return axis;
}

Axis multiDistribution(const xml::Reader& reader, const pugi::xml_node& multi) {
  reader.requireSubset(multi, {"ValueSetDistribution"});
  const pugi::xml_node sets = reader.only(multi, "ValueSetDistribution");
  reader.requireSubset(sets, {"ParameterValueSet"});
  Axis axis;
  for (const pugi::xml_node& set : sets.children("ParameterValueSet")) {
    reader.requireSubset(set, {"ParameterAssignment"});
    std::map<std::string, std::string> values;
    for (const pugi::xml_node& assignment : set.children("ParameterAssignment")) {
      const std::string name = reader.text(assignment, "parameterRef");
      if (!values.emplace(name, reader.text(assignment, "value")).second) {
        reader.fail(assignment, fmt::format("parameter '{}' is assigned twice in one <ParameterValueSet>", name));
      }
    }
    axis.push_back(values);
  }
  if (axis.empty()) reader.fail(sets, "expected at least one <ParameterValueSet>");
  return axis;
}

}  // namespace

ParameterGrid readParameterDistribution(const fs::path& file, const OscImportOptions& options, std::uint64_t seed) {
  xml::Reader reader(file, read_limits::kScenario);
  const pugi::xml_node root = reader.root();
  const pugi::xml_node distribution = root.child("ParameterValueDistribution");
  if (std::string(root.name()) != "OpenSCENARIO" || !distribution) {
    reader.fail(root, "expected <OpenSCENARIO> with a <ParameterValueDistribution>");
  }
  reader.requireSubset(root, {"FileHeader", "ParameterValueDistribution"});
  reader.requireSubset(distribution, {"ScenarioFile", "Deterministic", "Stochastic"});
  ParameterGrid grid;
  grid.file = file;
  const pugi::xml_node scenario = reader.only(distribution, "ScenarioFile");
  grid.scenarioFile =
      osc::referencedFile(options, file, reader.text(scenario, "filepath"), reader.where(scenario), "filepath");
  if (!fs::exists(grid.scenarioFile)) reader.fail(scenario, fmt::format("{} does not exist", grid.scenarioFile.string()));
  if (const ScenarioFormat& format = scenarioFormatOf(grid.scenarioFile); format.logical) {
    grid.logicalTemplate = format.logical(grid.scenarioFile);
  }
  if (distribution.child("Stochastic")) {
    if (distribution.child("Deterministic")) {
      reader.fail(distribution.child("Deterministic"), "expected either <Deterministic> or <Stochastic>, not both");
    }
    grid.sets = osc::drawStochasticSets(reader, reader.only(distribution, "Stochastic"), seed);
    return grid;
  }
  const pugi::xml_node deterministic = reader.only(distribution, "Deterministic");
  reader.requireSubset(deterministic, {"DeterministicSingleParameterDistribution", "DeterministicMultiParameterDistribution"});
  std::vector<Axis> axes;
  double product = 1.0;
  std::map<std::string, int> varied_at;  // parameter -> line of the distribution that varies it
  for (const pugi::xml_node& node : deterministic.children()) {
    if (node.type() != pugi::node_element) continue;
    axes.push_back(std::string(node.name()) == "DeterministicSingleParameterDistribution" ? singleDistribution(reader, node)
                                                                                          : multiDistribution(reader, node));
    // A parameter varied twice would take the later distribution's values only: refused.
    std::set<std::string> varied;
    for (const auto& alternative : axes.back()) {
      for (const auto& [name, value] : alternative) varied.insert(name);
    }
    for (const std::string& name : varied) {
      if (const auto earlier = varied_at.find(name); earlier != varied_at.end()) {
        reader.fail(node, fmt::format("parameter '{}' is varied by the distribution at line {} already: each "
                                      "parameter is varied by one distribution",
                                      name, earlier->second));
      }
      varied_at.emplace(name, reader.line(node));
    }
    product *= static_cast<double>(axes.back().size());
    if (product > kMaxSets) reader.fail(node, fmt::format("more than {} parameter sets", kMaxSets));
  }
  // The product, the last distribution varying fastest.
  grid.sets.push_back({});
  for (const auto& axis : axes) {
    std::vector<std::map<std::string, std::string>> next;
    next.reserve(grid.sets.size() * axis.size());
    for (const auto& set : grid.sets) {
      for (const auto& values : axis) {
        auto combined = set;
        for (const auto& [name, value] : values) combined[name] = value;
        next.push_back(std::move(combined));
      }
    }
    grid.sets = std::move(next);
  }
  return grid;
}

std::string SweepSummary::report() const {
  std::string text = run.report();
  const std::uint64_t runnable = sets - skipped - refused;
  text += fmt::format(
      "parameter sets: {} in the grid, {} skipped by the template's constraints, {} failed (refused by the import or "
      "road users that cannot start), {} run{}\n",
      sets, skipped, refused, simulated,
      simulated < runnable ? fmt::format(" (--samples: drawn with seed {} from the {} others)", drawnWithSeed,
                                         runnable)
                           : "");
  if (!firstSkipped.empty()) text += fmt::format("first skipped: {}\n", firstSkipped);
  if (!firstRefused.empty()) text += fmt::format("first failed: {}\n", firstRefused);
  if (overlapping > 0) {
    text += fmt::format("{} of the sets that run start with road users other than the Ego overlapping (simulated as "
                        "placed), the first: {}\n", overlapping, firstOverlapping);
  }
  return text;
}


namespace {

/// For each string parameter the grid varies, its values in order of appearance (their codes).
/// (A stochastic grid holds millions of distinct values: seen by a set, not a list search.)
osc::StringCodes stringCodes(const ParameterGrid& grid) {
  osc::StringCodes codes;
  std::map<std::string, std::set<std::string>> seen;
  for (const auto& set : grid.sets) {
    for (const auto& [name, value] : set) {
      if (seen[name].insert(value).second) codes[name].push_back(value);
    }
  }
  return codes;
}

/// A set over a logical scenario (as `scenario distribution` writes them): the inputs it names
/// become constants, the others are drawn as the file says (per seed and sample).
std::shared_ptr<const scenario::LogicalScenario> logicalSet(const ParameterGrid& grid, std::size_t set) {
  auto logical = std::make_shared<scenario::LogicalScenario>(*grid.logicalTemplate);
  const std::string where = fmt::format("{}: parameter set {}", grid.file.string(), set);
  for (const auto& [name, text] : grid.sets[set]) {
    const auto input = std::find_if(logical->inputs.begin(), logical->inputs.end(),
                                    [&name = name](const scenario::InputSpec& spec) { return spec.name == name; });
    if (input == logical->inputs.end()) {
      throw ConfigError(fmt::format("{}: '{}' is not an input of {} (its inputs: {})", where, name,
                                    grid.scenarioFile.string(), fmt::join(logical->inputNames(), ", ")));
    }
    scenario::Distribution fixed;
    fixed.value = scenario::Expression::constant(parseReal(text, NumberRange::any(), where, name));
    fixed.where = where + ": " + name;
    input->distribution = fixed;
  }
  return logical;
}

/// The language scenario of one parameter set; nullopt (and `violation`) if a constraint fails.
/// `warn`: print the translation's warnings (a road's slopes, say) — the sweep's first set does,
/// so that they are said once, not per set.
std::shared_ptr<const scenario::LogicalScenario> importSet(const ParameterGrid& grid, const OscImportOptions& import,
                                                           const osc::StringCodes& codes, std::size_t set,
                                                           std::string* violation, bool warn = false) {
  if (grid.logicalTemplate) return logicalSet(grid, set);
  osc::Findings findings(/*collect=*/false);
  const auto result = osc::translate(grid.scenarioFile, import, grid.sets[set], fmt::format("{}: parameter set {}",
                                     grid.file.string(), set), findings, codes);
  if (result.violated) {
    if (!violation) throw ConfigError(*result.violated);
    *violation = *result.violated;
    return nullptr;
  }
  for (const auto& line : findings.lines()) {
    if (warn && line.warn) spdlog::warn("{}", line.text);
  }
  return osc::loadLanguage(grid.file, result.yaml);
}

}  // namespace

namespace osc {

std::vector<std::string> checkStart(const scenario::ConcreteScenario& concrete) {
  const auto road = road::buildRoadGeometry(concrete);
  return sim::ScriptedTraffic(concrete, road).startOverlaps();
}

SetVerdict judgeSet(const ParameterGrid& grid, const OscImportOptions& import, const StringCodes& codes,
                    std::size_t set, std::uint64_t seed, std::uint64_t index) {
  faultPoint("osc.set");
  throwIfInterrupted();  // a grid of a million sets takes minutes to judge
  try {
    std::string violation;
    const auto logical = importSet(grid, import, codes, set, &violation);
    if (!logical) return {SetVerdict::Kind::Skipped, violation, ""};
    try {
      const auto overlaps = checkStart(scenario::sampleConcreteScenario(logical, seed, index));
      if (!overlaps.empty()) return {SetVerdict::Kind::Runs, "", overlaps.front()};
    } catch (const ConfigError& error) {
      return {SetVerdict::Kind::CannotStart, error.what(), ""};
    }
  } catch (const ConfigError& error) {
    return {SetVerdict::Kind::Refused, error.what(), ""};
  }
  return {};
}

}  // namespace osc

namespace {

/// A parameter set that runs, and the first pair of its road users let start overlapping ("" if none).
struct AcceptedSet {
  std::size_t set = 0;
  std::string overlap;
};

/// The sets of a grid that run, in grid order: each imported and its road users' start checked,
/// the others counted in `summary` (skipped by a constraint, failed at the start).
std::vector<AcceptedSet> acceptSets(const ParameterGrid& grid, const OscImportOptions& import,
                                    const osc::StringCodes& codes, std::uint64_t seed, SweepSummary& summary) {
  summary.sets = grid.sets.size();
  std::vector<AcceptedSet> accepted;
  Progress progress(fmt::format("import {}", grid.file.filename().string()), grid.sets.size(), "sets");
  for (std::size_t set = 0; set < grid.sets.size(); ++set, progress.advance()) {
    const auto verdict = osc::judgeSet(grid, import, codes, set, seed, accepted.size());
    switch (verdict.kind) {
      case osc::SetVerdict::Kind::Runs:
        accepted.push_back({set, verdict.overlap});
        break;
      case osc::SetVerdict::Kind::Skipped:
        if (summary.skipped++ == 0) summary.firstSkipped = fmt::format("parameter set {}: {}", set, verdict.message);
        break;
      case osc::SetVerdict::Kind::Refused:
      case osc::SetVerdict::Kind::CannotStart:
        if (summary.refused++ == 0) summary.firstRefused = fmt::format("parameter set {}: {}", set, verdict.message);
        break;
    }
  }
  if (accepted.empty()) {
    throw ConfigError(fmt::format("{}: none of the {} parameter sets can run ({} violate the template's constraints{}, "
                                  "{} fail: refused by the import or road users that cannot start{})",
                                  grid.file.string(), grid.sets.size(), summary.skipped,
                                  summary.firstSkipped.empty() ? "" : ", first: " + summary.firstSkipped,
                                  summary.refused,
                                  summary.firstRefused.empty() ? "" : ", first: " + summary.firstRefused));
  }
  return accepted;
}

/// `count` of the `accepted` sets, drawn without replacement from the seed's own stream (a
/// regular spacing would alias with a grid's periods and could leave a value out), in grid order.
std::vector<AcceptedSet> drawSets(const std::vector<AcceptedSet>& accepted, std::uint64_t count, std::uint64_t seed) {
  Rng rng = Rng::derive(seed, 0, RandomStream::GridSamples);
  std::vector<std::size_t> order = rng.permutation(accepted.size());
  order.resize(static_cast<std::size_t>(count));
  std::sort(order.begin(), order.end());
  std::vector<AcceptedSet> chosen;
  chosen.reserve(order.size());
  for (const std::size_t position : order) chosen.push_back(accepted[position]);
  return chosen;
}

/// Counts the sets that run with road users other than the Ego overlapping, the first named.
void countOverlaps(const std::vector<AcceptedSet>& running, SweepSummary& summary) {
  for (const AcceptedSet& accepted : running) {
    if (accepted.overlap.empty()) continue;
    if (summary.overlapping++ == 0) {
      summary.firstOverlapping = fmt::format("parameter set {}: {}", accepted.set, accepted.overlap);
    }
  }
}

/// What the sweep's workers do per sample: the set imported again, sampled, its road built.
pipeline::ScenarioWithRoad sweepSample(const ParameterGrid& grid, const OscImportOptions& import,
                                       const osc::StringCodes& codes, std::size_t set, std::uint64_t seed,
                                       std::uint64_t index) {
  const auto logical = importSet(grid, import, codes, set, nullptr);
  auto concrete = scenario::sampleConcreteScenario(logical, seed, index);
  auto road = road::buildRoadGeometry(concrete);
  return pipeline::ScenarioWithRoad{std::move(concrete), std::move(road)};
}

}  // namespace

SweepSummary runVariation(pipeline::RunOptions options, const OscImportOptions& import, bool samples_given) {
  options.validate();  // the flags before judging the sets, which takes minutes on a large grid
  const ParameterGrid grid = readParameterDistribution(options.scenarioFile, import, options.seed);
  // Numeric-looking strings are numbers in concrete.csv already; only names need codes.
  const osc::StringCodes codes = stringCodes(grid);
  SweepSummary summary;
  std::vector<AcceptedSet> accepted = acceptSets(grid, import, codes, options.seed, summary);
  const auto first = importSet(grid, import, codes, accepted.front().set, nullptr, /*warn=*/true);
  if (samples_given && options.samples < accepted.size()) {
    accepted = drawSets(accepted, options.samples, options.seed);
    summary.drawnWithSeed = options.seed;
  }
  countOverlaps(accepted, summary);
  options.samples = accepted.size();
  summary.simulated = accepted.size();
  options.firstSample = 0;
  options.source = [grid, import, codes, accepted, seed = options.seed](std::uint64_t index) {
    return sweepSample(grid, import, codes, accepted.at(index).set, seed, index);
  };
  summary.run = pipeline::runScenarios(first, options);
  return summary;
}

SweepImportTiming timeSweepImport(const fs::path& file, const OscImportOptions& import, std::uint64_t seed) {
  SweepImportTiming timing;
  auto start = std::chrono::steady_clock::now();
  const ParameterGrid grid = readParameterDistribution(file, import, seed);
  const osc::StringCodes codes = stringCodes(grid);
  timing.gridSeconds = secondsSince(start);
  start = std::chrono::steady_clock::now();
  const std::vector<AcceptedSet> accepted = acceptSets(grid, import, codes, seed, timing.counts);
  timing.acceptSeconds = secondsSince(start);
  countOverlaps(accepted, timing.counts);
  start = std::chrono::steady_clock::now();
  for (std::size_t index = 0; index < accepted.size(); ++index) {
    sweepSample(grid, import, codes, accepted[index].set, seed, index);
  }
  timing.sampleSeconds = secondsSince(start);
  timing.counts.simulated = accepted.size();
  return timing;
}

double SweepImportTiming::millisecondsPerSet() const {
  if (counts.sets == 0 || counts.simulated == 0) return 0.0;
  return 1000.0 * (acceptSeconds / static_cast<double>(counts.sets) +
                   sampleSeconds / static_cast<double>(counts.simulated));
}

}  // namespace vsd::interop
