#pragma once
// `vsd-sumo bench search`: the surrogates of `vsd-sumo search` side by side with the same
// budget, criterion and seeds: critical scenarios found, failure-region coverage, rate
// estimate and interval width, and the surrogate's overhead per round.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/bench/measure.hpp"
#include "vsd/search/search.hpp"

namespace vsd::bench {

struct SearchBenchOptions {
  search::SearchOptions search = defaultSearch();
  std::vector<std::string> surrogates = {"random", "extra-trees"};
  std::uint64_t seeds = 1;       ///< searches per surrogate
  std::uint64_t firstSeed = 1;   ///< their seeds: firstSeed .. firstSeed + seeds - 1
  std::filesystem::path report;  ///< HTML report of every search (empty: none)
  /// The true rate the estimates are checked against: P(criterion) by plain Monte Carlo over
  /// this many concrete scenarios (search::monteCarloRate); 0: none.
  std::uint64_t trueRateSamples = 0;
  /// Its seed: none of the searches' (its draws are independent of theirs).
  std::uint64_t trueRateSeed = 1'000'000;
  /// Results folder (searches.csv, surrogates.csv, README.md, manifest.json, written as one
  /// set; refused under the repository's results/ from a dirty build); empty: none.
  std::filesystem::path out;
  bool allowDirty = false;

  /// What the results folder is about: "<scenario file>: <criterion>".
  std::string subject() const;
  /// The benchmark's search: kDefaultScenario, criterion "d_min < 2".
  static search::SearchOptions defaultSearch();
  /// Throws ConfigError for a seed count outside 1 .. 1000, a true-rate seed among the
  /// searches' seeds, and (before any work) for a report file the output policy refuses or
  /// an --out under results/ from a dirty build.
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
  std::optional<search::MonteCarloRate> trueRate;                    ///< with trueRateSamples > 0
  double trueRateSeconds = 0.0;  ///< wall time of the true-rate run (s)
  double seconds = 0.0;          ///< wall time of the whole benchmark: true rate and every search (s)

  /// Mean critical scenarios of the random surrogate (0 if it was not run).
  double randomCritical() const;
};

/// Called after each search (surrogate, seed, its summary).
using OnSearch = std::function<void(const std::string&, std::uint64_t, const search::SearchSummary&)>;

SearchBenchResult runSearchBench(const SearchBenchOptions& options, const OnSearch& on_search = {});

/// True if the search's 95 % interval holds the true rate's point estimate.
bool coversTrueRate(const search::SearchSummary& summary, const search::MonteCarloRate& rate);

/// Searches of `surrogate` whose interval holds the true rate; nullopt without a true rate.
std::optional<std::size_t> seedsCoveringTrueRate(const SearchBenchResult& result, const std::string& surrogate);

/// Writes the results folder options.out: searches.csv (one row per search), surrogates.csv
/// (per surrogate: means and standard deviations over the seeds, the share of seeds whose
/// interval covers the true rate), README.md and manifest.json (command, version, seeds, sizes).
void writeSearchBenchResults(const SearchBenchOptions& options, const SearchBenchResult& result,
                             const std::string& command_line);

/// Writes the HTML report of every search to options.report (atomically).
void writeSearchBenchReport(const SearchBenchOptions& options, const SearchBenchResult& result,
                            const std::string& command_line);

}  // namespace vsd::bench
