#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/interop/run_openscenario.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::cli {

void addRunCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<pipeline::RunOptions>();
  CLI::App* run = app.add_subcommand(
      "run", "Sample concrete scenarios from a logical scenario, simulate them with SUMO and write concrete.csv, "
             "traces.h5 and manifest.json");
  run->add_option("scenario", options->scenarioFile,
                  "Logical scenario (YAML), e.g. scenarios/acc_lk.yaml, or a concrete scenario (OpenSCENARIO .xosc)")
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
  auto import = std::make_shared<interop::ImportOptions>();
  auto step = std::make_shared<double>(0.0);
  CLI::Option* step_option =
      run->add_option("--step", *step, "OpenSCENARIO input: simulation step (s) if the file does not set one");
  run->callback([options, &context, run, import, step, step_option] {
    context.action = [options, &context, run, import, step, step_option] {
      options->commandLine = context.commandLine;
      if (options->scenarioFile.extension() == ".xosc") {
        if (step_option->count() > 0) import->step = *step;
        std::vector<std::string> fixed_by_file;
        for (const char* flag : {"--samples", "--seed", "--first-sample"}) {
          if (run->count(flag) > 0) fixed_by_file.push_back(flag);
        }
        fmt::print("{}", interop::runOpenScenario(*options, *import, fixed_by_file).report());
        return 0;
      }
      if (step_option->count() > 0) {
        throw ConfigError::field("command line", "--step", options->scenarioFile.string(),
                                 "an OpenSCENARIO file (a logical scenario sets its step in time.step)");
      }
      const auto summary = pipeline::runScenarios(*options);
      fmt::print("{}", summary.report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
