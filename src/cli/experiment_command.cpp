// experiment: the paper's experiments from one YAML file.
#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "vsd/experiment/experiment.hpp"

namespace vsd::cli {

void addExperimentCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<experiment::ExperimentOptions>();
  CLI::App* command = app.add_subcommand(
      "experiment", "Reproduce the paper's experiments (ADE of training mixes, metric MAE of ET/BNN/VectorNet, "
                    "figures) from one YAML file; data and models are cached, a re-run only does what changed");
  command->add_option("spec", options->spec, "Experiment YAML, e.g. scenarios/experiments/paper.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("-o,--out", options->output, "Output folder (default: results/<name>, results/<name>-quick)");
  command->add_flag("--quick", options->quick, "The spec's small sizes: the same pipeline in minutes");
  command->add_flag("--force", options->force,
                    "Replace the results folder of another experiment (docs/output-policy.md); a re-run of the same "
                    "experiment resumes from its cache without it");
  addAllowDirtyFlag(*command, options->allowDirty);
  command->callback([=, &context] {
    context.action = [=, &context] {
      options->commandLine = context.commandLine;
      const auto summary = experiment::runExperiment(*options);
      fmt::print("{}", summary.report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
