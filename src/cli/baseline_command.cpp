#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/baseline/baseline.hpp"
#include "vsd/core/output_policy.hpp"

namespace vsd::cli {

void addBaselineCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<baseline::BaselineOptions>();
  CLI::App* command = app.add_subcommand(
      "baseline", "Regression metamodel (extra trees or BNN) from concrete inputs to metrics, evaluated on a test run");
  command->add_option("-d,--data", options->train, "Training run folder (its concrete.csv: concrete inputs and metrics)")
      ->required();
  command->add_option("-t,--test", options->test, "Test run folder of the same functional scenario")->required();
  command
      ->add_option("-m,--model", options->model,
                   "extra-trees or bnn (Bayesian neural network): the names of search's surrogates")
      ->capture_default_str()
      ->transform(CLI::Validator(
          [](std::string& name) {
            for (const auto& model : baseline::baselineModels()) {
              const auto& old = model.oldNames;
              if (std::find(old.begin(), old.end(), name) == old.end()) continue;
              std::fprintf(stderr, "vsd-sumo: note: baseline --model %s is deprecated; use %s (the old spelling still "
                                   "works for now)\n", name.c_str(), model.name.c_str());
              name = model.name;
            }
            return std::string();
          },
          "", "model"));
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
      if (!options->predictionsCsv.empty()) {
        static const OutputKind kTable = textFileKind("baseline predictions table", "sample,");
        checkOutput({options->predictionsCsv, &kTable, "", false, "--out", "--force",
                     {{"--data", options->train}, {"--test", options->test},
                      {"--data", baseline::concreteTableOf(options->train)},
                      {"--test", baseline::concreteTableOf(options->test)}}});
      }
      fmt::print("{}", baseline::runBaseline(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
