#include "vsd/bench/search_bench.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/output_policy.hpp"

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
  for (std::uint64_t seed = 1; seed <= options.seeds; ++seed) {
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
  if (!report.empty()) {  // the output policy (docs/output-policy.md), before any work
    checkOutput({report, &searchReportKind(), "", false, "--report", "--force", {{"scenario", search.scenarioFile}}});
  }
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
  for (const auto& surrogate : options.surrogates) {
    result.surrogates.emplace_back(surrogate,
                                   benchSurrogate(options, surrogate, work.path(), result.searches, on_search));
  }
  return result;
}

void writeSearchBenchReport(const SearchBenchOptions& options, const SearchBenchResult& result,
                            const std::string& command_line) {
  std::vector<const search::SearchSummary*> pointers;
  for (const auto& summary : result.searches) pointers.push_back(&summary);
  writeTextFileAtomically(options.report, search::searchReportHtml(pointers, {{"command line", command_line},
                                                                              {"load average", loadAverage()}}));
}

}  // namespace vsd::bench
