// `vsd-sumo scenario export | distribution`: concrete scenarios as OpenDRIVE +
// OpenSCENARIO, and a logical scenario as an OpenSCENARIO parameter distribution.

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/interop/distribution.hpp"
#include "vsd/interop/export.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::cli {

namespace {

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
  command->add_option("-o,--out", options->outputDir, "Output folder (refused if it exists, unless --force)")->required();
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
  command->add_flag("--force", options->force, "Replace an existing output folder");
  command->callback([options, &context] {
    context.action = [options, &context] {
      options->commandLine = context.commandLine;
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
      const auto logical = scenario::loadLogicalScenario(*scenario_file);
      fmt::print("{}", interop::writeParameterDistribution(*logical, *options).report());
      return 0;
    };
  });
}

}  // namespace

void addScenarioCommand(CLI::App& app, CommandContext& context) {
  CLI::App* scenario = app.add_subcommand("scenario", "Scenarios to and from other tools (OpenSCENARIO, OpenDRIVE)");
  scenario->require_subcommand(1);
  addExport(*scenario, context);
  addDistribution(*scenario, context);
}

}  // namespace vsd::cli
