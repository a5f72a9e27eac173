// `vsd-sumo run TEMPLATE.xosc` and `vsd-sumo scenario check FILE.xosc`.

#include <fmt/format.h>

#include "osc_network.hpp"
#include "osc_template.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

bool ScenarioCheck::runnable() const {
  for (const auto& line : lines) {
    if (line.kind == Line::Kind::Refused) return false;
  }
  return true;
}

std::string ScenarioCheck::report() const {
  std::string text;
  std::size_t refused = 0;
  std::size_t notes = 0;
  for (const auto& line : lines) {
    const char* tag = line.kind == Line::Kind::Mapped ? "ok     " : line.kind == Line::Kind::Note ? "note   " : "REFUSED";
    refused += line.kind == Line::Kind::Refused;
    notes += line.kind == Line::Kind::Note;
    text += fmt::format("{} {}\n", tag, line.text);
  }
  text += refused == 0 ? fmt::format("would run ({} notes)\n", notes)
                       : fmt::format("would not run: {} element(s) refused\n", refused);
  return text;
}

namespace {

ScenarioCheck::Line::Kind kindOf(osc::Findings::Kind kind) {
  switch (kind) {
    case osc::Findings::Kind::Mapped:
      return ScenarioCheck::Line::Kind::Mapped;
    case osc::Findings::Kind::Note:
      return ScenarioCheck::Line::Kind::Note;
    case osc::Findings::Kind::Refused:
      break;
  }
  return ScenarioCheck::Line::Kind::Refused;
}

/// Loads the language YAML of a translation (the language's own checks apply).
std::shared_ptr<const scenario::LogicalScenario> loadTranslation(const fs::path& xosc, const std::string& yaml) {
  return osc::loadLanguage(xosc, yaml);
}

/// Every set of a grid imported (not simulated): how many satisfy the constraints, how many
/// the import refuses (the first named), as `run` would meet them.
void countSets(const ParameterGrid& grid, const OscImportOptions& options, osc::Findings& findings) {
  std::size_t skipped = 0;
  std::size_t refused = 0;
  std::size_t failing = 0;
  std::size_t overlapping = 0;
  std::string first_overlapping;
  std::string first_skipped;
  std::string first_refused;
  std::string first_failing;
  Progress progress(fmt::format("check {}", grid.file.filename().string()), grid.sets.size(), "sets");
  for (std::size_t set = 0; set < grid.sets.size(); ++set, progress.advance()) {
    // Sample 0 of seed 1: a check has no sweep seed, and an imported set is one concrete scenario.
    const auto verdict = osc::judgeSet(grid, options, {}, set, 1, 0);
    const std::string first = fmt::format("set {}: {}", set, verdict.message);
    switch (verdict.kind) {
      case osc::SetVerdict::Kind::Runs:
        if (!verdict.overlap.empty() && overlapping++ == 0) {
          first_overlapping = fmt::format("set {}: {}", set, verdict.overlap);
        }
        break;
      case osc::SetVerdict::Kind::Skipped:
        if (skipped++ == 0) first_skipped = first;
        break;
      case osc::SetVerdict::Kind::Refused:
        if (refused++ == 0) first_refused = first;
        break;
      case osc::SetVerdict::Kind::CannotStart:
        if (failing++ == 0) first_failing = first;
        break;
    }
  }
  findings.mapped(grid.file.string(),
                  fmt::format("{} parameter sets: {} skipped by the template's constraints{}, {} refused, {} would "
                              "fail (road users that cannot start{}), {} would run",
                              grid.sets.size(), skipped, first_skipped.empty() ? "" : " (first: " + first_skipped + ")",
                              refused, failing, first_failing.empty() ? "" : "; first: " + first_failing,
                              grid.sets.size() - skipped - refused - failing));
  if (overlapping > 0) {
    findings.note(grid.file.string(), fmt::format("{} of the sets that would run start with road users other than the "
                                                  "Ego overlapping (simulated as placed), the first: {}",
                                                  overlapping, first_overlapping));
  }
  // `run` fails such sets alone and runs the others (runVariation); with none left it refuses the file.
  const bool none_run = skipped + refused + failing == grid.sets.size();
  if (refused > 0 && none_run) {
    findings.refuse(fmt::format("{}: {} parameter sets refused, the first: {}", grid.file.string(), refused, first_refused));
  } else if (refused > 0) {
    findings.note(grid.file.string(), fmt::format("{} parameter sets refused (they fail alone in run), the first: {}",
                                                  refused, first_refused));
  } else if (none_run) {
    findings.refuse(fmt::format("{}: none of the {} parameter sets would run", grid.file.string(), grid.sets.size()));
  }
}

/// The Ego's controllers as `run` builds them before it simulates (names, parameters): built-in
/// ones here; a plugin's code is not run by a check (noted: `run` loads it).
void checkControllers(const scenario::LogicalScenario& logical, const scenario::ConcreteScenario& concrete,
                      osc::Findings& findings) {
  bool plugin = !logical.ego.controller.library.empty();
  for (const auto& action : logical.ego.actions) plugin = plugin || !action.controller.library.empty();
  if (plugin) {
    findings.note(logical.sourceFile.string(), "a controller plugin: run loads it and checks its parameters");
    return;
  }
  pipeline::buildEgoControllers(logical, concrete);
}

/// Road users other than the Ego that start overlapping: OpenSCENARIO sets no rule against it.
std::string overlapNote(const std::string& overlap) {
  return overlap + " (road users other than the Ego may: simulated as placed, they move through each other)";
}

/// The template's one concrete scenario as `run` meets it: its start and the Ego's controllers.
/// Under a distribution the sets assign the values that count (each judged by countSets), so a
/// start that fails at the declared values is a note there.
void checkTemplateStart(const fs::path& file, const std::string& yaml, bool under_distribution,
                        osc::Findings& findings, ScenarioCheck& check) {
  const auto logical = loadTranslation(file, yaml);
  std::optional<scenario::ConcreteScenario> concrete;
  try {
    concrete = scenario::sampleConcreteScenario(logical, 1, 0);
    const auto overlaps = osc::checkStart(*concrete);
    if (!under_distribution) {
      for (const auto& overlap : overlaps) findings.note(file.string(), overlapNote(overlap));
    }
  } catch (const ConfigError& error) {
    if (!under_distribution) throw;
    findings.note(file.string(), std::string("the template cannot start at its declared values, so neither its start "
                                             "nor its controllers are checked at them (the sets are, above): ") +
                                     error.what());
    return;
  }
  checkControllers(*logical, *concrete, findings);
  check.yaml = yaml;
}

}  // namespace

ScenarioCheck checkOpenScenario(const fs::path& file, const OscImportOptions& options) {
  osc::checkCommandLine(options);  // a usage error, not a finding
  osc::Findings findings(/*collect=*/true);
  ScenarioCheck check;
  fs::path scenario_file = file;
  std::optional<ParameterGrid> grid;
  const bool readable = findings.attempt([&] {
    if (!xml::Reader(file, read_limits::kScenario).root().child("ParameterValueDistribution")) return;
    grid = readParameterDistribution(file, options, options.checkSeed);
    findings.mapped(file.string(), fmt::format("ParameterValueDistribution of {} parameter sets over {}",
                                               grid->sets.size(), grid->scenarioFile.string()));
    scenario_file = grid->scenarioFile;
  });
  if (!readable) {
    for (const auto& line : findings.lines()) check.lines.push_back({kindOf(line.kind), line.text});
    return check;
  }
  if (grid && options.network) {  // a usage error, as `run` says it
    throw ConfigError(fmt::format("command line: --network: {} is a parameter distribution: a network scenario is "
                                  "one concrete scenario (check its template with --network)",
                                  file.string()));
  }
  if (!grid && options.network) {
    findings.attempt([&] {
      const auto scenario = osc::translateNetwork(file, options, findings);
      if (scenario) osc::checkNetworkStart(*scenario, options.step.value_or(kDefaultStep), findings);
    });
  }
  if (options.network) {
    for (const auto& line : findings.lines()) check.lines.push_back({kindOf(line.kind), line.text});
    return check;
  }
  if (grid) countSets(*grid, options, findings);
  if (grid && grid->logicalTemplate) {
    findings.mapped(grid->scenarioFile.string(), "a logical scenario: each set fixes the inputs it names");
    for (const auto& line : findings.lines()) check.lines.push_back({kindOf(line.kind), line.text});
    return check;
  }
  osc::TranslationResult result;
  findings.attempt([&] { result = osc::translate(scenario_file, options, {}, "", findings); });
  if (result.violated && grid) {
    // The sets assign the values that count (each set is checked against the constraints above).
    findings.note(scenario_file.string(), "the template's declared values violate its constraints, so its elements "
                                          "are not checked at them: " + *result.violated);
  } else if (result.violated) {
    findings.refuse(*result.violated);  // as run refuses it
  }
  if (!result.yaml.empty()) {
    findings.attempt([&] { checkTemplateStart(scenario_file, result.yaml, grid.has_value(), findings, check); });
  }
  for (const auto& line : findings.lines()) check.lines.push_back({kindOf(line.kind), line.text});
  return check;
}

std::shared_ptr<const scenario::LogicalScenario> importTemplate(const fs::path& xosc, const OscImportOptions& options,
                                                                const std::map<std::string, std::string>& assigned) {
  osc::Findings findings(/*collect=*/false);
  const auto result = osc::translate(xosc, options, assigned, xosc.string(), findings);
  if (result.violated) throw ConfigError(*result.violated);
  for (const auto& line : findings.lines()) {
    if (line.warn) spdlog::warn("{}", line.text);
    else if (line.kind == osc::Findings::Kind::Note) spdlog::debug("{}", line.text);
  }
  return loadTranslation(xosc, result.yaml);
}

pipeline::RunSummary runTemplate(pipeline::RunOptions options, const OscImportOptions& import) {
  const auto logical = importTemplate(options.scenarioFile, import);
  for (const auto& overlap : osc::checkStart(scenario::sampleConcreteScenario(logical, options.seed, 0))) {
    spdlog::warn("{}: {}", options.scenarioFile.string(), overlapNote(overlap));
  }
  options.samples = 1;
  options.firstSample = 0;
  return pipeline::runScenarios(logical, options);
}

}  // namespace vsd::interop
