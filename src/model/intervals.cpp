#include "vsd/model/intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vsd::model {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The draws without NaN, sorted.
std::vector<double> sortedDraws(std::vector<double> draws) {
  draws.erase(std::remove_if(draws.begin(), draws.end(), [](double v) { return std::isnan(v); }), draws.end());
  std::sort(draws.begin(), draws.end());
  return draws;
}

/// Type-6 quantile of sorted draws (see sampleQuantile).
double quantileOfSorted(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return kNaN;
  const double n = static_cast<double>(sorted.size());
  const double h = q * (n + 1.0);  // 1-based fractional order statistic
  if (h <= 1.0) return sorted.front();
  if (h >= n) return sorted.back();
  const auto lower = static_cast<std::size_t>(std::floor(h)) - 1;
  const double fraction = h - std::floor(h);
  if (fraction == 0.0 || sorted[lower] == sorted[lower + 1]) return sorted[lower];
  return sorted[lower] + fraction * (sorted[lower + 1] - sorted[lower]);
}

}  // namespace

double sampleQuantile(std::vector<double> draws, double q) { return quantileOfSorted(sortedDraws(std::move(draws)), q); }

bool Interval::contains(double value, double level) const {
  if (std::isnan(value)) return false;
  if (level == 0.5) return value >= p25 && value <= p75;
  if (level == 0.9) return value >= p05 && value <= p95;
  return false;
}

Interval intervalOf(const std::vector<double>& draws) {
  const auto sorted = sortedDraws(draws);
  Interval interval;
  interval.draws = sorted.size();
  interval.p05 = quantileOfSorted(sorted, 0.05);
  interval.p25 = quantileOfSorted(sorted, 0.25);
  interval.median = quantileOfSorted(sorted, 0.5);
  interval.p75 = quantileOfSorted(sorted, 0.75);
  interval.p95 = quantileOfSorted(sorted, 0.95);
  return interval;
}

double quantilePosition(std::vector<double> draws, double value) {
  const auto sorted = sortedDraws(std::move(draws));
  if (sorted.empty() || std::isnan(value)) return kNaN;
  const double n = static_cast<double>(sorted.size());
  if (value < sorted.front()) return 0.0;
  if (value > sorted.back()) return 1.0;
  const auto low = std::lower_bound(sorted.begin(), sorted.end(), value);
  const auto high = std::upper_bound(sorted.begin(), sorted.end(), value);
  double h = 0.0;  // 1-based fractional order statistic
  if (low != high) {
    // Draws equal to the value occupy orders [first, last]: the quantile function is flat
    // there, so the value is in every interval reaching that range; take its order closest
    // to the centre (the smallest level containing it).
    const double first = static_cast<double>(low - sorted.begin()) + 1.0;
    const double last = static_cast<double>(high - sorted.begin());
    h = std::clamp(0.5 * (n + 1.0), first, last);
  } else {
    const auto above = static_cast<std::size_t>(low - sorted.begin());  // sorted[above - 1] < value < sorted[above]
    const double a = sorted[above - 1];
    const double b = sorted[above];
    const double fraction = std::isinf(b - a) ? 0.5 : (value - a) / (b - a);
    h = static_cast<double>(above) + fraction;
  }
  return h / (n + 1.0);
}

}  // namespace vsd::model
