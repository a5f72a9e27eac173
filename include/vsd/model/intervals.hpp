#pragma once
// Intervals from draws of a predictive distribution (e.g. a metric computed on every
// sampled future of a scene).

#include <cstddef>
#include <vector>

namespace vsd::model {

/// The q-quantile (0 <= q <= 1) of draws at the Weibull plotting position q (n + 1)
/// (Hyndman & Fan type 6), clamped to the smallest/largest draw: for exchangeable draws
/// the expected coverage of [quantile(a), quantile(b)] is b - a for every n, where the
/// usual (n - 1) interpolation covers less (84.5 % instead of 90 % for n = 32).
/// NaN draws are ignored; +-inf take part in the order. NaN if no draw is left.
double sampleQuantile(std::vector<double> draws, double q);

/// The central 50 % and 90 % intervals and the median of draws.
struct Interval {
  std::size_t draws = 0;  ///< draws that were not NaN
  double p05 = 0.0;
  double p25 = 0.0;
  double median = 0.0;
  double p75 = 0.0;
  double p95 = 0.0;
  /// Does the central interval of `level` (0.5 or 0.9) contain `value`?
  bool contains(double value, double level) const;
};
Interval intervalOf(const std::vector<double>& draws);

/// Where `value` lies in the draws, as the q with sampleQuantile(draws, q) == value
/// (linear between draws; 0 below the smallest, 1 above the largest draw). `value` lies in
/// the central interval of level L, [quantile((1 - L)/2), quantile((1 + L)/2)], exactly
/// when |2q - 1| <= L: one number per (scene, metric) gives the coverage of every level
/// (the reliability diagram). NaN if `value` or every draw is NaN.
double quantilePosition(std::vector<double> draws, double value);

}  // namespace vsd::model
