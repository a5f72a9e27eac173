#include "conformal.hpp"

#include <fmt/format.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>

#include "vsd/core/interrupt.hpp"
#include "vsd/model/model.hpp"

namespace vsd::model {

namespace {

/// Scenes predicted at a time (bounds the memory of sampled futures).
constexpr std::size_t kChunk = 256;

/// Squared Mahalanobis distance of the true position of step k to its prediction.
double mahalanobis2(const Prediction& prediction, const vector::VectorizedScene& scene, std::size_t k) {
  const Vec2 r = scene.target[k] - prediction.mostLikely.positions[k];
  return r.dot(prediction.positionCovariance[k].inverse() * r);
}

/// The keys a held-out scene counts under: pooled ("") and its own label.
std::vector<std::string> keysOf(const vector::VectorizedScene& scene) {
  if (scene.label.empty()) return {std::string()};
  return {std::string(), scene.label};
}

/// Per label ("" = all): per step, the squared distances of the valid held-out positions.
using DistancesByLabel = std::map<std::string, std::vector<std::vector<double>>>;

void addDistances(DistancesByLabel& distances, const Prediction& prediction, const vector::VectorizedScene& scene) {
  const auto steps = prediction.positionCovariance.size();
  for (const auto& key : keysOf(scene)) {
    auto& per_step = distances[key];
    per_step.resize(steps);
    for (std::size_t k = 0; k < steps && k < scene.target.size(); ++k) {
      if (scene.targetValid[k]) per_step[k].push_back(mahalanobis2(prediction, scene, k));
    }
  }
}

PositionRegions fitRegions(const DistancesByLabel& distances, std::size_t scenes) {
  PositionRegions regions;
  regions.scenes = scenes;
  for (const auto& [label, per_step] : distances) {
    std::vector<std::array<double, kCoverageLevels.size()>> radii;
    for (const auto& values : per_step) {
      if (values.size() < kMinCalibrationScenes) break;  // too few at this step: the label stays uncalibrated
      std::array<double, kCoverageLevels.size()> radius{};
      for (std::size_t l = 0; l < kCoverageLevels.size(); ++l) {
        radius[l] = std::max(conformalQuantile(values, kCoverageLevels[l]), 1e-12);
        if (l > 0) radius[l] = std::max(radius[l], radius[l - 1]);
      }
      radii.push_back(radius);
    }
    if (!per_step.empty() && radii.size() == per_step.size()) regions.byLabel[label] = std::move(radii);
  }
  return regions;
}

/// Per label ("" = all), per metric: the held-out scenes' draws and references.
using HeldOutByLabel = std::map<std::string, std::vector<std::vector<HeldOutMetric>>>;

/// The references of a held-out scene: its stored metric where its dataset has it, else the
/// metric of its recorded future.
std::vector<double> references(const vector::VectorizedScene& scene, const std::vector<std::string>* stored,
                               const MetricBinding& metrics) {
  auto values = metrics.compute(scene, Trajectory{scene.target, {}});
  if (stored == nullptr) return values;
  for (std::size_t m = 0; m < metrics.names.size(); ++m) {
    const auto found = std::find(stored->begin(), stored->end(), metrics.names[m]);
    const auto index = static_cast<std::size_t>(found - stored->begin());
    if (found != stored->end() && index < scene.metrics.size()) values[m] = scene.metrics[index];
  }
  return values;
}

void addMetrics(HeldOutByLabel& held_out, const Prediction& prediction, const vector::VectorizedScene& scene,
                const std::vector<std::string>* stored, const MetricBinding& metrics) {
  const std::size_t count = metrics.names.size();
  const auto reference = references(scene, stored, metrics);
  auto draws = metricDraws(scene, prediction, metrics.compute, count);
  for (const auto& key : keysOf(scene)) {
    auto& per_metric = held_out[key];
    per_metric.resize(count);
    for (std::size_t m = 0; m < count; ++m) per_metric[m].push_back({draws[m], reference.at(m)});
  }
}

IntervalCalibration fitIntervals(const HeldOutByLabel& held_out, const MetricBinding& metrics) {
  IntervalCalibration calibration;
  for (const auto& [label, per_metric] : held_out) {
    for (std::size_t m = 0; m < per_metric.size(); ++m) {
      IntervalWidening widening;
      if (fitIntervalWidening(per_metric[m], widening)) calibration.byLabel[label][metrics.names[m]] = widening;
    }
  }
  return calibration;
}

std::string wideningText(const IntervalWidening& widening, double level) {
  const double w = widening.wideningAt(level);
  return w > 0.0 ? fmt::format(" widened by {:.3f} x (90 % width + {:.3g})", w, widening.floor) : "";
}

}  // namespace

std::string ConformalFit::report() const {
  std::string text;
  const auto pooled = metricIntervals.byLabel.find("");
  if (pooled == metricIntervals.byLabel.end()) return text;
  for (const auto& [metric, widening] : pooled->second) {
    text += fmt::format("  {:<16} {} held-out scenes: the 50 % interval is the draws' {:.0f} % interval{}, the 90 % "
                        "one their {:.0f} % interval{}\n",
                        metric, widening.scenes, 100.0 * widening.rawLevelAt(0.5), wideningText(widening, 0.5),
                        100.0 * widening.rawLevelAt(0.9), wideningText(widening, 0.9));
  }
  return text;
}

ConformalFit fitConformal(const Predictor& predictor, const std::vector<vector::VectorizedScene>& held_out,
                          const StoredMetricNames& stored, const MetricBinding* metrics, std::uint64_t seed) {
  PredictOptions options;
  options.samples = metrics != nullptr ? kCalibrationDraws : 0;
  options.seed = seed;
  DistancesByLabel distances;
  HeldOutByLabel metric_values;
  double inside = 0.0;
  double scored = 0.0;
  for (std::size_t first = 0; first < held_out.size(); first += kChunk) {
    throwIfInterrupted();
    const std::vector<vector::VectorizedScene> chunk(
        held_out.begin() + static_cast<std::ptrdiff_t>(first),
        held_out.begin() + static_cast<std::ptrdiff_t>(std::min(held_out.size(), first + kChunk)));
    const auto predictions = predictor.predictDistribution(chunk, options);
    for (std::size_t i = 0; i < chunk.size(); ++i) {
      if (!predictions[i].probabilistic()) continue;
      addDistances(distances, predictions[i], chunk[i]);
      const auto last = chunk[i].target.size() - 1;
      if (chunk[i].targetValid[last]) {
        inside += mahalanobis2(predictions[i], chunk[i], last) <= gaussianRegionRadius2(0.9) ? 1.0 : 0.0;
        scored += 1.0;
      }
      const auto scene_index = first + i;
      const auto* names = scene_index < stored.size() ? stored[scene_index].get() : nullptr;
      if (metrics != nullptr) addMetrics(metric_values, predictions[i], chunk[i], names, *metrics);
    }
  }
  ConformalFit fit;
  fit.positionRegions = fitRegions(distances, held_out.size());
  if (metrics != nullptr) fit.metricIntervals = fitIntervals(metric_values, *metrics);
  fit.gaussianCoverage90AtEnd = scored > 0.0 ? inside / scored : 0.0;
  return fit;
}

}  // namespace vsd::model
