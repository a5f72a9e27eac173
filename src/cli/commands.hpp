#pragma once
// Subcommands of the vsd-sumo executable. Each registers its flags and sets the
// action to run after parsing; the action only calls library functions.

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

#include "vsd/interop/openscenario_import.hpp"

namespace vsd::bench {
struct Tool;  // vsd/bench/measure.hpp
}  // namespace vsd::bench

namespace vsd::cli {

using Action = std::function<int()>;

struct CommandContext {
  std::string commandLine;  ///< the whole invocation, for manifests
  Action action;            ///< set by the chosen subcommand
};

/// The commands that train or run models (libtorch): train, predict, evaluate,
/// baseline, experiment, compare, bench, search. Loading libtorch costs a process about a
/// second of CPU before main() (relocations and operator registrations), so these
/// live in a second executable, vsd-sumo-ml, built and installed next to vsd-sumo.
/// vsd-sumo hands every command line that is not one of its own commands (and
/// top-level --help) to vsd-sumo-ml unchanged (exec, same process), so users see
/// one tool and a scenario sweep never pays for libtorch.
/// Registers them and returns true in vsd-sumo-ml (model_command_set.cpp); returns
/// false in vsd-sumo (sweep_command_set.cpp).
bool addModelCommands(CLI::App& app, CommandContext& context);

/// Path of the sibling executable `name` (in the folder of the running executable).
std::string siblingExecutable(const std::string& name);

void addRunCommand(CLI::App& app, CommandContext& context);
void addExportCommand(CLI::App& app, CommandContext& context);
void addDatasetCommand(CLI::App& app, CommandContext& context);
void addTrainCommand(CLI::App& app, CommandContext& context);
void addPredictCommand(CLI::App& app, CommandContext& context);
void addEvaluateCommand(CLI::App& app, CommandContext& context);
void addBaselineCommand(CLI::App& app, CommandContext& context);
void addExperimentCommand(CLI::App& app, CommandContext& context);
void addCompareCommand(CLI::App& app, CommandContext& context);
/// `vsd-sumo deviations` (deviations_command.cpp).
void addDeviationsCommand(CLI::App& app, CommandContext& context);
void addBenchCommand(CLI::App& app, CommandContext& context);
void addMergeCommand(CLI::App& app, CommandContext& context);
void addScenarioCommand(CLI::App& app, CommandContext& context);
/// --ego-step-cost-ms: extra wall time per Ego step (stored in seconds in `seconds`).
void addEgoStepCostOption(CLI::App& command, double& seconds);
/// --allow-dirty: write into the repository's results/ from a build of uncommitted changes
/// (core/provenance.hpp refuses it otherwise).
void addAllowDirtyFlag(CLI::App& command, bool& allow);
/// --duration, --ego, --controller, --controller-map (OpenSCENARIO input), for `run` and `scenario check`.
void addImportOptions(CLI::App& command, interop::OscImportOptions& import);

void addSearchCommand(CLI::App& app, CommandContext& context);
/// The `vsd-sumo` next to this executable, which benchmarks start as separate processes.
bench::Tool benchTool();
/// `bench interop` (bench_scenarios.cpp), a subcommand of `bench`.
void addInteropBench(CLI::App& bench, CommandContext& context);
void addImportBench(CLI::App& bench, CommandContext& context);
/// `bench search` (bench_search.cpp), a subcommand of `bench`.
void addSearchBench(CLI::App& bench, CommandContext& context);
/// `vsd-sumo bench library` (bench_scenarios.cpp).
void addLibraryBench(CLI::App& bench, CommandContext& context);
/// `vsd-sumo bench train` (bench_train.cpp).
void addTrainBench(CLI::App& bench, CommandContext& context);
/// `vsd-sumo bench reference` (bench_scenarios.cpp).
void addReferenceBench(CLI::App& bench, CommandContext& context);
/// `vsd-sumo bench deviations` (bench_deviations.cpp).
void addDeviationsBench(CLI::App& bench, CommandContext& context);

}  // namespace vsd::cli
