#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/interop/scenario_formats.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::cli {

void addAllowDirtyFlag(CLI::App& command, bool& allow) {
  command.add_flag("--allow-dirty", allow,
                   "Write into the repository's results/ even though this binary was built from uncommitted changes");
}

void addEgoStepCostOption(CLI::App& command, double& seconds) {
  command
      .add_option_function<double>(
          "--ego-step-cost-ms", [&seconds](double ms) { seconds = ms / 1000.0; },
          "Extra wall time per Ego controller step (ms), e.g. to stand in for a slow Ego stack in a benchmark; "
          "counts against --step-timeout")
      ->default_str("0");
}

void addImportOptions(CLI::App& command, interop::OscImportOptions& import) {
  command.add_option_function<double>(
      "--duration",
      [&import](double seconds) {
        // Thrown while the command line is parsed: a usage error (exit 2), as CLI11's own checks are.
        if (!(seconds > 0.0 && std::isfinite(seconds))) {
          throw CLI::ValidationError("--duration", fmt::format("got '{}', expected finite seconds > 0", seconds));
        }
        import.duration = seconds;
      },
      "OpenSCENARIO input: seconds to simulate (needed when the StopTrigger is not a simulation time)");
  command
      .add_option_function<std::string>(
          "--ego", [&import](const std::string& name) { import.ego = name; },
          "OpenSCENARIO input without controllers: the entity that is the Ego")
      ->default_str(interop::kDefaultEgo);
  command
      .add_option_function<std::string>(
          "--controller", [&import](const std::string& name) { import.controller = name; },
          "OpenSCENARIO input without controllers: the Ego's vsd-sumo controller")
      ->default_str(interop::kDefaultEgoController);
  command.add_option("--controller-map", import.controllerMap,
                     "OpenSCENARIO input: YAML map from the file's controller names to vsd-sumo controllers")
      ->check(CLI::ExistingFile);
  command.add_flag("--network", import.network,
                   "OpenSCENARIO input: simulate the Init on SUMO's network of the file's OpenDRIVE roads (or its SUMO "
                   "controller's configuration) instead of the scenario language's one road; writes the scenes around "
                   "the Ego as `export` does (docs/openscenario-import.md)");
  command.add_option("--data-root", import.dataRoot,
                     "OpenSCENARIO input: the folder the files a scenario names (road, catalogs, template) may lie in, "
                     "e.g. esmini's resources/ (default: the scenario file's own folder)")
      ->check(CLI::ExistingDirectory);
}

namespace {

std::vector<std::string> givenFlags(const CLI::App& command) {
  std::vector<std::string> given;
  for (const CLI::Option* option : command.get_options()) {
    if (option->count() > 0 && !option->get_lnames().empty()) given.push_back("--" + option->get_lnames().front());
  }
  return given;
}

/// A flag the file's format cannot use is refused by name (never ignored).
void checkFlagsFor(const interop::ScenarioFormat& format, const interop::ScenarioRunRequest& request) {
  const std::string file = request.options.scenarioFile.string();
  if (!format.can.run) {
    throw ConfigError(fmt::format("{}: {} files are not run ({})", file, format.name, format.description));
  }
  const auto refuse = [&](const std::string& flag) {
    throw ConfigError::field("command line", flag, file, fmt::format("a flag for other formats than {}", format.name));
  };
  if (request.given("--step") && !format.can.step) refuse("--step");
  for (const char* flag : {"--duration", "--ego", "--controller", "--controller-map", "--data-root", "--network"}) {
    if (request.given(flag) && !format.can.importOptions) refuse(flag);
  }
  for (const char* flag : {"--shard", "--merge"}) {
    if (request.given(flag) && !format.can.distributed) refuse(flag);
  }
}

}  // namespace

void addRunCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<pipeline::RunOptions>();
  CLI::App* run = app.add_subcommand(
      "run", "Sample concrete scenarios from a logical scenario, simulate them with SUMO and write concrete.csv, "
             "traces.h5 and manifest.json");
  run->add_option("scenario", options->scenarioFile,
                  "Scenario file: a logical scenario (YAML, e.g. scenarios/acc_lk.yaml), an OpenSCENARIO scenario or "
                  "parameter distribution (.xosc); `vsd-sumo scenario check FILE` says what it holds")
      ->required()
      ->check(CLI::ExistingFile);
  addNumber(run, "-n,--samples", options->samples, "Number of concrete scenarios")->capture_default_str();
  addNumber(run, "-s,--seed", options->seed, "Random seed; same seed, same outputs")->capture_default_str();
  run->add_option("-o,--out", options->outputDir, "Output folder (default: out/<functional scenario>)");
  addNumber(run, "-j,--jobs", options->jobs, "Worker processes (one libsumo simulation each)")->capture_default_str();
  addNumber(run, "--net-batch", options->batch,
            "Concrete scenarios (samples) per SUMO network and simulation (was --batch)")
      ->capture_default_str();
  addNumber(run, "--first-sample", options->firstSample, "Index of the first concrete scenario")
      ->capture_default_str();
  addNumber(run, "--compression", options->compression, "Deflate level of dataset.h5's vectors: 0 (none) .. 9")
      ->capture_default_str();
  addNumber(run, "--step-timeout", options->watchdog.stepTimeout,
                  "Watchdog: longest Ego controller call or libsumo step (s); a scenario exceeding it fails")
      ->capture_default_str();
  addNumber(run, "--max-failures", options->maxFailures,
            "Fail fast: stop when each of the first N scenarios fails for the same reason (0: never stop early)")
      ->capture_default_str();
  addEgoStepCostOption(*run, options->egoStepCost);
  run->add_flag("--force", options->force,
                "Replace a run folder of another functional scenario (docs/output-policy.md)");
  run->add_option("--reference", options->reference,
                  "Run every concrete scenario a second time with this built-in controller as the Ego (e.g. "
                  "r157_reference_driver) and write both outcomes side by side in concrete.csv");
  run->add_flag("--keep-nets", options->keepNets, "Keep the generated networks in <out>/nets (open with sumo-gui)");
  run->add_flag("--fcd", options->fcd,
                "Write SUMO FCD XML per batch to <out>/fcd (replay: tools/replay_fcd.py); implies --keep-nets");
  auto shard = std::make_shared<std::string>();
  run->add_option("--shard", *shard,
                  "Run only shard K/N of the sweep (K = 0 .. N-1) into <out>/shards/shard-K-of-N; finished shards "
                  "are skipped, so re-running resumes. Join with `vsd-sumo merge <out>`");
  auto merge = std::make_shared<bool>(false);
  run->add_flag("--merge", *merge, "Under mpirun: rank 0 joins the shards into one run folder at the end");
  auto net_writer = std::make_shared<std::string>();
  run->add_option("--net-writer", *net_writer,
                  "How networks are built: direct (written by vsd-sumo) or netconvert; default: direct unless the "
                  "scenario gives sumo.netconvert_options")
      ->check(CLI::IsMember({"direct", "netconvert"}));
  auto import = std::make_shared<interop::OscImportOptions>();
  auto step = std::make_shared<double>(0.0);
  CLI::Option* step_option =
      addNumber(run, "--step", *step, "OpenSCENARIO input: simulation step (s) if the file does not set one");
  addImportOptions(*run, *import);
  run->callback([options, &context, run, import, step, step_option, net_writer, shard, merge] {
    context.action = [options, &context, run, import, step, step_option, net_writer, shard, merge] {
      options->commandLine = context.commandLine;
      if (!net_writer->empty()) options->netWriter = road::parseNetWriter(*net_writer, "command line: --net-writer");
      if (!shard->empty()) options->shard = ShardId::parse(*shard, "command line");
      if (step_option->count() > 0) import->step = *step;
      const interop::ScenarioFormat& format = interop::scenarioFormatOf(options->scenarioFile);
      interop::ScenarioRunRequest request{*options, *import, givenFlags(*run)};
      checkFlagsFor(format, request);
      if (format.can.distributed && pipeline::launchedAsMpiRank()) {
        const auto communicator = pipeline::joinMpiJob();
        const auto result = pipeline::runOnCluster(*options, *merge, *communicator);
        fmt::print("{}", result.report);
        return result.exitCode;
      }
      if (*merge) throw ConfigError("--merge is for mpirun; join shards with `vsd-sumo merge <out>`");
      fmt::print("{}", format.run(request));
      return 0;
    };
  });
}

}  // namespace vsd::cli
