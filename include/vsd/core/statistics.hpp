#pragma once
// Medians (the two definitions the project uses), mean and spread over seeds, and the interval of a
// proportion, in one place.
//
// median() is the textbook one (benchmarks' repeated timings). upperMedian() is the element
// at position n / 2 of the sorted values, for an even count the upper of the middle two: it
// is always one of the values (a scene's own error, a scene to draw), and the calibration
// scale of model/intervals.cpp was defined with it, so models keep their bytes.

#include <cstddef>
#include <vector>

namespace vsd {

/// The median (mean of the middle two for an even count). Throws Error for no values.
double median(std::vector<double> values);

/// The value at position n / 2 of the sorted values (the upper of the middle two for an
/// even count). Throws Error for no values.
double upperMedian(std::vector<double> values);

/// The index of upperMedian(values) in `values`; among equal values the smallest index.
/// Throws Error for no values.
std::size_t upperMedianIndex(const std::vector<double>& values);

/// The arithmetic mean. Throws Error for no values.
double sampleMean(const std::vector<double>& values);

/// The sample standard deviation (n - 1 in the denominator); 0 for fewer than two values.
double sampleStd(const std::vector<double>& values);

/// A range of a proportion (0..1).
struct ProportionInterval {
  double low = 0.0;
  double high = 1.0;
};

/// The Wilson score interval of a proportion observed as `share` of `trials` trials (the
/// share of simulated values an interval covered, say) at confidence 1 - alpha for the
/// standard-normal quantile `z` (1.96: 95 %). Unlike p ± z sqrt(p(1 - p)/n) it stays inside
/// 0..1 and is not empty at a share of 0 or 1. Throws Error for no trials or a share
/// outside 0..1.
ProportionInterval wilsonInterval(double share, std::size_t trials, double z = 1.959963984540054);

}  // namespace vsd
