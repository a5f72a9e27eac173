#pragma once
// Intervals from draws of a predictive distribution (e.g. a metric computed on every
// sampled future of a scene).

#include <array>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace vsd::model {

/// The q-quantile (0 <= q <= 1) of draws at the Weibull plotting position q (n + 1)
/// (Hyndman & Fan type 6), clamped to the smallest/largest draw: for exchangeable draws
/// the expected coverage of [quantile(a), quantile(b)] is b - a for every n, where the
/// usual (n - 1) interpolation covers less (84.5 % instead of 90 % for n = 32).
/// NaN draws are ignored; +-inf take part in the order. NaN if no draw is left.
double sampleQuantile(std::vector<double> draws, double q);

/// Split-conformal calibration of one metric's intervals over sampled futures, fitted on
/// held-out scenes whose reference value y is known (README "Calibration"). The calibrated
/// central interval of level L is the draws' central interval of another level L' = r(L)
/// (the quantile recalibration of Kuleshov et al. 2018: r(L) < L narrows over-cautious
/// intervals, r(L) > L widens over-confident ones), and where even all draws' range
/// [min, max] is too narrow (r(L) = 1), that range widened by w(L) u on both sides, u =
/// (q95 - q05 of the draws) + floor (wider where the futures spread more). r(L) is the
/// ceil((n + 1) L)-th smallest "smallest raw level holding y" of the n held-out scenes,
/// w(L) the same order statistic of how far outside the range y lies (in units of u), so
/// that at least L of new scenes exchangeable with them fall inside. Both are
/// non-decreasing in L: the intervals of increasing levels are nested.
struct IntervalWidening {
  std::vector<double> levels;     ///< ascending, in (0, 1)
  std::vector<double> rawLevels;  ///< r per level, in [0, 1], non-decreasing
  std::vector<double> widening;   ///< w per level (units of u), >= 0, non-decreasing; 0 while r < 1
  double floor = 0.0;             ///< metric unit, > 0: the median 90 % width of the held-out draws (or 1e-9)
  std::size_t scenes = 0;         ///< held-out scenes it was fitted on
  /// r and w at any level in [0, 1]: linear between the fitted levels, from (0, 0) at L = 0,
  /// constant above the last.
  double rawLevelAt(double level) const;
  double wideningAt(double level) const;
};

/// Sampled futures per held-out scene from which metric intervals are calibrated (the
/// default `--futures` of compare and `mae.draws` of experiment). Raw levels depend on
/// the number of draws: a calibrated interval holds its level for this many draws.
inline constexpr int kCalibrationDraws = 32;

/// Levels the metric calibration is fitted at (the reliability diagram's range).
inline constexpr std::array<double, 12> kCalibratedLevels = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6,
                                                             0.7, 0.8, 0.9, 0.95, 0.98, 0.99};

/// The metric calibration of a model: per scene label (the functional scenario or map it
/// came from) and pooled over all labels (label ""), per metric name.
struct IntervalCalibration {
  std::map<std::string, std::map<std::string, IntervalWidening>> byLabel;
  /// The label's own widening of `metric` when fitted, else the pooled one, else nullptr
  /// (an uncalibrated metric: plain intervals of the draws).
  const IntervalWidening* find(const std::string& label, const std::string& metric) const;
  bool empty() const { return byLabel.empty(); }
};

/// One held-out scene of a metric: its draws and its reference value.
struct HeldOutMetric {
  std::vector<double> draws;
  double reference = 0.0;
};

/// The split-conformal quantile of held-out scores: the ceil((n + 1) level)-th smallest
/// value (the largest when that exceeds n). NaN for no values.
double conformalQuantile(std::vector<double> values, double level);

/// Held-out scenes a widening needs at least (fewer: the metric stays uncalibrated).
inline constexpr std::size_t kMinCalibrationScenes = 20;
/// Fits the widening of one metric on held-out scenes (those with a finite reference and
/// finite 5 % / 95 % quantiles of their draws). False, `widening` untouched, with fewer
/// than kMinCalibrationScenes of them.
bool fitIntervalWidening(const std::vector<HeldOutMetric>& scenes, IntervalWidening& widening);

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
/// `widening` (optional) calibrates the 50 % and 90 % intervals; the median stays the draws'.
Interval intervalOf(const std::vector<double>& draws, const IntervalWidening* widening = nullptr);

/// The central interval of level L (0..1) of the draws, widened when `widening` is given.
/// An interval narrowed past its centre is empty: {NaN, NaN}.
std::array<double, 2> centralInterval(const std::vector<double>& draws, double level,
                                      const IntervalWidening* widening = nullptr);

/// The smallest level L in [0, 1] whose central interval (widened when given) holds
/// `value`: the reference lies in the interval of level L exactly when this is <= L (the
/// reliability diagram). 1 when not even the level-1 interval holds it; NaN if `value` or
/// every draw is NaN. Without widening it is |2 quantilePosition - 1|.
double containingLevel(const std::vector<double>& draws, double value, const IntervalWidening* widening = nullptr);

/// Where `value` lies in the draws, as the q with sampleQuantile(draws, q) == value
/// (linear between draws; 0 below the smallest, 1 above the largest draw). `value` lies in
/// the central interval of level L, [quantile((1 - L)/2), quantile((1 + L)/2)], exactly
/// when |2q - 1| <= L: one number per (scene, metric) gives the coverage of every level
/// (the reliability diagram). NaN if `value` or every draw is NaN.
double quantilePosition(std::vector<double> draws, double value);

}  // namespace vsd::model
