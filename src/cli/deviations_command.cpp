// deviations: recorded Ego behaviour the model trained on test data did not expect.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/compare/deviations.hpp"

namespace vsd::cli {

void addDeviationsCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<compare::DeviationOptions>();
  CLI::App* command = app.add_subcommand(
      "deviations", "Score how surprising recorded Ego behaviour (field data) is under a calibrated model trained on "
                    "test data; flag, rank and group the scenes beyond --level (SOTIF area 3; docs/deviations.md)");
  command->add_option("-m,--model", options->model,
                      "Probabilistic model trained with --decoder-option calibrate=1 (vsd-sumo train)")
      ->required();
  command->add_option("-d,--data", options->data, "Field data: dataset files or run folders")->required();
  command->add_option("--calibration", options->calibration,
                      "Clean recorded runs of the field's scenarios that the model never trained on (e.g. test runs "
                      "of other seeds): p-values by conformal rank among them instead of the model's own calibration "
                      "(narrower, docs/deviations.md)");
  command->add_option("-o,--out", options->output, "Report folder (deviations.csv, report.html)")->required();
  addNumber(command, "--level", options->level, "Flag scenes whose tail probability is below this, in (0, 1)")
      ->capture_default_str();
  command->add_option("--metrics", options->metrics,
                      "Metrics to score, e.g. a_min,d_min,lane_offset_max (default: those the data stores, else all "
                      "that apply)")
      ->delimiter(',');
  command->add_flag("--force", options->force,
                    "Replace a deviations report of other data or another model (docs/output-policy.md)");
  addNumber(command, "--threads", options->threads, "libtorch threads")->capture_default_str();
  addNumber(command, "--future-seed", options->seed, "Seed of the sampled futures")->capture_default_str();
  addNumber(command, "--drawn", options->drawn, "Flagged scenes drawn in the report, most surprising first")
      ->capture_default_str();
  addAllowDirtyFlag(*command, options->allowDirty);
  command->callback([=, &context] {
    context.action = [=, &context] {
      options->commandLine = context.commandLine;
      fmt::print("{}", compare::findDeviations(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
