#include "vsd/report/comparison.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace vsd::report {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Value at quantile q (0..1) of sorted values, linear interpolation.
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return kNaN;
  const double position = q * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const auto above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (position - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

double ratio(std::size_t numerator, std::size_t denominator) {
  return denominator == 0 ? kNaN : static_cast<double>(numerator) / static_cast<double>(denominator);
}

std::string failCell(int fails) { return fails < 0 ? "" : std::to_string(fails); }

void intervalCells(std::vector<std::string>& row, const MetricInterval* interval) {
  for (const double value : {interval ? interval->p05 : kNaN, interval ? interval->p25 : kNaN,
                             interval ? interval->median : kNaN, interval ? interval->p75 : kNaN,
                             interval ? interval->p95 : kNaN}) {
    row.push_back(interval && interval->draws > 0 ? formatNumber(value) : "");
  }
}
}  // namespace

Distribution describe(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  Distribution d;
  d.count = values.size();
  if (values.empty()) {
    d.mean = d.median = d.p90 = d.max = kNaN;
    return d;
  }
  std::sort(values.begin(), values.end());
  double sum = 0.0;
  for (double v : values) sum += v;
  d.mean = sum / static_cast<double>(values.size());
  d.median = quantile(values, 0.5);
  d.p90 = quantile(values, 0.9);
  d.max = values.back();
  return d;
}

namespace {

/// Coverage of the sampled futures' intervals for metric m (probabilistic models).
void calibrate(MetricStatistics& stats, const Comparison& comparison, std::size_t m) {
  std::vector<std::size_t> inside(kReliabilityLevels.size(), 0);
  double width_sum = 0.0;
  double median_error_sum = 0.0;
  std::size_t median_errors = 0;
  std::size_t inside50 = 0;
  std::size_t inside90 = 0;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok() || m >= scenario.intervals.size()) continue;
    const auto& interval = scenario.intervals[m];
    if (interval.draws == 0 || std::isnan(interval.containingLevel)) continue;
    ++stats.intervalPairs;
    const double level = interval.containingLevel;  // smallest central level holding it
    for (std::size_t l = 0; l < kReliabilityLevels.size(); ++l) inside[l] += level <= kReliabilityLevels[l] ? 1 : 0;
    inside50 += level <= 0.5 ? 1 : 0;
    inside90 += level <= 0.9 ? 1 : 0;
    if (std::isfinite(interval.p95 - interval.p05)) width_sum += interval.p95 - interval.p05;
    const double median_error = std::abs(interval.median - scenario.reference.at(m));
    if (std::isfinite(median_error)) {
      median_error_sum += median_error;
      ++median_errors;
    }
  }
  if (stats.intervalPairs == 0) return;
  const auto n = static_cast<double>(stats.intervalPairs);
  stats.coverage50 = static_cast<double>(inside50) / n;
  stats.coverage90 = static_cast<double>(inside90) / n;
  stats.meanWidth90 = width_sum / n;
  stats.medianDrawMae = median_errors == 0 ? kNaN : median_error_sum / static_cast<double>(median_errors);
  for (const auto count : inside) stats.reliability.push_back(static_cast<double>(count) / n);
}

/// Which verdicts of criterion c the sampled futures agree on, and how often they are right.
void judgeConfidence(CriterionStatistics& stats, const Comparison& comparison, std::size_t c) {
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok() || c >= scenario.failShare.size()) continue;
    const double share = scenario.failShare[c];
    const int reference = scenario.referenceFails.at(c);
    if (std::isnan(share) || reference < 0) continue;
    if (share >= comparison.confidence || share <= 1.0 - comparison.confidence) {
      ++stats.confident;
      stats.confidentWrong += (share >= comparison.confidence) != (reference == 1) ? 1 : 0;
    } else {
      ++stats.uncertain;
      stats.uncertainPointWrong += scenario.predictedFails.at(c) >= 0 && scenario.predictedFails.at(c) != reference ? 1 : 0;
    }
  }
}

/// Errors of the predicted metric m against the reference (simulated or recorded) values.
MetricStatistics metricStatistics(const Comparison& comparison, std::size_t m) {
  MetricStatistics stats;
  stats.name = comparison.metricNames[m];
  stats.unit = m < comparison.metricUnits.size() ? comparison.metricUnits[m] : "";
  std::vector<double> absolute_errors;
  double error_sum = 0.0;
  double floor_sum = 0.0;
  std::size_t floor_pairs = 0;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) continue;
    const double predicted = scenario.predicted.at(m);
    const double reference = scenario.reference.at(m);
    if (std::isfinite(predicted) && std::isfinite(reference)) {
      absolute_errors.push_back(std::abs(predicted - reference));
      error_sum += predicted - reference;
      if (m < scenario.fromReferencePositions.size() && std::isfinite(scenario.fromReferencePositions[m])) {
        floor_sum += std::abs(scenario.fromReferencePositions[m] - reference);
        ++floor_pairs;
      }
    } else if (std::isinf(predicted) && std::isinf(reference) && (predicted > 0) == (reference > 0)) {
      ++stats.bothInfinite;
    } else if (!(std::isnan(predicted) && std::isnan(reference))) {
      ++stats.finitenessMismatch;
    }
  }
  stats.pairs = absolute_errors.size();
  if (stats.pairs > 0) {
    double sum = 0.0;
    for (double e : absolute_errors) sum += e;
    stats.mae = sum / static_cast<double>(stats.pairs);
    stats.bias = error_sum / static_cast<double>(stats.pairs);
    std::sort(absolute_errors.begin(), absolute_errors.end());
    stats.medianAbsoluteError = quantile(absolute_errors, 0.5);
    stats.p90AbsoluteError = quantile(absolute_errors, 0.9);
  } else {
    stats.mae = stats.bias = stats.medianAbsoluteError = stats.p90AbsoluteError = kNaN;
  }
  if (floor_pairs > 0) stats.floorMae = floor_sum / static_cast<double>(floor_pairs);
  calibrate(stats, comparison, m);
  return stats;
}

/// How often the predicted verdicts of criterion c agree with the reference ones.
CriterionStatistics criterionStatistics(const Comparison& comparison, std::size_t c) {
  CriterionStatistics stats;
  stats.name = comparison.criteria[c].name;
  stats.expression = comparison.criteria[c].expression;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) continue;
    const int predicted = scenario.predictedFails.at(c);
    const int reference = scenario.referenceFails.at(c);
    if (predicted < 0 || reference < 0) {
      ++stats.undefined;
    } else if (predicted && reference) {
      ++stats.bothFail;
    } else if (predicted) {
      ++stats.falseAlarm;
    } else if (reference) {
      ++stats.missed;
    } else {
      ++stats.bothPass;
    }
  }
  judgeConfidence(stats, comparison, c);
  return stats;
}

}  // namespace

double CriterionStatistics::agreement() const { return ratio(bothFail + bothPass, bothFail + bothPass + falseAlarm + missed); }
double CriterionStatistics::recall() const { return ratio(bothFail, bothFail + missed); }

ComparisonStatistics computeStatistics(const Comparison& comparison) {
  ComparisonStatistics s;
  std::vector<double> ades;
  std::vector<double> fdes;
  for (const auto& scenario : comparison.scenarios) {
    if (!scenario.ok()) {
      ++s.failed;
      continue;
    }
    ++s.compared;
    ades.push_back(scenario.ade);
    fdes.push_back(scenario.fde);
  }
  s.ade = describe(ades);
  s.fde = describe(fdes);
  for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) s.metrics.push_back(metricStatistics(comparison, m));
  for (std::size_t c = 0; c < comparison.criteria.size(); ++c) s.criteria.push_back(criterionStatistics(comparison, c));
  return s;
}

void writeComparisonCsv(const Comparison& comparison, const std::filesystem::path& path) {
  AtomicOutput output(path);
  {
    std::ofstream stream(output.tempPath());
    if (!stream) throw IoError(path.string() + ": cannot create the file");
    CsvWriter csv(stream);
    std::vector<std::string> header = {"sample", "label", "status", "failure"};
    for (const auto& name : comparison.inputNames) header.push_back(name);
    header.insert(header.end(), {columnWithUnit("ade", "m"), columnWithUnit("fde", "m")});
    const bool intervals = comparison.draws > 0;
    for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
      // Every column of a quantity carries its unit (the same convention as ade_m).
      const auto& name = comparison.metricNames[m];
      const std::string unit = m < comparison.metricUnits.size() ? comparison.metricUnits[m] : std::string();
      header.push_back(columnWithUnit(name + "_predicted", unit));
      header.push_back(columnWithUnit(name + "_" + comparison.referenceName, unit));
      header.push_back(columnWithUnit(name + "_error", unit));
      if (!intervals) continue;
      for (const char* q : {"_p05", "_p25", "_median", "_p75", "_p95"}) header.push_back(columnWithUnit(name + q, unit));
    }
    for (const auto& criterion : comparison.criteria) {
      header.push_back(criterion.name + "_predicted_fail");
      header.push_back(criterion.name + "_" + comparison.referenceName + "_fail");
      if (intervals) header.push_back(criterion.name + "_fail_share");
    }
    csv.writeRow(header);
    for (const auto& scenario : comparison.scenarios) {
      std::vector<std::string> row = {std::to_string(scenario.sample), scenario.label, scenario.ok() ? "ok" : "failed",
                                      scenario.failure};
      for (std::size_t i = 0; i < comparison.inputNames.size(); ++i) {
        row.push_back(i < scenario.inputs.size() ? formatNumber(scenario.inputs[i]) : "");
      }
      const bool ok = scenario.ok();
      row.push_back(ok ? formatNumber(scenario.ade) : "");
      row.push_back(ok ? formatNumber(scenario.fde) : "");
      for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
        const double predicted = ok ? scenario.predicted.at(m) : kNaN;
        const double reference = ok ? scenario.reference.at(m) : kNaN;
        row.push_back(formatNumber(predicted));
        row.push_back(formatNumber(reference));
        row.push_back(std::isfinite(predicted) && std::isfinite(reference) ? formatNumber(predicted - reference) : "");
        if (intervals) intervalCells(row, ok && m < scenario.intervals.size() ? &scenario.intervals[m] : nullptr);
      }
      for (std::size_t c = 0; c < comparison.criteria.size(); ++c) {
        row.push_back(ok ? failCell(scenario.predictedFails.at(c)) : "");
        row.push_back(ok ? failCell(scenario.referenceFails.at(c)) : "");
        if (intervals) {
          const bool known = ok && c < scenario.failShare.size() && !std::isnan(scenario.failShare[c]);
          row.push_back(known ? formatNumber(scenario.failShare[c]) : "");
        }
      }
      csv.writeRow(row);
    }
    stream.flush();
    if (!stream) throw IoError(path.string() + ": write failed (disk full?)");
  }
  output.commit();
}

std::string textSummary(const Comparison& comparison, const ComparisonStatistics& s) {
  std::ostringstream out;
  out << fmt::format("{}: {} compared, {} without a {} reference\n", comparison.title, s.compared, s.failed,
                     comparison.referenceName);
  for (const auto& warning : comparison.warnings) out << "  warning: " << warning << "\n";
  out << fmt::format("  ADE  mean {:.3f} m, median {:.3f} m, p90 {:.3f} m, max {:.3f} m\n", s.ade.mean, s.ade.median,
                     s.ade.p90, s.ade.max);
  out << fmt::format("  FDE  mean {:.3f} m, median {:.3f} m, p90 {:.3f} m, max {:.3f} m\n", s.fde.mean, s.fde.median,
                     s.fde.p90, s.fde.max);
  for (const auto& m : s.metrics) {
    out << fmt::format("  {:<16} MAE {:.3f} {}, median |error| {:.3f} {}, bias {:+.3f} {} ({} pairs", m.name, m.mae,
                       m.unit, m.medianAbsoluteError, m.unit, m.bias, m.unit, m.pairs);
    if (m.bothInfinite) out << fmt::format(", {} both infinite", m.bothInfinite);
    if (m.finitenessMismatch) out << fmt::format(", {} finite on one side only", m.finitenessMismatch);
    if (m.floorMae) out << fmt::format("; from {} positions {:.3f} {}", comparison.referenceName, *m.floorMae, m.unit);
    out << ")\n";
    if (m.intervalPairs > 0) {
      out << fmt::format("  {:<16} intervals of {} sampled futures: {} value in the 50 % interval {:.1f} %, in the "
                         "90 % interval {:.1f} % (mean width {:.3f} {}); their median: MAE {:.3f} {}\n",
                         "", comparison.draws, comparison.referenceName, 100.0 * m.coverage50, 100.0 * m.coverage90,
                         m.meanWidth90, m.unit, m.medianDrawMae, m.unit);
    }
  }
  for (const auto& c : s.criteria) {
    out << fmt::format("  criterion {} ({}): both fail {}, false alarms {}, missed {}, both pass {}", c.name,
                       c.expression, c.bothFail, c.falseAlarm, c.missed, c.bothPass);
    if (c.undefined) out << fmt::format(", undefined {}", c.undefined);
    out << fmt::format(" -> agreement {:.1f} %\n", 100.0 * c.agreement());
    if (c.confident + c.uncertain > 0) {
      out << fmt::format("  {:<16} confident verdicts (>= {:.0f} % of the futures agree) {}, of them wrong {}; "
                         "uncertain {} (the most likely future wrong in {})\n",
                         "", 100.0 * comparison.confidence, c.confident, c.confidentWrong, c.uncertain,
                         c.uncertainPointWrong);
    }
  }
  if (!comparison.timings.empty()) {
    out << "  time:";
    for (std::size_t i = 0; i < comparison.timings.size(); ++i) {
      out << fmt::format("{} {} {:.2f} s", i ? "," : "", comparison.timings[i].first, comparison.timings[i].second);
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace vsd::report
