#include "vsd/model/intervals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "vsd/core/statistics.hpp"

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

namespace {

/// Piecewise-linear value of `values` (at `levels`) at `level`, from 0 at level 0.
double interpolate(const std::vector<double>& levels, const std::vector<double>& values, double level) {
  if (levels.empty()) return 0.0;
  if (level >= levels.back()) return values.back();
  if (level <= levels.front()) return values.front() * std::max(0.0, level) / levels.front();
  const auto upper = static_cast<std::size_t>(std::upper_bound(levels.begin(), levels.end(), level) - levels.begin());
  const double fraction = (level - levels[upper - 1]) / (levels[upper] - levels[upper - 1]);
  return values[upper - 1] + fraction * (values[upper] - values[upper - 1]);
}

}  // namespace

double IntervalWidening::rawLevelAt(double level) const { return interpolate(levels, rawLevels, level); }
double IntervalWidening::wideningAt(double level) const { return interpolate(levels, widening, level); }

const IntervalWidening* IntervalCalibration::find(const std::string& label, const std::string& metric) const {
  for (const auto& key : {label, std::string()}) {
    const auto per_label = byLabel.find(key);
    if (per_label == byLabel.end()) continue;
    const auto found = per_label->second.find(metric);
    if (found != per_label->second.end()) return &found->second;
  }
  return nullptr;
}

namespace {

/// A held-out scene's sorted draws, their 90 % width and reference (usable ones only).
struct Scored {
  std::vector<double> sorted;
  double width90 = 0.0;
  double reference = 0.0;
};

/// The scale of the normalised score: the (upper) median 90 % width, or (draws without
/// spread) the (upper) median distance of the references from the draws' medians.
double widthFloor(const std::vector<Scored>& scored) {
  std::vector<double> widths;
  std::vector<double> distances;
  for (const auto& s : scored) {
    widths.push_back(s.width90);
    distances.push_back(std::abs(s.reference - quantileOfSorted(s.sorted, 0.5)));
  }
  const double width = upperMedian(widths);
  if (width > 0.0) return width;
  return std::max(upperMedian(distances), 1e-9);
}

/// The smallest central level of sorted draws holding `value` (1 outside their range).
double rawContainingLevel(const std::vector<double>& sorted, double value) {
  if (value < sorted.front() || value > sorted.back()) return 1.0;
  return std::abs(2.0 * quantilePosition(sorted, value) - 1.0);
}

/// centralInterval of draws already sorted without NaN.
std::array<double, 2> centralIntervalOfSorted(const std::vector<double>& sorted, double level,
                                              const IntervalWidening* widening) {
  if (sorted.empty()) return {kNaN, kNaN};
  const double raw = widening == nullptr ? level : widening->rawLevelAt(level);
  double low = quantileOfSorted(sorted, 0.5 * (1.0 - raw));
  double high = quantileOfSorted(sorted, 0.5 * (1.0 + raw));
  if (widening == nullptr) return {low, high};
  const double scale = quantileOfSorted(sorted, 0.95) - quantileOfSorted(sorted, 0.05) + widening->floor;
  const double extra = widening->wideningAt(level) * scale;
  if (extra > 0.0 && std::isfinite(scale)) {  // infinite draws (e.g. ttc_min): nothing to scale by
    low -= extra;
    high += extra;
  }
  return {low, high};
}

}  // namespace

double conformalQuantile(std::vector<double> values, double level) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double n = static_cast<double>(values.size());
  const auto rank = std::min(values.size(), static_cast<std::size_t>(std::ceil((n + 1.0) * level)));
  return values[std::max<std::size_t>(rank, 1) - 1];
}

bool fitIntervalWidening(const std::vector<HeldOutMetric>& scenes, IntervalWidening& widening) {
  std::vector<Scored> scored;
  for (const auto& scene : scenes) {
    if (!std::isfinite(scene.reference)) continue;
    Scored s{sortedDraws(scene.draws), 0.0, scene.reference};
    if (s.sorted.empty()) continue;
    s.width90 = quantileOfSorted(s.sorted, 0.95) - quantileOfSorted(s.sorted, 0.05);
    if (!std::isfinite(s.width90) || !std::isfinite(s.sorted.front()) || !std::isfinite(s.sorted.back())) continue;
    scored.push_back(std::move(s));
  }
  if (scored.size() < kMinCalibrationScenes) return false;
  IntervalWidening fitted;
  fitted.floor = widthFloor(scored);
  fitted.scenes = scored.size();
  std::vector<double> raw_levels;   // per scene: the smallest raw level holding its reference
  std::vector<double> outside;      // per scene: how far outside the draws' range, in units of u (<= 0 inside)
  for (const auto& s : scored) {
    raw_levels.push_back(rawContainingLevel(s.sorted, s.reference));
    outside.push_back(std::max(s.sorted.front() - s.reference, s.reference - s.sorted.back()) /
                      (s.width90 + fitted.floor));
  }
  for (const double level : kCalibratedLevels) {
    double raw = conformalQuantile(raw_levels, level);
    double w = raw < 1.0 ? 0.0 : std::max(0.0, conformalQuantile(outside, level));
    if (!fitted.levels.empty()) {  // nested intervals
      raw = std::max(raw, fitted.rawLevels.back());
      w = std::max(w, fitted.widening.back());
    }
    fitted.levels.push_back(level);
    fitted.rawLevels.push_back(raw);
    fitted.widening.push_back(w);
  }
  widening = std::move(fitted);
  return true;
}

std::array<double, 2> centralInterval(const std::vector<double>& draws, double level, const IntervalWidening* widening) {
  return centralIntervalOfSorted(sortedDraws(draws), level, widening);
}

bool Interval::contains(double value, double level) const {
  if (std::isnan(value)) return false;
  if (level == 0.5) return value >= p25 && value <= p75;
  if (level == 0.9) return value >= p05 && value <= p95;
  return false;
}

Interval intervalOf(const std::vector<double>& draws, const IntervalWidening* widening) {
  const auto sorted = sortedDraws(draws);
  Interval interval;
  interval.draws = sorted.size();
  interval.median = quantileOfSorted(sorted, 0.5);
  const auto inner = centralIntervalOfSorted(sorted, 0.5, widening);
  const auto outer = centralIntervalOfSorted(sorted, 0.9, widening);
  interval.p25 = inner[0];
  interval.p75 = inner[1];
  interval.p05 = outer[0];
  interval.p95 = outer[1];
  return interval;
}

double containingLevel(const std::vector<double>& draws, double value, const IntervalWidening* widening) {
  if (widening == nullptr) {
    const double q = quantilePosition(draws, value);
    return std::isnan(q) ? kNaN : std::abs(2.0 * q - 1.0);
  }
  const auto sorted = sortedDraws(draws);
  if (sorted.empty() || std::isnan(value)) return kNaN;
  const auto inside = [&](double level) {
    const auto interval = centralIntervalOfSorted(sorted, level, widening);
    return value >= interval[0] && value <= interval[1];  // false for an empty interval (NaN)
  };
  if (!inside(1.0)) return 1.0;
  // The intervals are nested in the level: bisect for the smallest one holding the value.
  double low = 0.0;
  double high = 1.0;
  if (inside(low)) return 0.0;
  for (int iteration = 0; iteration < 40; ++iteration) {
    const double middle = 0.5 * (low + high);
    (inside(middle) ? high : low) = middle;
  }
  return high;
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
