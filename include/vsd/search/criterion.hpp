#pragma once
// A search criterion: a boolean expression over registered metrics that marks a
// concrete scenario as critical ("d_min < 2", "ttc_min < 1 or d_min < 0.5" written
// in muparser syntax: `ttc_min < 1 || d_min < 0.5`), or the name of a criterion the
// logical scenario's YAML defines (`criteria: [{name: close_approach, fail_if: d_min < 2}]`),
// or, in a search with --reference, `reference_avoids_sut_collides`: UN R157's pass
// criterion fails (the reference driver avoided a collision the system under test had).

#include <optional>
#include <string>
#include <vector>

#include "vsd/scenario/expression.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::search {

class Criterion {
 public:
  /// `text` is a criterion name of `logical` or an expression. `metricNames` are the
  /// metrics the scenario's runs compute. Throws ConfigError (one line) for an unknown
  /// metric (listing the scenario's metrics and, for registered metrics it does not
  /// compute, saying so), a syntax error, or an expression that uses no metric.
  Criterion(const std::string& text, const scenario::LogicalScenario& logical,
            const std::vector<std::string>& metricNames);

  const std::string& name() const { return name_; }              ///< the YAML name, or the expression itself
  const std::string& expression() const { return expression_; }
  /// The metrics the expression reads, in metricNames order (the surrogates' targets).
  const std::vector<std::string>& usedMetrics() const { return used_; }
  /// Positions of usedMetrics() within metricNames.
  const std::vector<std::size_t>& usedColumns() const { return usedColumns_; }

  /// Verdict for all metric values (metricNames order): true if critical; nullopt when a
  /// metric it reads is NaN (not computable, failed run).
  std::optional<bool> verdict(const std::vector<double>& metricValues) const;
  /// Verdict for values of usedMetrics() only (what surrogates predict); never NaN inputs.
  bool meetsUsed(const std::vector<double>& usedValues) const;
  /// Verdict for values of usedMetrics() only; nullopt when one is NaN or the expression
  /// gives NaN (as verdict() on all values).
  std::optional<bool> verdictOfUsed(const std::vector<double>& usedValues) const;

 private:
  std::string name_;
  std::string expression_;
  std::vector<std::string> used_;
  std::vector<std::size_t> usedColumns_;
  scenario::Expression onAll_;
  scenario::Expression onUsed_;
};

}  // namespace vsd::search
