// compare: predicted vs simulated (or recorded) Ego behaviour, as an HTML report.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/compare/compare.hpp"

namespace vsd::cli {

void addCompareCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<compare::CompareOptions>();
  CLI::App* command = app.add_subcommand(
      "compare", "Predict the Ego in fresh scenarios of a logical scenario (or in dataset samples), simulate them, and "
                 "write an HTML report and comparison.csv of predicted vs simulated (or recorded) behaviour");
  command->add_option("scenario", options->scenarioFile, "Logical scenario (YAML), e.g. scenarios/acc_lk.yaml")
      ->check(CLI::ExistingFile);
  command->add_option("-m,--model", options->model, "VectorNet model file (vsd-sumo train), or cv / ca (no training)")
      ->required();
  command->add_option("-d,--data", options->data, "Instead of a scenario: dataset files or run folders (predicted "
                                                  "vs recorded)");
  command->add_option("-o,--out", options->output, "Report folder (default: reports/<scenario or dataset name>)");
  command->add_flag("--force", options->force,
                    "Replace a report folder of another scenario, dataset or model (docs/output-policy.md)");
  addNumber(command, "-n,--samples", options->samples,
                      "Scenarios to sample and simulate (default 500); datasets: the first N samples (default: all)");
  addNumber(command, "-s,--seed", options->seed, "Sampling seed")->capture_default_str();
  addNumber(command, "-j,--jobs", options->jobs, "SUMO worker processes")->capture_default_str();
  addNumber(command, "--threads", options->threads, "libtorch threads")->capture_default_str();
  addNumber(command, "--worst", options->worst, "Scenarios with the largest ADE drawn in the report")
      ->capture_default_str();
  addNumber(command, "--futures", options->draws,
            "Futures drawn per scenario from a probabilistic model: metric intervals, calibration, confident "
            "verdicts (0: none; was --draws)")
      ->capture_default_str();
  addNumber(command, "--future-seed", options->drawSeed, "Seed of the drawn futures (was --draw-seed)")
      ->capture_default_str();
  addNumber(command, "--confidence", options->confidence,
                      "A criterion's verdict is confident when this share of the drawn futures agrees")
      ->capture_default_str();
  addAllowDirtyFlag(*command, options->allowDirty);
  command->add_option("--metrics", options->metrics, "Datasets: metrics to compare, e.g. a_min,d_min")->delimiter(',');
  command->add_option("--criterion", options->criteria,
                      "Pass/fail criterion (repeatable), added to a scenario's own: a comparison of metrics such as "
                      "'d_min < 2' or 'ttc_min < 1 or d_min < 0.5', optionally named ('close: d_min < 2'); "
                      "docs/cli.md \"Criteria\"");
  command->callback([=, &context] {
    context.action = [=, &context] {
      options->commandLine = context.commandLine;
      fmt::print("{}", compare::runComparison(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
