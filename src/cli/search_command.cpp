#include <fmt/format.h>

#include <memory>
#include <string>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/search/search.hpp"
#include "vsd/search/surrogate.hpp"

namespace vsd::cli {

namespace {

// Both from the registry the search is handed (SearchOptions::surrogates).
std::vector<std::string> surrogateNames(const search::SurrogateRegistry& surrogates) {
  std::vector<std::string> names;
  for (const auto& entry : surrogates.entries()) names.push_back(entry.name);
  return names;
}

std::string surrogateHelp(const search::SurrogateRegistry& surrogates) {
  std::string text = "Surrogate that selects the executions:";
  for (const auto& entry : surrogates.entries()) text += fmt::format("\n  {}: {}", entry.name, entry.description);
  return text;
}

/// What is searched: the scenario, the criterion and the output folder.
void addSearchSubject(CLI::App* command, search::SearchOptions& options, bool& force) {
  command->add_option("scenario", options.scenarioFile, "Logical scenario (YAML), e.g. scenarios/acc_lk.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("-c,--criterion", options.criterion,
                      "Critical if true: a comparison of the scenario's metrics ('d_min < 2', 'ttc_min < 1 or "
                      "d_min < 0.5'), optionally named ('close: d_min < 2'), or a criterion name from the "
                      "scenario's `criteria:`; docs/cli.md \"Criteria\"")
      ->required();
  command->add_option("-o,--out", options.outputDir, "Output folder; re-running with it resumes the search")
      ->required();
  command->add_flag("--force", force,
                    "Start afresh in a search folder of another scenario or criterion, discarding its search "
                    "(docs/output-policy.md)");
}

/// How executions are chosen: the surrogate, the budget and the shape of the rounds.
void addSelectionOptions(CLI::App* command, search::SearchOptions& options) {
  command->add_option("--surrogate", options.surrogate, surrogateHelp(*options.surrogates))
      ->capture_default_str()
      ->check(CLI::IsMember(surrogateNames(*options.surrogates)));  // a name the registry lacks is a usage error
  addNumber(command, "--budget", options.budget,
            "SUMO simulations in total (an execution with --reference costs two)")
      ->capture_default_str();
  addNumber(command, "--initial", options.initial, "Executions of the initial random design")->capture_default_str();
  addNumber(command, "--round", options.roundSize, "Executions per later round")->capture_default_str();
  addNumber(command, "--estimate-share", options.estimateShare,
                      "Share of each later round drawn by importance sampling from the candidates (feeds the unbiased "
                      "rate estimate; the rest is chosen by the acquisition)")
      ->capture_default_str();
  addNumber(command, "--pool", options.pool, "Candidate concrete scenarios scored per round")->capture_default_str();
  addNumber(command, "--diversity", options.diversity,
                      "Weight of the distance to critical scenarios already found in the acquisition")
      ->capture_default_str();
  command->add_option("--reference", options.reference,
                      "Run every execution a second time with this built-in controller as the Ego (e.g. "
                      "r157_reference_driver); the criterion may then read reference_<metric> and "
                      "reference_avoids_sut_collides (UN R157's pass criterion fails)");
}

/// Options of one surrogate each (named by their help's prefix).
void addSurrogateOptions(CLI::App* command, search::SearchOptions& options) {
  addNumber(command, "--trees", options.trees, "extra-trees: trees per criterion metric")->capture_default_str();
  command->add_option("--probability", options.probability,
                      "extra-trees: probability from the trees' predictions shifted by -1/0/+1 spreads (shifts) or the "
                      "Gaussian tail of their mean and spread (tail; above 0 everywhere, for rare criteria)")
      ->capture_default_str();
  command->add_flag("--rank-targets", options.rankTargets,
                    "extra-trees: fit each metric's empirical rank and map back through its quantiles, extrapolated "
                    "beyond the observed range (for criteria below every value seen so far)");
  addNumber(command, "--bnn-epochs", options.bnnEpochs, "bnn: training epochs per round")->capture_default_str();
  command->add_option("--prior", options.priors,
                      "vectornet: datasets or run/export folders of other functional scenarios or maps, mixed into "
                      "its training from the first round (same step and horizon as the scenario)")
      ->check(CLI::ExistingPath);
  addNumber(command, "--vectornet-steps", options.vectornetSteps,
            "vectornet: optimizer steps of each round's training (from scratch, on every execution so far)")
      ->capture_default_str();
  addNumber(command, "--futures", options.futureSamples,
            "vectornet: sampled futures per candidate; probability = share meeting the criterion (was "
            "--future-samples)")
      ->capture_default_str();
}

/// Runs the search (after discarding an old one with --force, once the new one is known to be valid).
int runSearchCommand(search::SearchOptions& options, bool force, const CommandContext& context) {
  options.commandLine = context.commandLine;
  const auto logical = scenario::loadLogicalScenario(options.scenarioFile);
  const std::string subject = fmt::format("{}: {}", logical->name, options.criterion);
  const auto status = checkOutput({options.outputDir, &output_kinds::searchFolder(), subject, force, "--out", "--force",
                                   {{"scenario", options.scenarioFile}}});
  if (force && status != OutputStatus::New) {
    // The options and the criterion are checked before the old search is removed.
    options.validate();
    const metrics::MetricSet metric_set(logical->metrics, pipeline::scenarioAvailability(*logical),
                                        logical->sourceFile.string() + ": metrics");
    search::Criterion(options.criterion, *logical, search::executionColumns(metric_set.names(), options.reference));
    search::discardSearchState(options.outputDir);
  }
  fmt::print("{}", search::runSearch(options).report());
  return 0;
}

}  // namespace

void addSearchCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<search::SearchOptions>();
  auto force = std::make_shared<bool>(false);
  CLI::App* command = app.add_subcommand(
      "search", "Find the concrete scenarios that meet a criterion with few executions: a surrogate picks which to "
                "simulate; estimates how often the criterion occurs");
  addSearchSubject(command, *options, *force);
  addSelectionOptions(command, *options);
  addSurrogateOptions(command, *options);
  addNumber(command, "-s,--seed", options->seed, "Random seed; same seed, same choices")->capture_default_str();
  addNumber(command, "-j,--jobs", options->jobs, "Worker processes for the simulations")->capture_default_str();
  addNumber(command, "--threads", options->threads, "libtorch threads (bnn, vectornet)")->capture_default_str();
  addEgoStepCostOption(*command, options->egoStepCost);
  command->callback([options, force, &context] {
    context.action = [options, force, &context] { return runSearchCommand(*options, *force, context); };
  });
}

}  // namespace vsd::cli
