// The rate estimate of P(criterion) under the logical scenario's distribution.
//
// Monte Carlo (random surrogate): the critical share of the random stream, Wilson interval.
// Guided surrogates: stratified importance sampling over each round's pool of N candidates,
// a sample of the logical scenario's distribution. Stratum A, the acquired candidates, is
// simulated in full: its C_r critical ones are known exactly. Stratum B, the rest, is
// sampled: draw j picked candidate i with probability q_i (fixed before the round from the
// surrogate fitted on earlier rounds). z_j = C_r / N + y_j / (N q_i) then has
// E[z | pool] = the pool's critical share, so the mean of all z is unbiased whatever the
// surrogate predicts; the better it predicts, the more critical mass lies in A or where
// q is large, and the smaller the variance. Interval: normal, with the draws' pooled
// variance / n plus the pools' own sampling variance; with no critical draw in B the upper
// bound adds the rule of three for weights <= 1 / a: 3 / (a n). The initial design is left
// out of this estimate (fixed in advance, so no bias): its Monte Carlo draws have a far
// larger variance each. Runs without a verdict (failed simulation, metric not computable)
// count as not critical in A and are left out of B; the summary counts them.

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
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

/// Contributions of every importance draw, repeated as often as drawn: z = C_r / N + y / (N q),
/// C_r the critical acquired candidates of its round (stratum A, simulated in full).
std::vector<double> importanceContributions(const std::vector<Execution>& executions, double pool_size,
                                            std::uint64_t& rounds) {
  std::map<std::uint64_t, double> acquired_critical;
  for (const auto& e : executions) {
    if (e.origin == "acquired" && e.verdict == 1) acquired_critical[e.round] += 1.0;
  }
  std::vector<double> values;
  std::set<std::uint64_t> seen_rounds;
  for (const auto& e : executions) {
    if (e.draws == 0 || e.verdict < 0 || e.fromRandomStream()) continue;
    values.insert(values.end(), e.draws, acquired_critical[e.round] / pool_size + e.weight * e.verdict);
    seen_rounds.insert(e.round);
  }
  rounds = seen_rounds.size();
  return values;
}

bool anyCriticalDraw(const std::vector<Execution>& executions) {
  return std::any_of(executions.begin(), executions.end(),
                     [](const Execution& e) { return e.origin == "importance" && e.verdict == 1; });
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
  std::uint64_t rounds = 0;
  const auto draws = importanceContributions(executions, static_cast<double>(context.options.pool), rounds);
  if (context.guides && !draws.empty()) {
    const double n = static_cast<double>(draws.size());
    const double estimate = std::clamp(mean(draws), 0.0, 1.0);
    // Each round's pool is N fresh draws of the distribution; rounds weigh by their draws,
    // so the pools' sampling variance adds up to about p (1 - p) / (N * rounds).
    const double pool_variance =
        estimate * (1.0 - estimate) / (static_cast<double>(context.options.pool) * static_cast<double>(rounds));
    const double half = kZ95 * std::sqrt(variance(draws) / n + pool_variance);
    result.method = "importance-sampling";
    result.draws = draws.size();
    result.estimate = estimate;
    result.low = std::max(0.0, estimate - half);
    result.high = std::min(1.0, estimate + half);
    if (!anyCriticalDraw(executions)) result.high = std::min(1.0, result.high + 3.0 / (kDefensiveShare * n));
  } else {
    result.draws = result.randomExecutions;
  }
  result.sameBudgetRandomWidth = wilsonWidth(result.estimate, static_cast<double>(context.options.budget));
  return result;
}

}  // namespace vsd::search::detail
