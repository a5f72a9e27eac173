#pragma once
// Medians: the two definitions the project uses, in one place.
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

}  // namespace vsd
