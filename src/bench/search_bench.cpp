#include "vsd/bench/search_bench.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/report/numbers.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

/// The output policy's kind of the report (docs/output-policy.md): what an existing file
/// must start with to be replaced.
const OutputKind& searchReportKind() {
  static const OutputKind kind = textFileKind(
      "search report", "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                       "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
                       "<title>vsd-sumo search: ");
  return kind;
}

void addSearch(SurrogateTotals& totals, const search::SearchSummary& summary) {
  const auto& e = summary.estimate;
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
}

SurrogateTotals benchSurrogate(const SearchBenchOptions& options, const std::string& surrogate, const fs::path& work,
                               std::vector<search::SearchSummary>& summaries, const OnSearch& on_search) {
  SurrogateTotals totals;
  for (std::uint64_t seed = options.firstSeed; seed < options.firstSeed + options.seeds; ++seed) {
    search::SearchOptions run = options.search;
    run.surrogate = surrogate;
    run.seed = seed;
    run.outputDir = work / fmt::format("{}_{}", surrogate, seed);
    const auto summary = search::runSearch(run);
    if (on_search) on_search(surrogate, seed, summary);
    addSearch(totals, summary);
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

search::SearchOptions SearchBenchOptions::defaultSearch() {
  search::SearchOptions search;
  search.scenarioFile = kDefaultScenario;
  search.criterion = "d_min < 2";
  return search;
}

void SearchBenchOptions::validate() const {
  if (seeds < 1 || seeds > 1000) throw ConfigError::field("command line", "--seeds", std::to_string(seeds), "1 .. 1000");
  if (firstSeed > (std::uint64_t{1} << 62)) {  // firstSeed + seeds must not wrap around
    throw ConfigError::field("command line", "--first-seed", std::to_string(firstSeed), "0 .. 2^62");
  }
  if (trueRateSamples > 10'000'000) {
    throw ConfigError::field("command line", "--true-rate-samples", std::to_string(trueRateSamples), "0 .. 10000000");
  }
  for (const auto& surrogate : surrogates) {  // every search's options before any work (the true-rate run comes first)
    search::SearchOptions each = search;
    each.surrogate = surrogate;
    if (each.outputDir.empty()) each.outputDir = ".";  // validated, never written: each search gets its own folder
    each.validate();
  }
  if (trueRateSamples > 0 && trueRateSeed >= firstSeed && trueRateSeed < firstSeed + seeds) {
    throw ConfigError::field("command line", "--true-rate-seed", std::to_string(trueRateSeed),
                             fmt::format("a seed none of the searches uses (they use {} .. {})", firstSeed,
                                         firstSeed + seeds - 1));
  }
  if (!out.empty()) {
    refuseDirtyCommittedResults(out, allowDirty, "--allow-dirty");
    checkOutput({out, &output_kinds::searchBenchmarkFolder(), subject(), false, "--out", "--force",
                 {{"scenario", search.scenarioFile}}});
  }
  if (!report.empty()) {  // the output policy (docs/output-policy.md), before any work
    checkOutput({report, &searchReportKind(), "", false, "--report", "--force", {{"scenario", search.scenarioFile}}});
  }
}

std::string SearchBenchOptions::subject() const {
  return fmt::format("{}: {}", search.scenarioFile.string(), search.criterion);
}

double SearchBenchResult::randomCritical() const {
  for (const auto& [name, totals] : surrogates) {
    if (name == "random") return totals.critical;
  }
  return 0.0;
}

SearchBenchResult runSearchBench(const SearchBenchOptions& options, const OnSearch& on_search) {
  options.validate();
  TemporaryDirectory work("vsd-bench-search");
  SearchBenchResult result;
  // Wall times: the docs state each committed benchmark's time budget against them.
  const auto started = std::chrono::steady_clock::now();
  if (options.trueRateSamples > 0) {
    result.trueRate = search::monteCarloRate(options.search, options.trueRateSeed, options.trueRateSamples);
    result.trueRateSeconds = secondsSince(started);
  }
  for (const auto& surrogate : options.surrogates) {
    result.surrogates.emplace_back(surrogate,
                                   benchSurrogate(options, surrogate, work.path(), result.searches, on_search));
  }
  result.seconds = secondsSince(started);
  return result;
}

bool coversTrueRate(const search::SearchSummary& summary, const search::MonteCarloRate& rate) {
  return summary.estimate.low <= rate.estimate && rate.estimate <= summary.estimate.high;
}

std::optional<std::size_t> seedsCoveringTrueRate(const SearchBenchResult& result, const std::string& surrogate) {
  if (!result.trueRate) return std::nullopt;
  return static_cast<std::size_t>(std::count_if(result.searches.begin(), result.searches.end(), [&](const auto& s) {
    return s.surrogate == surrogate && coversTrueRate(s, *result.trueRate);
  }));
}

namespace {

std::string percent(double share) { return formatNumber(100.0 * share); }

/// Critical executions found by the end of each round, "3/8/15/...": the learning curve.
std::string criticalByRound(const search::SearchSummary& summary) {
  std::vector<std::uint64_t> found;
  for (const auto& execution : summary.executionsList) {
    if (execution.round >= found.size()) found.resize(execution.round + 1, 0);
    if (execution.verdict == 1) ++found[execution.round];
  }
  for (std::size_t r = 1; r < found.size(); ++r) found[r] += found[r - 1];
  return fmt::format("{}", fmt::join(found, "/"));
}

std::string searchesCsv(const SearchBenchResult& result) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow({"surrogate", "seed", "executions", "critical", "cells", "method", "estimate_percent", "low_percent",
                "high_percent", "covers_true_rate", "critical_by_round", "seconds", "surrogate_seconds",
                "simulation_seconds"});
  for (const auto& s : result.searches) {
    const auto& e = s.estimate;
    csv.writeRow({s.surrogate, std::to_string(s.seed), std::to_string(s.executions), std::to_string(s.critical),
                  std::to_string(s.coverageCells), e.method, percent(e.estimate), percent(e.low), percent(e.high),
                  result.trueRate ? std::to_string(coversTrueRate(s, *result.trueRate) ? 1 : 0) : "", criticalByRound(s),
                  formatNumber(s.seconds), formatNumber(s.surrogateSeconds), formatNumber(s.simulationSeconds)});
  }
  return text.str();
}

/// One surrogate's searches: values of one field.
template <typename Field>
std::vector<double> valuesOf(const SearchBenchResult& result, const std::string& surrogate, Field field) {
  std::vector<double> values;
  for (const auto& s : result.searches) {
    if (s.surrogate == surrogate) values.push_back(field(s));
  }
  return values;
}

/// One row of surrogates.csv: the means come from the surrogate's totals, the spreads from its searches.
std::vector<std::string> surrogateRow(const SearchBenchResult& result, const std::string& name,
                                      const SurrogateTotals& t, std::uint64_t seeds) {
  const auto critical = valuesOf(result, name, [](const auto& s) { return static_cast<double>(s.critical); });
  const auto estimate = valuesOf(result, name, [](const auto& s) { return 100.0 * s.estimate.estimate; });
  const double random = result.randomCritical();
  std::string covered;
  std::string covered_share;
  if (const auto k = seedsCoveringTrueRate(result, name)) {
    covered = fmt::format("{}/{}", *k, seeds);
    covered_share = formatNumber(static_cast<double>(*k) / static_cast<double>(seeds));
  }
  return {name, std::to_string(seeds), fmt::format("{:.1f}", t.critical), fmt::format("{:.1f}", sampleStd(critical)),
          random > 0 ? fmt::format("{:.2f}", t.critical / random) : "", fmt::format("{:.1f}", t.coverage),
          fmt::format("{:.4f}", 100.0 * t.estimate), fmt::format("{:.4f}", sampleStd(estimate)),
          fmt::format("{:.4f}", 100.0 * t.width), covered, covered_share, fmt::format("{:.1f}", t.seconds)};
}

std::string surrogatesCsv(const SearchBenchResult& result, std::uint64_t seeds) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow({"surrogate", "seeds", "critical_mean", "critical_std", "x_random", "cells_mean",
                "estimate_mean_percent", "estimate_std_percent", "interval_width_mean_percent", "covers_true_rate",
                "covers_true_rate_share", "seconds_mean"});
  for (const auto& [name, totals] : result.surrogates) csv.writeRow(surrogateRow(result, name, totals, seeds));
  return text.str();
}

std::string resultsReadme(const SearchBenchOptions& options, const SearchBenchResult& result,
                          const std::string& command_line) {
  const auto& s = options.search;
  std::string text = fmt::format(
      "# Search benchmark: {}, criterion '{}'\n\nMade by `{}` with vsd-sumo {} (docs/search.md, "
      "docs/benchmarks.md).\n\n- Searches: surrogates {}, seeds {} .. {}, budget {} simulations (initial design {} "
      "executions, rounds of {}, pool {}, estimate share {}), {} simulation job(s).\n",
      s.scenarioFile.string(), s.criterion, command_line, toolVersion(), fmt::join(options.surrogates, ", "),
      options.firstSeed, options.firstSeed + options.seeds - 1, s.budget, s.initial, s.roundSize, s.pool,
      s.estimateShare, s.jobs);
  if (!s.reference.empty()) {
    text += fmt::format("- Reference driver: `{}`; every execution runs twice (the system under test and the "
                        "reference), so an execution costs two simulations of the budget.\n",
                        s.reference);
  }
  if (!s.priors.empty()) {
    std::vector<std::string> priors;
    for (const auto& prior : s.priors) priors.push_back(prior.string());
    text += fmt::format("- Priors (vectornet): {}; {} steps per round, {} futures per candidate.\n",
                        fmt::join(priors, ", "), s.vectornetSteps, s.futureSamples);
  }
  text += fmt::format("- libtorch threads per search: {}.\n", s.threads);
  if (result.trueRate) {
    const auto& r = *result.trueRate;
    text += fmt::format(
        "- True rate: plain Monte Carlo over {} concrete scenarios of seed {} (no search's seed): {} critical, "
        "P = {} (Wilson 95 %), {} without a verdict. A search's interval covers the true rate when it holds this "
        "point estimate.\n",
        r.samples, r.seed, r.critical, report::percentWithInterval(r.estimate, r.low, r.high), r.withoutVerdict);
  }
  text += fmt::format("- Wall time: {:.0f} s in all{}.\n", result.seconds,
                      result.trueRate ? fmt::format(", of them {:.0f} s for the true rate", result.trueRateSeconds) : "");
  text += "\n`surrogates.csv`: per surrogate, mean and standard deviation over the seeds; `searches.csv`: every "
          "search.\n";
  return text;
}

}  // namespace

void writeSearchBenchResults(const SearchBenchOptions& options, const SearchBenchResult& result,
                             const std::string& command_line) {
  OutputFolder output(options.out);
  output.stageText("searches.csv", searchesCsv(result));
  output.stageText("surrogates.csv", surrogatesCsv(result, options.seeds));
  output.stageText("README.md", resultsReadme(options, result, command_line));
  nlohmann::json manifest{{"kind", "search-benchmark"},
                          {"subject", options.subject()},
                          {"command", command_line},
                          {"version", toolVersion()},
                          {"seeds", {{"first", options.firstSeed}, {"count", options.seeds}}},
                          {"sizes",
                           {{"budget", options.search.budget},
                            {"initial", options.search.initial},
                            {"round", options.search.roundSize},
                            {"pool", options.search.pool}}},
                          {"reference", options.search.reference},
                          {"seconds", result.seconds}};
  if (result.trueRate) {
    const auto& r = *result.trueRate;
    manifest["true_rate"] = {{"seed", r.seed},         {"samples", r.samples}, {"critical", r.critical},
                             {"estimate", r.estimate}, {"low", r.low},         {"high", r.high},
                             {"seconds", result.trueRateSeconds}};
  }
  output.commit(manifest);
}

void writeSearchBenchReport(const SearchBenchOptions& options, const SearchBenchResult& result,
                            const std::string& command_line) {
  std::vector<const search::SearchSummary*> pointers;
  for (const auto& summary : result.searches) pointers.push_back(&summary);
  writeTextFileAtomically(options.report, search::searchReportHtml(pointers, {{"command line", command_line},
                                                                              {"load average", loadAverage()}}));
}

}  // namespace vsd::bench
