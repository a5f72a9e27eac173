// `vsd-sumo scenario export | distribution`: concrete scenarios as OpenDRIVE +
// OpenSCENARIO, and a logical scenario as an OpenSCENARIO parameter distribution.

#include <fmt/format.h>

#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/criterion_syntax.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/interop/distribution.hpp"
#include "vsd/interop/openscenario_export.hpp"
#include "vsd/interop/scenario_formats.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::cli {

namespace {

/// The logical scenario of `scenario export`'s input: a logical scenario file, or the one
/// a run folder's manifest names.
std::shared_ptr<const scenario::LogicalScenario> logicalOf(const std::filesystem::path& input) {
  if (!std::filesystem::is_directory(input)) return scenario::loadLogicalScenario(input);
  const auto manifest = nlohmann::json::parse(readTextFile(input / "manifest.json"));
  return scenario::loadLogicalScenario(manifest.at("scenario_file").get<std::string>());
}

/// The functional scenario of `scenario export`'s input.
std::string functionalScenarioOf(const std::filesystem::path& input) {
  if (std::filesystem::is_directory(input)) return pipeline::readRunManifest(input).functionalScenario;
  return scenario::loadLogicalScenario(input)->name;
}

/// --only failures judges by the scenario's criteria: each must be a comparison (docs/cli.md
/// "Criteria"), checked before any work.
void checkCriteriaOf(const std::filesystem::path& input) {
  try {
    for (const auto& criterion : logicalOf(input)->criteria) checkCriterion(criterion.expression, criterion.where);
  } catch (const nlohmann::json::exception&) {
    // No readable manifest: the export reports the folder itself.
  }
}

void addExport(CLI::App& scenario, CommandContext& context) {
  auto options = std::make_shared<interop::ScenarioExportOptions>();
  // The same defaults as `run`: `scenario export X.yaml` writes the scenarios `run X.yaml` simulates.
  const pipeline::RunOptions run_defaults;
  options->samples = run_defaults.samples;
  options->seed = run_defaults.seed;
  CLI::App* command = scenario.add_subcommand(
      "export", "Concrete scenarios as OpenSCENARIO 1.2 + OpenDRIVE 1.6 files (one .xosc + .xodr each)");
  command->add_option("input", options->input, "Logical scenario (YAML) or run folder (output of `vsd-sumo run`)")
      ->required()
      ->check(CLI::ExistingPath);
  command->add_option("-o,--out", options->outputDir, "Output folder")->required();
  command->add_option("--format", options->format, "File format")->capture_default_str();
  addNumber(command, "-n,--samples", options->samples, "YAML input: number of concrete scenarios")->capture_default_str();
  addNumber(command, "-s,--seed", options->seed, "YAML input: random seed (as for `run`)")->capture_default_str();
  addNumber(command, "--first-sample", options->firstSample, "YAML input: index of the first concrete scenario")
      ->capture_default_str();
  command
      ->add_option("--only", options->only,
                   "Run folder input: all scenarios, or those failing one of the scenario's criteria")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, interop::ScenarioExportOptions::Only>{{"all", interop::ScenarioExportOptions::Only::All},
                                                                      {"failures", interop::ScenarioExportOptions::Only::Failures}},
          CLI::ignore_case));
  command->add_flag("--force", options->force,
                    "Replace the export folder of another functional scenario (docs/output-policy.md)");
  command->callback([options, &context] {
    context.action = [options, &context] {
      options->commandLine = context.commandLine;
      const auto status = checkOutput({options->outputDir, &output_kinds::scenarioExportFolder(),
                                       functionalScenarioOf(options->input), options->force, "--out", "--force",
                                       {{"input", options->input}}});
      if (status != OutputStatus::New) options->force = true;  // the policy allowed the replacement
      if (options->only == interop::ScenarioExportOptions::Only::Failures) checkCriteriaOf(options->input);
      fmt::print("{}", interop::exportScenarios(*options).report());
      return 0;
    };
  });
}

void addDistribution(CLI::App& scenario, CommandContext& context) {
  auto scenario_file = std::make_shared<std::filesystem::path>();
  auto options = std::make_shared<interop::DistributionOptions>();
  auto grid = std::make_shared<int>(0);
  const pipeline::RunOptions run_defaults;
  options->samples = run_defaults.samples;
  options->seed = run_defaults.seed;
  CLI::App* command = scenario.add_subcommand(
      "distribution", "A logical scenario's inputs as an OpenSCENARIO ParameterValueDistribution");
  command->add_option("scenario", *scenario_file, "Logical scenario (YAML)")->required()->check(CLI::ExistingFile);
  command->add_option("-o,--out", options->output, "The .xosc to write")->required();
  addNumber(command, "-n,--samples", options->samples, "Stochastic: numberOfTestRuns")->capture_default_str();
  addNumber(command, "-s,--seed", options->seed, "Stochastic: randomSeed")->capture_default_str();
  CLI::Option* grid_option =
      addNumber(command, "--grid", *grid, "A deterministic grid of this many points per input instead");
  command->callback([scenario_file, options, grid, grid_option, &context] {
    context.action = [scenario_file, options, grid, grid_option] {
      if (grid_option->count() > 0) options->grid = *grid;
      checkOutput({options->output, &output_kinds::distributionFile(), "", false, "--out", "--force",
                   {{"scenario", *scenario_file}}});
      const auto logical = scenario::loadLogicalScenario(*scenario_file);
      fmt::print("{}", interop::writeParameterDistribution(*logical, *options).report());
      return 0;
    };
  });
}

void addCheck(CLI::App& scenario, CommandContext& context) {
  auto file = std::make_shared<std::filesystem::path>();
  auto import = std::make_shared<interop::OscImportOptions>();
  auto step = std::make_shared<double>(0.0);
  auto yaml = std::make_shared<bool>(false);
  CLI::App* command = scenario.add_subcommand(
      "check", "What a scenario file holds and whether `run` would take it, element by element, without running; "
               "exit status 0 if it would run");
  command->add_option("file", *file, "Scenario file (any format `run` reads)")->required()->check(CLI::ExistingFile);
  CLI::Option* step_option = addNumber(command, "--step", *step, "OpenSCENARIO input: simulation step (s)");
  addImportOptions(*command, *import);
  addNumber(command, "--seed", import->checkSeed,
            "Stochastic parameter distribution without a randomSeed: draw its sets as `run --seed` would (default 1)");
  command->add_flag("--yaml", *yaml, "OpenSCENARIO input: print the translation into the scenario language too");
  command->callback([file, import, step, step_option, yaml, &context] {
    context.action = [file, import, step, step_option, yaml] {
      if (step_option->count() > 0) import->step = *step;
      if (*yaml && import->network) {
        throw ConfigError("command line: --yaml: a network scenario (--network) has no translation into the "
                          "scenario language");
      }
      const interop::ScenarioFormat& format = interop::scenarioFormatOf(*file);
      if (!format.can.check) {
        throw ConfigError(fmt::format("{}: {} files are not checked on their own ({})", file->string(), format.name,
                                      format.description));
      }
      const interop::ScenarioCheck check = format.check(*file, *import);
      fmt::print("format: {} ({})\n{}", format.name, format.description, check.report());
      if (*yaml && !check.yaml.empty()) fmt::print("--- the scenario in the scenario language:\n{}", check.yaml);
      return check.runnable() ? 0 : 1;
    };
  });
}

}  // namespace

void addScenarioCommand(CLI::App& app, CommandContext& context) {
  CLI::App* scenario = app.add_subcommand("scenario", "Scenarios to and from other tools (OpenSCENARIO, OpenDRIVE)");
  scenario->require_subcommand(1);
  addExport(*scenario, context);
  addDistribution(*scenario, context);
  addCheck(*scenario, context);
}

}  // namespace vsd::cli
