#include "vsd/interop/openscenario_export.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/interop/openscenario.hpp"
#include "vsd/interop/scenario_formats.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/scenario/expression.hpp"
#include "vsd/sim/controller.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

/// What to export: the logical scenario and the (seed, sample) of each concrete scenario.
struct Plan {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> selected;  ///< (seed, sample index)
  std::uint64_t considered = 0;
};

Plan planFromLogicalScenario(const ScenarioExportOptions& options) {
  Plan plan;
  plan.logical = scenario::loadLogicalScenario(options.input);
  for (std::uint64_t i = 0; i < options.samples; ++i) plan.selected.emplace_back(options.seed, options.firstSample + i);
  plan.considered = options.samples;
  return plan;
}

nlohmann::json readRunManifest(const fs::path& folder) {
  const fs::path manifest = folder / "manifest.json";
  if (!fs::exists(manifest)) {
    throw ConfigError(fmt::format("{}: not a run folder (no manifest.json; expected the output of `vsd-sumo run`)",
                                  folder.string()));
  }
  try {
    return nlohmann::json::parse(readTextFile(manifest));
  } catch (const nlohmann::json::exception& error) {
    throw DatasetError(fmt::format("{}: not valid JSON ({})", manifest.string(), error.what()));
  }
}

/// The logical scenario a run was made from, as its manifest names it, unchanged since.
std::shared_ptr<const scenario::LogicalScenario> runScenario(const fs::path& folder, const nlohmann::json& manifest) {
  const fs::path manifest_file = folder / "manifest.json";
  const fs::path scenario_file = manifest.value("scenario_file", std::string());
  if (scenario_file.empty() || !fs::exists(scenario_file)) {
    throw ConfigError(fmt::format("{}: scenario_file '{}' does not exist (the run folder needs the logical scenario it "
                                  "was made from, at the path the run was given)",
                                  manifest_file.string(), scenario_file.string()));
  }
  const ScenarioFormat& format = scenarioFormatOf(scenario_file);
  if (!format.can.exportable) {
    throw ConfigError(fmt::format("{}: the run simulated {} (format {}); it is its own export",
                                  manifest_file.string(), scenario_file.string(), format.name));
  }
  const std::string recorded = manifest.value("scenario_sha256", std::string());
  if (!recorded.empty() && recorded != sha256OfFile(scenario_file)) {
    throw ConfigError(fmt::format("{}: {} has changed since the run (SHA-256 differs from the manifest's); its concrete "
                                  "scenarios cannot be re-sampled",
                                  manifest_file.string(), scenario_file.string()));
  }
  return scenario::loadLogicalScenario(scenario_file);
}

/// Compiled criteria over the run's metric columns: true if a row fails any of them.
class CriteriaCheck {
 public:
  CriteriaCheck(const scenario::LogicalScenario& logical, const CsvTable& table, const std::vector<std::string>& metrics) {
    if (logical.criteria.empty()) {
      throw ConfigError(fmt::format("--only failures: {} defines no criteria (add e.g. `criteria: [{{name: close, "
                                    "fail_if: d_min < 2}}]`)",
                                    logical.sourceFile.string()));
    }
    for (const auto& name : metrics) columns_.push_back(table.column(name));
    for (const auto& criterion : logical.criteria) {
      expressions_.push_back(scenario::Expression::compile(criterion.expression, metrics, criterion.where));
    }
  }
  bool fails(const CsvTable& table, std::size_t row) const {
    std::vector<double> values;
    for (const auto column : columns_) values.push_back(table.number(row, column));
    for (const auto& expression : expressions_) {
      const double verdict = expression.evaluate(values);
      if (!std::isnan(verdict) && verdict != 0.0) return true;  // NaN: a metric was not computable
    }
    return false;
  }

 private:
  std::vector<std::size_t> columns_;
  std::vector<scenario::Expression> expressions_;
};

Plan planFromRunFolder(const ScenarioExportOptions& options) {
  const nlohmann::json manifest = readRunManifest(options.input);
  Plan plan;
  plan.logical = runScenario(options.input, manifest);
  const CsvTable table = CsvTable::read(options.input / "concrete.csv");
  const auto sample_column = table.column("sample");
  const auto seed_column = table.column("seed");
  const auto status_column = table.column("status");
  std::optional<CriteriaCheck> criteria;
  if (options.only == ScenarioExportOptions::Only::Failures) {
    criteria.emplace(*plan.logical, table, manifest.value("metrics", std::vector<std::string>{}));
  }
  for (std::size_t row = 0; row < table.rows(); ++row) {
    ++plan.considered;
    if (criteria && (table.cell(row, status_column) != "ok" || !criteria->fails(table, row))) continue;
    plan.selected.emplace_back(static_cast<std::uint64_t>(table.number(row, seed_column)),
                               static_cast<std::uint64_t>(table.number(row, sample_column)));
  }
  return plan;
}

nlohmann::json exportManifest(const ScenarioExportOptions& options, const Plan& plan) {
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  manifest["tool_version"] = toolVersion();
  manifest["command_line"] = options.commandLine;
  manifest["input"] = options.input.string();
  manifest["scenario_file"] = plan.logical->sourceFile.string();
  manifest["scenario_sha256"] = sha256OfFile(plan.logical->sourceFile);
  manifest["functional_scenario"] = plan.logical->name;
  manifest["format"] = options.format;
  manifest["exported"] = plan.selected.size();
  return manifest;  // OutputFolder::commit adds every file's SHA-256 and size
}

}  // namespace

void ScenarioExportOptions::validate() const {
  if (format != "openscenario") {
    throw ConfigError::field("command line", "--format", format, "openscenario (OpenSCENARIO 1.2 + OpenDRIVE 1.6)");
  }
  const bool run_folder = fs::is_directory(input);
  if (!run_folder && samples < 1) throw ConfigError::field("command line", "--samples", std::to_string(samples), ">= 1");
  if (!run_folder && only != Only::All) {
    throw ConfigError::field("command line", "--only", "failures",
                             "a run folder (failures are judged on simulated metrics; run the scenario first)");
  }
}

/// The files carry what the paper's scenarios are made of: a polynomial road, road users
/// placed by x, each scripted road user's speed at every step. Anything else comes back as
/// another scenario (a cut-in without its lane change, an arc road's road users 30 m off), so
/// it is refused before anything is written.
void refuseWhatTheFilesCannotCarry(const scenario::LogicalScenario& logical) {
  const std::string limit = "the OpenSCENARIO export carries the paper's kind of scenario only (docs/interop.md); "
                            "a file of this one would re-simulate another scenario";
  if (logical.road.shape != scenario::RoadSpec::Shape::Polynomial) {
    throw ConfigError(fmt::format("{}: road.shape: an arc or polyline road: {}", logical.sourceFile.string(), limit));
  }
  const auto& active_from = logical.ego.controller.activeFrom;
  if (!active_from.isConstant() || active_from.evaluate({}) != 0.0) {
    throw ConfigError(fmt::format("{}: controller.active_from {}: the Ego's scripted phase is not written: {}",
                                  logical.ego.controller.where, active_from.text(), limit));
  }
  std::vector<const scenario::VehicleSpec*> users = {&logical.ego};
  for (const auto& other : logical.others) users.push_back(&other);
  for (const scenario::VehicleSpec* user : users) {
    if (user->along != scenario::VehicleSpec::Along::X) {
      throw ConfigError(fmt::format("{}: '{}' placed by s, ds or gap rather than x: {}", user->where, user->id, limit));
    }
    if (user->againstRoad) {
      throw ConfigError(fmt::format("{}: '{}' drives against the road (direction: against): {}", user->where, user->id,
                                    limit));
    }
    if (user->mayStartOverlapping) {
      throw ConfigError(fmt::format("{}: '{}' may start overlapping others (may_start_overlapping: true), which is not "
                                    "written: {}", user->where, user->id, limit));
    }
    if (user->actions.empty()) continue;
    const auto& action = user->actions.front();
    throw ConfigError(fmt::format("{}: action '{}' of '{}': actions and their triggers are not written: {}",
                                  action.where, action.id, user->id, limit));
  }
}

ScenarioExportSummary exportScenarios(const ScenarioExportOptions& options) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  const Plan plan = fs::is_directory(options.input) ? planFromRunFolder(options) : planFromLogicalScenario(options);
  refuseWhatTheFilesCannotCarry(*plan.logical);
  OutputFolder::Options folder_options;
  folder_options.refuseExisting = !options.force;
  OutputFolder folder(options.outputDir, folder_options);
  const ExportHeader header{fileDate(plan.logical->sourceFile), sha256OfFile(plan.logical->sourceFile)};
  folder.stageText(kControllerCatalogFile,
                   controllerCatalogText(sim::ControllerRegistry::withBuiltins().available(), header.date));
  Progress progress(fmt::format("export {}", plan.logical->name), plan.selected.size(), "scenarios");
  for (const auto& [seed, index] : plan.selected) {
    const auto concrete = scenario::sampleConcreteScenario(plan.logical, seed, index);
    exportConcreteScenario(concrete, folder.stagingPath(), fmt::format("{}_{:06}", plan.logical->name, index), header);
    progress.advance(1);
  }
  progress.finish();
  folder.commit(exportManifest(options, plan));

  ScenarioExportSummary summary;
  summary.outputDir = folder.path();
  summary.functionalScenario = plan.logical->name;
  summary.considered = plan.considered;
  summary.exported = plan.selected.size();
  summary.seconds = secondsSince(start);
  return summary;
}

std::string ScenarioExportSummary::report() const {
  return fmt::format("{}: exported {} of {} concrete scenarios in {:.2f} s ({:.0f} scenarios/s) to {} (.xosc + .xodr each, "
                     "vsd_controllers.xosc, manifest.json)\n",
                     functionalScenario, exported, considered, seconds, static_cast<double>(exported) / std::max(seconds, 1e-9),
                     outputDir.string());
}

}  // namespace vsd::interop
