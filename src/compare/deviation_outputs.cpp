#include "deviation_outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "vsd/core/csv.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/model/intervals.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace vsd::compare {

namespace {

/// Rows of the flagged list in the report (every scene is in deviations.csv).
constexpr std::size_t kMaxListed = 200;
/// Points of a drawn region ellipse.
constexpr int kEllipsePoints = 24;

std::string cell(double value, int decimals = 2) {
  if (std::isnan(value)) return "-";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return fmt::format("{:.{}f}", value, decimals);
}

std::string pCell(double p) { return std::isnan(p) ? "-" : fmt::format("{:.3g}", p); }

/// Mean and standard deviation of feature `f` over `scenes` (finite values only).
std::pair<double, double> moments(const std::vector<const SceneDeviation*>& scenes, std::size_t f) {
  double sum = 0.0;
  double square = 0.0;
  double n = 0.0;
  for (const auto* scene : scenes) {
    if (f >= scene->features.size() || !std::isfinite(scene->features[f])) continue;
    sum += scene->features[f];
    square += scene->features[f] * scene->features[f];
    n += 1.0;
  }
  if (n == 0.0) return {std::nan(""), std::nan("")};
  const double mean = sum / n;
  return {mean, std::sqrt(std::max(square / n - mean * mean, 0.0))};
}

/// The two features whose mean in `group` differs most from all scored scenes' (in standard
/// deviations of all): "v0_ego 14.1 vs 12.0 m/s (+1.2 sd)".
std::string distinguishingFeatures(const DeviationResult& result, const std::vector<const SceneDeviation*>& group,
                                   const std::vector<const SceneDeviation*>& all) {
  std::vector<std::pair<double, std::string>> ranked;
  for (std::size_t f = 0; f < result.featureNames.size(); ++f) {
    const auto [mean_all, sd_all] = moments(all, f);
    const auto [mean_group, sd_group] = moments(group, f);
    if (!(sd_all > 0.0) || std::isnan(mean_group)) continue;
    const double z = (mean_group - mean_all) / sd_all;
    const std::string unit = result.featureUnits[f].empty() ? "" : " " + result.featureUnits[f];
    ranked.emplace_back(std::abs(z), fmt::format("{} {:.3g} vs {:.3g}{} ({:+.1f} sd)", result.featureNames[f],
                                                 mean_group, mean_all, unit, z));
  }
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string text;
  for (std::size_t i = 0; i < std::min<std::size_t>(2, ranked.size()); ++i) text += (i ? "; " : "") + ranked[i].second;
  return text.empty() ? "-" : text;
}

report::TextTable groupTable(const DeviationSummary& summary) {
  const auto& result = summary.result;
  std::vector<const SceneDeviation*> scored;
  for (const auto& scene : result.scenes) {
    if (scene.status == SceneStatus::Scored) scored.push_back(&scene);
  }
  std::map<std::string, std::vector<const SceneDeviation*>> groups;
  for (const auto i : summary.ranked) groups[result.scenes[i].group].push_back(&result.scenes[i]);
  std::vector<std::pair<std::string, std::vector<const SceneDeviation*>>> ordered(groups.begin(), groups.end());
  std::stable_sort(ordered.begin(), ordered.end(), [](const auto& a, const auto& b) { return a.second.size() > b.second.size(); });
  report::TextTable table;
  table.id = "groups";
  table.heading = "What deviates";
  table.intro = "Flagged scenes grouped by label, the axis along which the recorded path departs furthest from the "
                "predicted one (in predicted standard deviations), and the metric with the smallest tail "
                "probability; the features that set the group apart from all scored scenes (mean in the group vs "
                "in all, in standard deviations of all).";
  table.header = {"group", "scenes", "share of scored", "median p", "median |along| (m)", "median |across| (m)",
                  "scene features"};
  for (const auto& [name, members] : ordered) {
    std::vector<double> p, along, across;
    for (const auto* scene : members) {
      p.push_back(scene->p);
      along.push_back(std::abs(scene->longitudinal));
      across.push_back(std::abs(scene->lateral));
    }
    table.rows.push_back({name, std::to_string(members.size()),
                          fmt::format("{:.1f} %", 100.0 * static_cast<double>(members.size()) /
                                                      static_cast<double>(std::max<std::size_t>(scored.size(), 1))),
                          pCell(upperMedian(p)), cell(upperMedian(along)), cell(upperMedian(across)),
                          distinguishingFeatures(result, members, scored)});
  }
  return table;
}

report::SceneDrawing drawScene(const DeviationResult& result, const SceneDeviation& row, vector::VectorizedScene scene,
                               std::size_t rank) {
  std::vector<vector::TrajectoryOverlay> overlays = {{"predicted (most likely)", {}, "#e31a1c", true}};
  overlays[0].points.push_back(scene.egoInitialState().position());
  for (const auto& p : row.predicted) overlays[0].points.push_back(p);
  for (std::size_t k = 0; k < row.region90.size() && k < row.predicted.size(); ++k) {
    if (k % 2 == 0 && k + 1 != row.region90.size()) continue;  // every other step: readable
    const auto& [a, b, angle] = row.region90[k];
    vector::TrajectoryOverlay ellipse{overlays.size() == 1 ? "calibrated 90 % region" : "", {}, "#fb9a99", false};
    for (int i = 0; i <= kEllipsePoints; ++i) {
      const double t = 2.0 * M_PI * i / kEllipsePoints;
      const Vec2 local(a * std::cos(t), b * std::sin(t));
      ellipse.points.push_back(row.predicted[k] + Vec2(local.x() * std::cos(angle) - local.y() * std::sin(angle),
                                                       local.x() * std::sin(angle) + local.y() * std::cos(angle)));
    }
    overlays.push_back(std::move(ellipse));
  }
  const auto& tail = row.metrics.at(row.worstMetric);
  const std::string what = row.pathWorst
                               ? fmt::format("path: mean region excess {}", cell(row.regionMeanExcess, 1))
                               : fmt::format("{} {}", result.metricNames[row.worstMetric], cell(tail.recorded));
  const std::string title = fmt::format("#{} {} sample {}: p {:.3g} ({})", rank, row.label, row.sample, row.p, what);
  return {row.sample, row.reason,
          vector::renderSceneSvg(scene, overlays, title, 560, "recorded future", /*focus_margin_m=*/8.0)};
}

report::TextTable flaggedList(const DeviationSummary& summary) {
  const auto& result = summary.result;
  report::TextTable table;
  table.id = "flagged";
  table.heading = fmt::format("Flagged scenes ({})", summary.ranked.size());
  table.intro = summary.ranked.size() > kMaxListed
                    ? fmt::format("The {} most surprising; every scene is in deviations.csv.", kMaxListed)
                    : "Most surprising first; every scene is in deviations.csv.";
  table.header = {"rank", "source", "sample", "label", "p", "group", "why"};
  for (std::size_t r = 0; r < summary.ranked.size() && r < kMaxListed; ++r) {
    const auto& s = result.scenes[summary.ranked[r]];
    table.rows.push_back({std::to_string(r + 1), s.source, std::to_string(s.sample), s.label, pCell(s.p), s.group, s.reason});
  }
  return table;
}

report::TextTable apartList(const DeviationResult& result, SceneStatus status) {
  report::TextTable table;
  const bool ood = status == SceneStatus::OutOfDistribution;
  table.id = ood ? "out-of-distribution" : "not-scored";
  table.heading = ood ? "Out of the model's distribution" : "Not scored";
  table.intro = ood ? "Scenes of labels the model never trained on: its predictions there are extrapolation, so they "
                      "are not judged as behavioural deviations (test such scenes, then retrain)."
                    : "Scenes without a recorded future or without a defined metric.";
  table.header = {"source", "sample", "label", "reason"};
  for (const auto& s : result.scenes) {
    if (s.status != status) continue;
    if (table.rows.size() == kMaxListed) break;
    table.rows.push_back({s.source, std::to_string(s.sample), s.label, s.reason});
  }
  return table;
}

/// How the report's p-values were computed.
std::string pValueNote(const DeviationResult& result) {
  if (result.calibrationRuns > 0) {
    return fmt::format(
        "Metrics scored: {}, and the path. p-values are conformal ranks among {} clean calibration runs the model "
        "never trained on (per label): a metric's score is its distance from the most likely future's value, the "
        "path's its squared distance from the most likely future over the calibrated 90 % region's, averaged over "
        "the steps; p = (1 + runs scoring at least as high) / (n + 1). A metric's 90 % interval is the most likely "
        "value +- the runs' 90 % score. A scene's p combines them by Simes' rule.",
        fmt::join(result.metricNames, ", "), result.calibrationRuns);
  }
  return fmt::format(
      "Metrics scored: {}. Per metric, p = 1 - the smallest calibrated central interval of the {} sampled futures' "
      "metric holding the recorded value (no smaller than the calibration resolves: 0.01, or 1 / (n + 1) for n "
      "held-out scenes; not scored where the recorded value or the draws' 5-95 % range is infinite); a scene's p "
      "combines them by Simes' rule.",
      fmt::join(result.metricNames, ", "), model::kCalibrationDraws);
}

}  // namespace

std::vector<std::string> csvHeader(const DeviationResult& result) {
  std::vector<std::string> header = {"source", "row", "sample", "label", "status", "p", "flagged", "rank", "group",
                                     "worst_metric", "axis", "region_excess_90", "region_mean_excess_90", "path_p",
                                     columnWithUnit("region_time", "s"),
                                     columnWithUnit("along", "m"), columnWithUnit("across", "m")};
  for (std::size_t m = 0; m < result.metricNames.size(); ++m) {
    const auto& name = result.metricNames[m];
    const auto& unit = result.metricUnits[m];
    for (const char* part : {"_recorded", "_median", "_most_likely", "_p05", "_p95"}) header.push_back(columnWithUnit(name + part, unit));
    header.push_back(name + "_p");
  }
  for (std::size_t f = 0; f < result.featureNames.size(); ++f) {
    header.push_back(columnWithUnit(result.featureNames[f], result.featureUnits[f]));
  }
  header.push_back("reason");
  return header;
}

std::vector<std::string> csvRow(const DeviationResult& result, const SceneDeviation& s, std::size_t rank) {
  const bool scored = s.status == SceneStatus::Scored;
  std::vector<std::string> row = {s.source, std::to_string(s.row), std::to_string(s.sample), s.label,
                                  statusName(s.status), formatNumber(s.p), s.flagged ? "1" : "0",
                                  rank ? std::to_string(rank) : "", s.group,
                                  scored ? result.metricNames[s.worstMetric] : "", s.axis, formatNumber(s.regionExcess),
                                  formatNumber(s.regionMeanExcess), formatNumber(s.pathP),
                                  scored ? formatNumber(result.step * s.regionStep) : "",
                                  scored ? formatNumber(s.longitudinal) : "", scored ? formatNumber(s.lateral) : ""};
  for (std::size_t m = 0; m < result.metricNames.size(); ++m) {
    const MetricTail tail = m < s.metrics.size() ? s.metrics[m] : MetricTail{};
    for (const double v : {tail.recorded, tail.median, tail.mostLikely, tail.p05, tail.p95, tail.p}) row.push_back(formatNumber(v));
  }
  for (std::size_t f = 0; f < result.featureNames.size(); ++f) {
    row.push_back(f < s.features.size() ? formatNumber(s.features[f]) : "");
  }
  row.push_back(s.reason);
  return row;
}

report::DeviationReport buildReport(const DeviationSummary& summary, const std::vector<vector::VectorizedScene>& drawn_scenes,
                                    std::vector<std::pair<std::string, std::string>> provenance) {
  const auto& result = summary.result;
  report::DeviationReport out;
  out.level = result.level;
  const std::size_t scored = summary.scored();
  out.title = fmt::format("{} scenes at level {:g}", result.scenes.size(), result.level);
  out.summary.push_back(fmt::format(
      "{} of {} scored scenes ({:.1f} %) flagged: their recorded Ego behaviour has a tail probability below {:g} "
      "under the model's calibrated prediction. On scenes like {}, at most about {:.0f} % are flagged by chance.",
      summary.ranked.size(), scored, scored ? 100.0 * static_cast<double>(summary.ranked.size()) / static_cast<double>(scored) : 0.0,
      result.level, result.calibrationRuns > 0 ? "the calibration runs" : "the model's test data", 100.0 * result.level));
  out.warnings = summary.warnings;
  if (summary.outOfDistribution() > 0) {
    out.warnings.push_back(fmt::format("{} scenes are of labels the model never trained on: listed apart, not scored.",
                                       summary.outOfDistribution()));
  }
  out.notes.push_back(pValueNote(result));
  for (const auto& scene : result.scenes) {
    if (scene.status == SceneStatus::Scored) out.pValues.push_back(scene.p);
  }
  out.groups.push_back(groupTable(summary));
  for (std::size_t r = 0; r < drawn_scenes.size(); ++r) {
    out.drawings.push_back(drawScene(result, result.scenes[summary.ranked[r]], drawn_scenes[r], r + 1));
  }
  out.lists.push_back(flaggedList(summary));
  out.lists.push_back(apartList(result, SceneStatus::OutOfDistribution));
  out.lists.push_back(apartList(result, SceneStatus::NotScored));
  out.provenance = std::move(provenance);
  return out;
}

}  // namespace vsd::compare
