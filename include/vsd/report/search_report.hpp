#pragma once
// The HTML report of `vsd-sumo search` and `vsd-sumo bench search`: learning curves
// (critical scenarios found against executions, one per surrogate) and the rate
// estimates of P(criterion) with their 95 % intervals side by side. Self-contained
// (inline CSS and SVG), like the comparison report.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vsd::report {

/// Critical scenarios found after each number of executions.
struct LearningCurve {
  std::string name;  ///< e.g. "extra-trees (seed 1)"
  std::vector<std::pair<double, double>> points;  ///< (executions, critical found)
};

/// One estimate of P(criterion) with its 95 % interval.
struct RateRow {
  std::string name;    ///< e.g. "extra-trees: importance sampling"
  std::string method;  ///< e.g. "importance-sampling", "monte-carlo (Wilson)"
  std::uint64_t executions = 0;  ///< executions it rests on
  double estimate = 0.0;
  double low = 0.0;
  double high = 0.0;
};

struct SearchReport {
  std::string title;                 ///< e.g. "acc_lk: d_min < 2"
  std::vector<std::string> summary;  ///< lines under the title (plain text)
  std::vector<LearningCurve> curves;
  std::vector<RateRow> rates;
  /// Key/value lines: scenario file and SHA-256, seed, versions, command line.
  std::vector<std::pair<std::string, std::string>> provenance;
};

/// The complete HTML document.
std::string renderSearchReport(const SearchReport& report);

}  // namespace vsd::report
