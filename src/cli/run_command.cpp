#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::cli {

void addRunCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<pipeline::RunOptions>();
  CLI::App* run = app.add_subcommand(
      "run", "Sample concrete scenarios from a logical scenario, simulate them with SUMO and write concrete.csv, "
             "traces.h5 and manifest.json");
  run->add_option("scenario", options->scenarioFile, "Logical scenario (YAML), e.g. scenarios/acc_lk.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  addNumber(run, "-n,--samples", options->samples, "Number of concrete scenarios")->capture_default_str();
  addNumber(run, "-s,--seed", options->seed, "Random seed; same seed, same outputs")->capture_default_str();
  run->add_option("-o,--out", options->outputDir, "Output folder (default: out/<functional scenario>)");
  addNumber(run, "-j,--jobs", options->jobs, "Worker processes (one libsumo simulation each)")->capture_default_str();
  addNumber(run, "-b,--batch", options->batch, "Concrete scenarios per SUMO network and simulation")
      ->capture_default_str();
  addNumber(run, "--first-sample", options->firstSample, "Index of the first concrete scenario")
      ->capture_default_str();
  addNumber(run, "--compression", options->compression, "Deflate level of dataset.h5's vectors: 0 (none) .. 9")
      ->capture_default_str();
  run->add_flag("--keep-nets", options->keepNets, "Keep the generated networks in <out>/nets (open with sumo-gui)");
  run->add_flag("--fcd", options->fcd,
                "Write SUMO FCD XML per batch to <out>/fcd (replay: tools/replay_fcd.py); implies --keep-nets");
  run->callback([options, &context] {
    context.action = [options, &context] {
      options->commandLine = context.commandLine;
      const auto summary = pipeline::runScenarios(*options);
      fmt::print("{}", summary.report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
