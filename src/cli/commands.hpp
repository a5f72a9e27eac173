#pragma once
// Subcommands of the vsd-sumo executable. Each registers its flags and sets the
// action to run after parsing; the action only calls library functions.

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace vsd::cli {

using Action = std::function<int()>;

struct CommandContext {
  std::string commandLine;  ///< the whole invocation, for manifests
  Action action;            ///< set by the chosen subcommand
};

void addRunCommand(CLI::App& app, CommandContext& context);
void addExportCommand(CLI::App& app, CommandContext& context);
void addDatasetCommand(CLI::App& app, CommandContext& context);
void addTrainCommand(CLI::App& app, CommandContext& context);
void addPredictCommand(CLI::App& app, CommandContext& context);
void addEvaluateCommand(CLI::App& app, CommandContext& context);
void addBaselineCommand(CLI::App& app, CommandContext& context);
void addExperimentCommand(CLI::App& app, CommandContext& context);
void addCompareCommand(CLI::App& app, CommandContext& context);
void addBenchCommand(CLI::App& app, CommandContext& context);
void addScenarioCommand(CLI::App& app, CommandContext& context);
/// `bench interop` (bench_interop.cpp), a subcommand of `bench`.
void addInteropBench(CLI::App& bench, CommandContext& context);

}  // namespace vsd::cli
