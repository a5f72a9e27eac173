// `vsd-sumo bench search`: flags and printing of the surrogate comparison
// (vsd/bench/search_bench.hpp).

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/bench/search_bench.hpp"
#include "vsd/report/numbers.hpp"

namespace vsd::cli {

namespace {

void printSearch(const std::string& surrogate, std::uint64_t seed, const search::SearchSummary& summary) {
  const auto& e = summary.estimate;
  fmt::print("    {:<12} seed {:>3}: {:>5} critical / {} executions, {:>4} cells, P = {} ({}), {:.1f} s (surrogate "
             "{:.1f} s)\n",
             surrogate, seed, summary.critical, summary.executions, summary.coverageCells,
             report::percentWithInterval(e.estimate, e.low, e.high), e.method, summary.seconds,
             summary.surrogateSeconds);
}

void printTrueRate(const bench::SearchBenchResult& result) {
  if (!result.trueRate) return;
  const auto& r = *result.trueRate;
  fmt::print("  true rate (plain Monte Carlo, {} scenarios, seed {}): {} critical, P = {} ({:.1f} s)\n", r.samples,
             r.seed, r.critical, report::percentWithInterval(r.estimate, r.low, r.high), r.seconds);
}

void printCoverage(const bench::SearchBenchOptions& options, const bench::SearchBenchResult& result) {
  if (!result.trueRate) return;
  fmt::print("  intervals holding the true rate:");
  for (const auto& [name, totals] : result.surrogates) {
    fmt::print(" {} {}/{}", name, bench::seedsCoveringTrueRate(result, name).value_or(0), options.seeds);
  }
  fmt::print("\n");
}

void printTotals(const bench::SearchBenchResult& result) {
  const double random_critical = result.randomCritical();
  fmt::print("  mean over seeds:\n  {:<12} {:>9} {:>8} {:>7} {:>11} {:>11} {:>16} {:>9} {:>14} {:>12} {:>12}\n",
             "surrogate", "critical", "x random", "cells", "P est. %", "CI width %", "random CI width %", "seconds",
             "surrogate s/rnd", "sim ms/exec", "surr ms/exec");
  for (const auto& [name, t] : result.surrogates) {
    fmt::print("  {:<12} {:>9.1f} {:>8} {:>7.1f} {:>11.4f} {:>11.4f} {:>16.4f} {:>9.1f} {:>14.2f} {:>12.1f} "
               "{:>12.1f}\n",
               name, t.critical, random_critical > 0 ? fmt::format("{:.1f}", t.critical / random_critical) : "-",
               t.coverage, 100 * t.estimate, 100 * t.width, 100 * t.randomWidth, t.seconds,
               t.surrogateSecondsPerRound, t.simulationMsPerExecution, t.surrogateMsPerExecution);
  }
}

int printSearchBench(const bench::SearchBenchOptions& options, const std::string& command_line) {
  options.validate();
  const auto& s = options.search;
  fmt::print("{}: '{}', budget {} (initial {}, rounds of {}, pool {}), {} seed(s), Ego step cost {} ms; load "
             "average {}\n",
             s.scenarioFile.string(), s.criterion, s.budget, s.initial, s.roundSize, s.pool, options.seeds,
             1000.0 * s.egoStepCost, bench::loadAverage());
  const auto result = bench::runSearchBench(options, printSearch);
  printTrueRate(result);
  printTotals(result);
  printCoverage(options, result);
  if (!options.out.empty()) {
    bench::writeSearchBenchResults(options, result, command_line);
    fmt::print("  results: {}\n", options.out.string());
  }
  if (!options.report.empty()) {
    bench::writeSearchBenchReport(options, result, command_line);
    fmt::print("  report: {}\n", options.report.string());
  }
  fmt::print("  load average after: {}\n", bench::loadAverage());
  return 0;
}

void addSearchFlags(CLI::App& command, search::SearchOptions& search) {
  addNumber(&command, "--budget", search.budget,
            "SUMO simulations per search (an execution with --reference costs two)")
      ->capture_default_str();
  addNumber(&command, "--initial", search.initial, "Initial design")->capture_default_str();
  addNumber(&command, "--round", search.roundSize, "Executions per round")->capture_default_str();
  addNumber(&command, "--pool", search.pool, "Candidates per round")->capture_default_str();
  addNumber(&command, "--estimate-share", search.estimateShare,
            "Share of each round drawn by importance sampling for the rate estimate")
      ->capture_default_str();
  command.add_option("--reference", search.reference,
                     "Run every execution, the true-rate run's too, a second time with this built-in controller as "
                     "the Ego (see search --reference)");
  command.add_option("--probability", search.probability, "extra-trees: shifts or tail")->capture_default_str();
  command.add_flag("--rank-targets", search.rankTargets, "extra-trees: fit metric ranks");
  addNumber(&command, "--diversity", search.diversity, "Weight of the distance term in the acquisition")
      ->capture_default_str();
  command.add_option("--prior", search.priors, "vectornet: prior datasets (see search --prior)")
      ->check(CLI::ExistingPath);
  addNumber(&command, "--vectornet-steps", search.vectornetSteps, "vectornet: training steps per round")
      ->capture_default_str();
  addNumber(&command, "--futures", search.futureSamples, "vectornet: sampled futures per candidate")
      ->capture_default_str();
}

}  // namespace

void addSearchBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::SearchBenchOptions>();
  CLI::App* command = bench.add_subcommand("search", "Surrogates of `vsd-sumo search` side by side (same budget, seeds), their rate estimates against the true rate");
  command->add_option("scenario", options->search.scenarioFile, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  command->add_option("--criterion", options->search.criterion, "Criterion")->capture_default_str();
  command->add_option("--surrogates", options->surrogates, "Surrogates to compare")->delimiter(',')->capture_default_str();
  addSearchFlags(*command, options->search);
  addNumber(command, "--seeds", options->seeds, "Searches per surrogate")->capture_default_str();
  addNumber(command, "--first-seed", options->firstSeed, "Seed of the first search (then +1 each)")
      ->capture_default_str();
  addNumber(command, "--true-rate-samples", options->trueRateSamples,
            "Estimate the true rate by plain Monte Carlo over this many scenarios (0: none) and count the searches "
            "whose interval holds it")
      ->capture_default_str();
  addNumber(command, "--true-rate-seed", options->trueRateSeed, "Seed of that Monte Carlo run (no search's seed)")
      ->capture_default_str();
  command->add_option("--out", options->out,
                      "Write searches.csv, surrogates.csv, README.md and manifest.json into this folder");
  addAllowDirtyFlag(*command, options->allowDirty);
  command->add_option("--report", options->report,
                      "Write an HTML report (learning curves of every search, rate estimates) to this file");
  addNumber(command, "-j,--jobs", options->search.jobs, "Worker processes for the simulations")->capture_default_str();
  addNumber(command, "--threads", options->search.threads, "libtorch threads (bnn, vectornet)")->capture_default_str();
  addEgoStepCostOption(*command, options->search.egoStepCost);
  command->callback([options, &context] {
    context.action = [options, &context] { return printSearchBench(*options, context.commandLine); };
  });
}

}  // namespace vsd::cli
