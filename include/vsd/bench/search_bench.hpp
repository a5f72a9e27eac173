#pragma once
// `vsd-sumo bench search`: the surrogates of `vsd-sumo search` side by side with the same
// budget, criterion and seeds: critical scenarios found, failure-region coverage, rate
// estimate and interval width, and the surrogate's overhead per round.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/bench/measure.hpp"
#include "vsd/search/search.hpp"

namespace vsd::bench {

struct SearchBenchOptions {
  search::SearchOptions search = defaultSearch();
  std::vector<std::string> surrogates = {"random", "extra-trees"};
  std::uint64_t seeds = 1;       ///< searches per surrogate (seeds 1..N)
  std::filesystem::path report;  ///< HTML report of every search (empty: none)

  /// The benchmark's search: kDefaultScenario, criterion "d_min < 2".
  static search::SearchOptions defaultSearch();
  /// Throws ConfigError for a seed count outside 1 .. 1000, and (before any work) for a
  /// report file the output policy refuses.
  void validate() const;
};

/// Means over the seeds of one surrogate.
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

struct SearchBenchResult {
  std::vector<std::pair<std::string, SurrogateTotals>> surrogates;  ///< in the order asked for
  std::vector<search::SearchSummary> searches;                       ///< every search

  /// Mean critical scenarios of the random surrogate (0 if it was not run).
  double randomCritical() const;
};

/// Called after each search (surrogate, seed, its summary).
using OnSearch = std::function<void(const std::string&, std::uint64_t, const search::SearchSummary&)>;

SearchBenchResult runSearchBench(const SearchBenchOptions& options, const OnSearch& on_search = {});

/// Writes the HTML report of every search to options.report (atomically).
void writeSearchBenchReport(const SearchBenchOptions& options, const SearchBenchResult& result,
                            const std::string& command_line);

}  // namespace vsd::bench
