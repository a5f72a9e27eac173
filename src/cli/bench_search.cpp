// `vsd-sumo bench search`: the surrogates of `vsd-sumo search` side by side with the
// same budget, criterion and seeds: critical scenarios found, failure-region coverage,
// rate estimate and interval width, and the surrogate's overhead per round.

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/report/numbers.hpp"
#include "vsd/search/search.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

struct SearchBenchOptions {
  search::SearchOptions search;
  std::vector<std::string> surrogates = {"random", "extra-trees"};
  std::uint64_t seeds = 1;
  fs::path report;  ///< HTML report of every search (empty: none)
};

struct SurrogateTotals {
  double critical = 0.0;
  double coverage = 0.0;
  double estimate = 0.0;
  double width = 0.0;
  double randomWidth = 0.0;
  double seconds = 0.0;
  double surrogateSecondsPerRound = 0.0;
  double simulationMsPerExecution = 0.0;
  double surrogateMsPerExecution = 0.0;
};

std::string loadAverage() {
  std::istringstream text(readTextFile("/proc/loadavg"));
  std::string one, five, fifteen;
  text >> one >> five >> fifteen;
  return fmt::format("{} {} {}", one, five, fifteen);
}

SurrogateTotals benchSurrogate(const SearchBenchOptions& options, const std::string& surrogate, const fs::path& work,
                               std::vector<search::SearchSummary>& summaries) {
  SurrogateTotals totals;
  for (std::uint64_t seed = 1; seed <= options.seeds; ++seed) {
    search::SearchOptions run = options.search;
    run.surrogate = surrogate;
    run.seed = seed;
    run.outputDir = work / fmt::format("{}_{}", surrogate, seed);
    const auto summary = search::runSearch(run);
    const auto& e = summary.estimate;
    fmt::print("    {:<12} seed {:>3}: {:>5} critical / {} executions, {:>4} cells, P = {} ({}), {:.1f} s (surrogate "
               "{:.1f} s)\n",
               surrogate, seed, summary.critical, summary.executions, summary.coverageCells,
               report::percentWithInterval(e.estimate, e.low, e.high), e.method, summary.seconds,
               summary.surrogateSeconds);
    totals.critical += static_cast<double>(summary.critical);
    totals.coverage += static_cast<double>(summary.coverageCells);
    totals.estimate += e.estimate;
    totals.width += e.high - e.low;
    totals.randomWidth += e.sameBudgetRandomWidth;
    totals.seconds += summary.seconds;
    totals.surrogateSecondsPerRound +=
        summary.rounds > 1 ? summary.surrogateSeconds / static_cast<double>(summary.rounds - 1) : 0.0;
    const double executions = static_cast<double>(std::max<std::uint64_t>(summary.executions, 1));
    totals.simulationMsPerExecution += 1000.0 * summary.simulationSeconds / executions;
    totals.surrogateMsPerExecution += 1000.0 * summary.surrogateSeconds / executions;
    summaries.push_back(summary);
  }
  const double n = static_cast<double>(options.seeds);
  for (double* value : {&totals.critical, &totals.coverage, &totals.estimate, &totals.width, &totals.randomWidth,
                        &totals.seconds, &totals.surrogateSecondsPerRound, &totals.simulationMsPerExecution,
                        &totals.surrogateMsPerExecution}) {
    *value /= n;
  }
  return totals;
}

}  // namespace

void addSearchBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<SearchBenchOptions>();
  options->search.scenarioFile = "scenarios/acc_lk.yaml";
  options->search.criterion = "d_min < 2";
  CLI::App* command = bench.add_subcommand("search", "Surrogates of `vsd-sumo search` side by side (same budget, seeds)");
  command->add_option("scenario", options->search.scenarioFile, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  command->add_option("--criterion", options->search.criterion, "Criterion")->capture_default_str();
  command->add_option("--surrogates", options->surrogates, "Surrogates to compare")->delimiter(',')->capture_default_str();
  addNumber(command, "--budget", options->search.budget, "Executions per search")->capture_default_str();
  addNumber(command, "--initial", options->search.initial, "Initial design")->capture_default_str();
  addNumber(command, "--round", options->search.roundSize, "Executions per round")->capture_default_str();
  addNumber(command, "--pool", options->search.pool, "Candidates per round")->capture_default_str();
  addNumber(command, "--estimate-share", options->search.estimateShare,
            "Share of each round drawn by importance sampling for the rate estimate")
      ->capture_default_str();
  command->add_option("--probability", options->search.probability, "extra-trees: shifts or tail")
      ->capture_default_str();
  command->add_flag("--rank-targets", options->search.rankTargets, "extra-trees: fit metric ranks");
  addNumber(command, "--diversity", options->search.diversity, "Weight of the distance term in the acquisition")
      ->capture_default_str();
  command->add_option("--prior", options->search.priors, "vectornet: prior datasets (see search --prior)")
      ->check(CLI::ExistingPath);
  addNumber(command, "--vectornet-steps", options->search.vectornetSteps, "vectornet: training steps per round")
      ->capture_default_str();
  addNumber(command, "--futures", options->search.futureSamples, "vectornet: sampled futures per candidate")
      ->capture_default_str();
  addNumber(command, "--seeds", options->seeds, "Searches per surrogate (seeds 1..N)")->capture_default_str();
  command->add_option("--report", options->report,
                      "Write an HTML report (learning curves of every search, rate estimates) to this file");
  addNumber(command, "-j,--jobs", options->search.jobs, "Worker processes for the simulations")->capture_default_str();
  addEgoStepCostOption(*command, options->search.egoStepCost);
  command->callback([options, &context] {
    context.action = [options, &context] {
      if (options->seeds < 1 || options->seeds > 1000) {
        throw ConfigError::field("command line", "--seeds", std::to_string(options->seeds), "1 .. 1000");
      }
      if (!options->report.empty()) {  // the output policy (docs/output-policy.md), before any work
        static const OutputKind kSearchReport = textFileKind(
            "search report", "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                             "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                             "<title>vsd-sumo search: ");
        checkOutput({options->report, &kSearchReport, "", false, "--report", "--force",
                     {{"scenario", options->search.scenarioFile}}});
      }
      TemporaryDirectory work("vsd-bench-search");
      const auto& s = options->search;
      fmt::print("{}: '{}', budget {} (initial {}, rounds of {}, pool {}), {} seed(s), Ego step cost {} ms; load "
                 "average {}\n",
                 s.scenarioFile.string(), s.criterion, s.budget, s.initial, s.roundSize, s.pool, options->seeds,
                 1000.0 * s.egoStepCost, loadAverage());
      std::vector<std::pair<std::string, SurrogateTotals>> results;
      std::vector<search::SearchSummary> summaries;
      for (const auto& surrogate : options->surrogates) {
        results.emplace_back(surrogate, benchSurrogate(*options, surrogate, work.path(), summaries));
      }
      double random_critical = 0.0;
      for (const auto& [name, totals] : results) {
        if (name == "random") random_critical = totals.critical;
      }
      fmt::print("  mean over seeds:\n  {:<12} {:>9} {:>8} {:>7} {:>11} {:>11} {:>16} {:>9} {:>14} {:>12} {:>12}\n",
                 "surrogate", "critical", "x random", "cells", "P est. %", "CI width %", "random CI width %",
                 "seconds", "surrogate s/rnd", "sim ms/exec", "surr ms/exec");
      for (const auto& [name, t] : results) {
        fmt::print("  {:<12} {:>9.1f} {:>8} {:>7.1f} {:>11.4f} {:>11.4f} {:>16.4f} {:>9.1f} {:>14.2f} {:>12.1f} "
                   "{:>12.1f}\n",
                   name, t.critical, random_critical > 0 ? fmt::format("{:.1f}", t.critical / random_critical) : "-",
                   t.coverage, 100 * t.estimate, 100 * t.width, 100 * t.randomWidth, t.seconds,
                   t.surrogateSecondsPerRound, t.simulationMsPerExecution, t.surrogateMsPerExecution);
      }
      if (!options->report.empty()) {
        std::vector<const search::SearchSummary*> pointers;
        for (const auto& summary : summaries) pointers.push_back(&summary);
        writeTextFileAtomically(options->report,
                                search::searchReportHtml(pointers, {{"command line", context.commandLine},
                                                                    {"load average", loadAverage()}}));
        fmt::print("  report: {}\n", options->report.string());
      }
      fmt::print("  load average after: {}\n", loadAverage());
      return 0;
    };
  });
}

}  // namespace vsd::cli
