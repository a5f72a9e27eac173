// The rate estimate of P(criterion) under the logical scenario's distribution: the
// mean of every estimator draw's contribution (see search.hpp). Draws of the random
// stream contribute their verdict; importance draws from a round's pool contribute
// mean_pool(p) + (y - p) / (N q), unbiased for the pool's critical share whatever the
// surrogate predicts. Runs without a verdict (failed simulation, metric not computable)
// are left out; `failedRuns` in the summary says how many there were.

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "search_internal.hpp"

namespace vsd::search::detail {

namespace {

constexpr double kZ95 = 1.959963984540054;

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (const double value : values) sum += value;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

/// Sample variance (n - 1).
double variance(const std::vector<double>& values) {
  if (values.size() < 2) return 0.0;
  const double m = mean(values);
  double sum = 0.0;
  for (const double value : values) sum += (value - m) * (value - m);
  return sum / static_cast<double>(values.size() - 1);
}

/// One round's contributions, each repeated as often as it was drawn.
struct RoundDraws {
  std::vector<double> values;
  bool fromPool = false;  ///< importance draws from a pool (adds the pool's own sampling variance)
};

std::map<std::uint64_t, RoundDraws> contributionsByRound(const std::vector<Execution>& executions) {
  std::map<std::uint64_t, RoundDraws> rounds;
  for (const auto& e : executions) {
    if (e.draws == 0 || e.verdict < 0) continue;
    const double y = e.verdict;
    const double z = e.fromRandomStream() ? y : e.poolMean + e.weight * (y - e.control);
    auto& round = rounds[e.round];
    round.fromPool = round.fromPool || !e.fromRandomStream();
    round.values.insert(round.values.end(), e.draws, z);
  }
  return rounds;
}

/// Wilson interval width at a (possibly fractional) rate p for n draws.
double wilsonWidth(double p, double n) {
  const double denominator = 1.0 + kZ95 * kZ95 / n;
  return 2.0 * kZ95 * std::sqrt(p * (1.0 - p) / n + kZ95 * kZ95 / (4.0 * n * n)) / denominator;
}

}  // namespace

RateEstimate estimateRate(const SearchContext& context, const std::vector<Execution>& executions) {
  RateEstimate result;
  for (const auto& execution : executions) {
    if (execution.verdict < 0 || !execution.fromRandomStream()) continue;
    ++result.randomExecutions;
    result.randomCritical += execution.verdict == 1 ? 1 : 0;
  }
  result.randomEstimate = result.randomExecutions == 0 ? 0.0
                                                : static_cast<double>(result.randomCritical) /
                                                      static_cast<double>(result.randomExecutions);
  std::tie(result.randomLow, result.randomHigh) = wilsonInterval(result.randomCritical, result.randomExecutions);
  result.method = "monte-carlo";
  result.estimate = result.randomEstimate;
  result.low = result.randomLow;
  result.high = result.randomHigh;
  if (context.guides) {
    const auto rounds = contributionsByRound(executions);
    std::vector<double> all;
    for (const auto& [round, draws] : rounds) all.insert(all.end(), draws.values.begin(), draws.values.end());
    const double n = static_cast<double>(all.size());
    const double estimate = mean(all);
    // Rounds are conditionally independent given the past: their variances add.
    double estimate_variance = 0.0;
    for (const auto& [round, draws] : rounds) {
      const double share = static_cast<double>(draws.values.size()) / n;
      const double within = draws.values.size() >= 2 ? variance(draws.values) : variance(all);
      double round_variance = within / static_cast<double>(draws.values.size());
      if (draws.fromPool) {
        const double p = std::clamp(estimate, 0.0, 1.0);
        round_variance += p * (1.0 - p) / static_cast<double>(context.options.pool);
      }
      estimate_variance += share * share * round_variance;
    }
    result.method = "importance+control-variate";
    result.draws = all.size();
    result.estimate = std::clamp(estimate, 0.0, 1.0);
    const double half = kZ95 * std::sqrt(estimate_variance);
    result.low = std::max(0.0, estimate - half);
    result.high = std::min(1.0, estimate + half);
  } else {
    result.draws = result.randomExecutions;
  }
  result.sameBudgetRandomWidth = wilsonWidth(result.estimate, static_cast<double>(context.options.budget));
  return result;
}

}  // namespace vsd::search::detail
