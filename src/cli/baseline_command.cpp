#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/baseline/baseline.hpp"

namespace vsd::cli {

void addBaselineCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<baseline::BaselineOptions>();
  CLI::App* command = app.add_subcommand(
      "baseline", "Regression metamodel (extra trees or BNN) from concrete inputs to metrics, evaluated on a test run");
  command->add_option("-d,--data", options->train, "Training run: concrete.csv or its folder")->required();
  command->add_option("-t,--test", options->test, "Test run of the same functional scenario")->required();
  command->add_option("-m,--model", options->model, "et (extra trees) or bnn (Bayesian neural network)")
      ->capture_default_str();
  command->add_option("--targets", options->targets, "Metrics to predict, e.g. a_min,d_min,p_lat_max")
      ->required()
      ->delimiter(',');
  command->add_option("--inputs", options->inputs, "Input columns (default: every input of the scenario)")
      ->delimiter(',');
  addNumber(command, "--train-rows", options->maxTrainRows, "Use the first N completed rows (0: all)")
      ->capture_default_str();
  command->add_option("-o,--out", options->predictionsCsv, "Write per-row truth and prediction (and std) as CSV");
  addNumber(command, "--trees", options->extraTrees.trees, "Extra trees: number of trees")->capture_default_str();
  addNumber(command, "--max-features", options->extraTrees.maxFeatures, "Extra trees: share of features per split")
      ->capture_default_str();
  addNumber(command, "--min-samples-split", options->extraTrees.minSamplesSplit, "Extra trees: smallest node to split")
      ->capture_default_str();
  addNumber(command, "--bnn-hidden", options->bnn.hidden, "BNN: width")->capture_default_str();
  addNumber(command, "--bnn-epochs", options->bnn.epochs, "BNN: epochs")->capture_default_str();
  addNumber(command, "--bnn-samples", options->bnn.samples, "BNN: weight draws per prediction")->capture_default_str();
  addNumber(command, "-s,--seed", options->extraTrees.seed, "Seed")->capture_default_str();
  command->callback([=, &context] {
    context.action = [=] {
      options->bnn.seed = options->extraTrees.seed;
      fmt::print("{}", baseline::runBaseline(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
