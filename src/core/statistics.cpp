#include "vsd/core/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "vsd/core/error.hpp"

namespace vsd {

namespace {

void requireValues(const std::vector<double>& values, const char* what) {
  if (values.empty()) throw Error(std::string("internal: ") + what + " of no values");
}

}  // namespace

double median(std::vector<double> values) {
  requireValues(values, "median");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double upperMedian(std::vector<double> values) {
  requireValues(values, "upper median");
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

std::size_t upperMedianIndex(const std::vector<double>& values) {
  requireValues(values, "upper median");
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto middle = order.begin() + static_cast<std::ptrdiff_t>(order.size() / 2);
  // Ordered by value, then by index: the same element as sorting (value, index) pairs.
  std::nth_element(order.begin(), middle, order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] < values[b] || (values[a] == values[b] && a < b);
  });
  return *middle;
}

double sampleMean(const std::vector<double>& values) {
  if (values.empty()) throw Error("internal: the mean of no values");
  double sum = 0.0;
  for (const double value : values) sum += value;
  return sum / static_cast<double>(values.size());
}

double sampleStd(const std::vector<double>& values) {
  if (values.size() < 2) return 0.0;
  const double average = sampleMean(values);
  double squares = 0.0;
  for (const double value : values) squares += (value - average) * (value - average);
  return std::sqrt(squares / static_cast<double>(values.size() - 1));
}

ProportionInterval wilsonInterval(double share, std::size_t trials, double z) {
  if (trials == 0 || !(share >= 0.0 && share <= 1.0)) {
    throw Error("internal: a proportion interval needs trials and a share in 0..1");
  }
  const double n = static_cast<double>(trials);
  const double z2 = z * z;
  const double centre = (share + z2 / (2.0 * n)) / (1.0 + z2 / n);
  const double half = z / (1.0 + z2 / n) * std::sqrt(share * (1.0 - share) / n + z2 / (4.0 * n * n));
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

}  // namespace vsd
