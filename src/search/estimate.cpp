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
// q is large, and the smaller the variance. Interval: normal, with the draws' variance
// within rounds (pooled; rounds differ in C_r, which is known, not noise) / n plus the
// pools' own sampling variance; with no critical draw in B the upper bound adds the rule
// of three for weights <= 1 / a: 3 / (a n). The initial design is left out of this
// estimate (fixed in advance, so no bias): its Monte Carlo draws have a far larger
// variance each. Runs without a verdict (failed simulation, metric not computable) count
// as not critical in A and are left out of B; the summary counts them.

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "search_internal.hpp"

namespace vsd::search::detail {

namespace {

constexpr double kZ95 = 1.959963984540054;

/// One importance draw: its round, the round's known part C_r / N and the draw's own
/// part y / (N q).
struct ImportanceDraw {
  std::uint64_t round = 0;
  double known = 0.0;
  double own = 0.0;
};

/// Every importance draw, repeated as often as drawn.
std::vector<ImportanceDraw> importanceDraws(const std::vector<Execution>& executions, double pool_size) {
  std::map<std::uint64_t, double> acquired_critical;
  for (const auto& e : executions) {
    if (e.origin == "acquired" && e.verdict == 1) acquired_critical[e.round] += 1.0;
  }
  std::vector<ImportanceDraw> draws;
  for (const auto& e : executions) {
    if (e.draws == 0 || e.verdict < 0 || e.fromRandomStream()) continue;
    const ImportanceDraw draw{e.round, acquired_critical[e.round] / pool_size, e.weight * static_cast<double>(e.verdict)};
    draws.insert(draws.end(), e.draws, draw);
  }
  return draws;
}

/// The variance of the draws' own parts within rounds, pooled over the rounds (n - rounds
/// degrees of freedom).
double pooledWithinRoundVariance(const std::vector<ImportanceDraw>& draws, std::uint64_t& rounds) {
  std::map<std::uint64_t, std::pair<double, double>> sums;  // round -> (count, sum)
  for (const auto& d : draws) {
    sums[d.round].first += 1.0;
    sums[d.round].second += d.own;
  }
  rounds = sums.size();
  double squares = 0.0;
  for (const auto& d : draws) {
    const auto& [count, sum] = sums[d.round];
    squares += (d.own - sum / count) * (d.own - sum / count);
  }
  const double freedom = static_cast<double>(draws.size()) - static_cast<double>(rounds);
  return freedom > 0.0 ? squares / freedom : 0.0;
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
  const auto draws = importanceDraws(executions, static_cast<double>(context.options.pool));
  if (context.guides && !draws.empty()) {
    const double n = static_cast<double>(draws.size());
    double sum = 0.0;
    for (const auto& d : draws) sum += d.known + d.own;
    const double estimate = std::clamp(sum / n, 0.0, 1.0);
    std::uint64_t rounds = 0;
    const double within = pooledWithinRoundVariance(draws, rounds);
    // Each round's pool is N fresh draws of the distribution; rounds weigh by their draws,
    // so the pools' sampling variance adds up to about p (1 - p) / (N * rounds).
    const double pool_variance =
        estimate * (1.0 - estimate) / (static_cast<double>(context.options.pool) * static_cast<double>(rounds));
    const double half = kZ95 * std::sqrt(within / n + pool_variance);
    result.method = "importance-sampling";
    result.draws = draws.size();
    result.estimate = estimate;
    result.low = std::max(0.0, estimate - half);
    result.high = std::min(1.0, estimate + half);
    if (!anyCriticalDraw(executions)) result.high = std::min(1.0, result.high + 3.0 / (kDefensiveShare * n));
  } else {
    result.draws = result.randomExecutions;
  }
  result.sameBudgetRandomWidth = wilsonWidth(result.estimate, static_cast<double>(context.options.executionBudget()));
  return result;
}

}  // namespace vsd::search::detail
