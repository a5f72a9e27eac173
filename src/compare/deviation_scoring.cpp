// Scoring recorded scenes against a calibrated probabilistic model (compare/deviations.hpp).
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>

#include "vsd/compare/deviations.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/intervals.hpp"
#include "vsd/model/predictor.hpp"
#include "vsd/pipeline/scenes.hpp"

namespace vsd::compare {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Index of the 90 % level in model::kCoverageLevels.
constexpr std::size_t kRegion90 = 1;
static_assert(model::kCoverageLevels[kRegion90] == 0.9, "the 90 % region is the second coverage level");

/// Simes' combination of p-values: min over k of M p_(k) / k (NaN ones left out).
double simes(std::vector<double> p) {
  p.erase(std::remove_if(p.begin(), p.end(), [](double v) { return std::isnan(v); }), p.end());
  if (p.empty()) return kNaN;
  std::sort(p.begin(), p.end());
  const double m = static_cast<double>(p.size());
  double combined = 1.0;
  for (std::size_t k = 0; k < p.size(); ++k) combined = std::min(combined, m * p[k] / static_cast<double>(k + 1));
  return combined;
}

/// The scene's p from its metrics' and its path's (Simes), and which of them is smallest.
void combine(SceneDeviation& row) {
  std::vector<double> p = {row.pathP};
  for (const auto& tail : row.metrics) p.push_back(tail.p);
  row.p = simes(p);
  row.worstMetric = 0;
  for (std::size_t m = 0; m < row.metrics.size(); ++m) {
    const double pm = row.metrics[m].p;
    if (!std::isnan(pm) && (std::isnan(row.metrics[row.worstMetric].p) || pm < row.metrics[row.worstMetric].p)) {
      row.worstMetric = m;
    }
  }
  const double worst = row.metrics.empty() ? kNaN : row.metrics[row.worstMetric].p;
  row.pathWorst = !std::isnan(row.pathP) && !(worst <= row.pathP);
}

/// A metric's conformal score: how far the recorded value is from the most likely future's.
/// 0 where both are the same infinity; +inf where only one is finite (e.g. a recorded time to
/// collision where the most likely future never closes in: as surprising as it gets); NaN
/// where either is NaN.
double metricScore(const MetricTail& tail) {
  if (std::isnan(tail.recorded) || std::isnan(tail.mostLikely)) return kNaN;
  if (tail.recorded == tail.mostLikely) return 0.0;
  if (!std::isfinite(tail.recorded) || !std::isfinite(tail.mostLikely)) return std::numeric_limits<double>::infinity();
  return std::abs(tail.recorded - tail.mostLikely);
}

/// Whether calibration runs can rank a scene: one the model's calibration scored, or one it
/// could not (no metric defined) whose path has a region excess.
bool rankable(const SceneDeviation& scene) {
  if (scene.status == SceneStatus::Scored) return true;
  return scene.status == SceneStatus::NotScored && !std::isnan(scene.regionMeanExcess);
}

/// (1 + calibration scores >= score) / (n + 1): the split-conformal p of `score` among the
/// sorted `scores`; NaN for a NaN score or no scores.
double conformalP(const std::vector<double>& scores, double score) {
  if (std::isnan(score) || scores.empty()) return kNaN;
  const auto at_least = scores.end() - std::lower_bound(scores.begin(), scores.end(), score);
  return static_cast<double>(1 + at_least) / static_cast<double>(scores.size() + 1);
}

/// The conformal 90 % bound of the sorted `scores`: the ceil(0.9 (n + 1))-th smallest
/// (infinite when n is too small to give one).
double conformalBound90(const std::vector<double>& scores) {
  const auto rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(scores.size() + 1)));
  return rank <= scores.size() ? scores[rank - 1] : std::numeric_limits<double>::infinity();
}

/// 1 - the smallest calibrated level holding `value`, no smaller than the smallest tail the
/// calibration resolves: the highest level it was fitted at, and no more than n / (n + 1) of
/// its n held-out scenes (beyond, a conformal interval is their largest score, which holds a
/// new scene with probability n / (n + 1) only). NaN where the calibration does not hold:
/// a non-finite recorded value or 5 % / 95 % draw (such scenes were left out of its fit).
double tailProbability(const std::vector<double>& draws, double value, const model::IntervalWidening* widening) {
  if (!std::isfinite(value) || widening == nullptr) return kNaN;
  const double q05 = model::sampleQuantile(draws, 0.05);
  const double q95 = model::sampleQuantile(draws, 0.95);
  if (!std::isfinite(q05) || !std::isfinite(q95)) return kNaN;
  const double n = static_cast<double>(widening->scenes);
  const double floor = std::max(1.0 - widening->levels.back(), 1.0 / (n + 1.0));
  return std::max(1.0 - model::containingLevel(draws, value, widening), floor);
}

/// The semi-axes (a >= b, m) and the angle of a (rad) of {r : r' S^-1 r <= r2}.
std::array<double, 3> ellipseOf(const Eigen::Matrix2d& covariance, double r2) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(covariance);
  const auto values = solver.eigenvalues();  // ascending
  const Eigen::Vector2d major = solver.eigenvectors().col(1);
  return {std::sqrt(std::max(values(1), 0.0) * r2), std::sqrt(std::max(values(0), 0.0) * r2),
          std::atan2(major.y(), major.x())};
}

/// The predicted heading at step k: the model's state where it has one, else the direction
/// from the previous predicted position (the Ego's start for k = 0).
double predictedHeading(const model::Prediction& prediction, const vector::VectorizedScene& scene, std::size_t k) {
  const auto& states = prediction.mostLikely.states;
  if (k < states.size()) return states[k].heading;
  const auto& positions = prediction.mostLikely.positions;
  const Vec2 from = k == 0 ? scene.egoInitialState().position() : positions[k - 1];
  const Vec2 d = positions[k] - from;
  return d.norm() > 1e-6 ? std::atan2(d.y(), d.x()) : scene.egoInitialState().heading;
}

/// Where the recorded path leaves its calibrated 90 % region furthest, split along and
/// across the predicted heading, and its mean excess over the steps; the region ellipses for
/// drawing.
void scorePath(SceneDeviation& row, const model::Prediction& prediction, const vector::VectorizedScene& scene) {
  const std::size_t steps = std::min(prediction.positionCovariance.size(), scene.target.size());
  double worst = -1.0;
  double sum = 0.0;
  double counted = 0.0;
  for (std::size_t k = 0; k < steps; ++k) {
    const auto& covariance = prediction.positionCovariance[k];
    const double r2 = prediction.regionRadius2[k][kRegion90];
    row.region90.push_back(ellipseOf(covariance, r2));
    if (!scene.targetValid[k]) continue;
    const Vec2 r = scene.target[k] - prediction.mostLikely.positions[k];
    const double d2 = r.dot(covariance.inverse() * r);
    sum += d2 / r2;
    counted += 1.0;
    if (!(d2 / r2 > worst)) continue;
    worst = d2 / r2;
    const double h = predictedHeading(prediction, scene, k);
    const Vec2 along(std::cos(h), std::sin(h));
    const Vec2 across(-std::sin(h), std::cos(h));
    row.regionStep = static_cast<int>(k) + 1;
    row.longitudinal = r.dot(along);
    row.lateral = r.dot(across);
    const double sd_along = std::sqrt(std::max(along.dot(covariance * along), 1e-12));
    const double sd_across = std::sqrt(std::max(across.dot(covariance * across), 1e-12));
    row.axis = std::abs(row.longitudinal) / sd_along >= std::abs(row.lateral) / sd_across ? "longitudinal" : "lateral";
  }
  row.regionExcess = worst >= 0.0 ? worst : kNaN;
  row.regionMeanExcess = counted > 0 ? sum / counted : kNaN;
  row.predicted = prediction.mostLikely.positions;
}

}  // namespace

std::size_t RunCalibration::runsNeeded(std::size_t metrics, double level) {
  const double c = static_cast<double>(metrics + 1);  // the metrics and the path
  auto n = static_cast<std::size_t>(std::floor(c / level));
  if (c / static_cast<double>(n + 1) >= level) ++n;  // rounding
  return n;
}

double intervalCentre(const DeviationResult& result, const MetricTail& tail) {
  return result.calibrationRuns > 0 ? tail.mostLikely : tail.median;
}

RunCalibration::RunCalibration(const std::vector<SceneDeviation>& scenes, std::size_t metrics, std::string source,
                               double level)
    : source_(std::move(source)), level_(level) {
  for (const auto& scene : scenes) {
    if (!rankable(scene)) continue;
    auto& scores = byLabel_[scene.label];
    scores.metrics.resize(metrics);
    ++scores.runs;
    for (std::size_t m = 0; m < metrics && m < scene.metrics.size(); ++m) {
      const double score = metricScore(scene.metrics[m]);
      if (!std::isnan(score)) scores.metrics[m].push_back(score);
    }
    if (!std::isnan(scene.regionMeanExcess)) scores.path.push_back(scene.regionMeanExcess);
  }
  for (auto& [label, scores] : byLabel_) {
    for (auto& metric : scores.metrics) std::sort(metric.begin(), metric.end());
    std::sort(scores.path.begin(), scores.path.end());
  }
}

std::size_t RunCalibration::runs(const std::string& label) const {
  const auto found = byLabel_.find(label);
  return found == byLabel_.end() ? 0 : found->second.runs;
}

std::size_t RunCalibration::runs() const {
  std::size_t total = 0;
  for (const auto& [label, scores] : byLabel_) total += scores.runs;
  return total;
}

void RunCalibration::requireRuns(const std::string& label, std::size_t metrics) const {
  const std::size_t needed = runsNeeded(metrics, level_);
  if (runs(label) >= needed) return;
  throw ConfigError::field("command line", "--calibration " + source_,
                           fmt::format("{} runs of label '{}'", runs(label), label),
                           fmt::format("at least {} clean runs of each label of the field data (with fewer, one of "
                                       "the {} p-values - {} metrics and the path - cannot flag a scene alone at the "
                                       "level {:g})",
                                       needed, metrics + 1, metrics, level_));
}

void RunCalibration::apply(SceneDeviation& row) const {
  if (!rankable(row)) return;
  requireRuns(row.label, row.metrics.size());
  const auto& scores = byLabel_.at(row.label);
  for (std::size_t m = 0; m < row.metrics.size() && m < scores.metrics.size(); ++m) {
    auto& tail = row.metrics[m];
    tail.p = conformalP(scores.metrics[m], metricScore(tail));
    const double bound = conformalBound90(scores.metrics[m]);
    tail.p05 = tail.mostLikely - bound;
    tail.p95 = tail.mostLikely + bound;
  }
  row.pathP = conformalP(scores.path, row.regionMeanExcess);
  combine(row);
  if (!std::isnan(row.p) && row.status == SceneStatus::NotScored) {  // its path is ranked now
    row.status = SceneStatus::Scored;
    row.reason.clear();
  }
}

const char* statusName(SceneStatus status) {
  switch (status) {
    case SceneStatus::Scored:
      return "scored";
    case SceneStatus::OutOfDistribution:
      return "out_of_distribution";
    case SceneStatus::NotScored:
      return "not_scored";
  }
  return "";
}

struct DeviationScorer::Impl {
  const model::Predictor& predictor;
  std::unique_ptr<metrics::MetricSet> scored;  ///< the calibrated metrics among the field data's
  std::uint64_t seed = 1;

  /// The recorded values: stored where the data stores them (the calibration's references), else
  /// from the recorded future.
  std::vector<double> recorded(const vector::VectorizedScene& scene, const std::vector<std::string>& stored) const {
    auto values = pipeline::metricsOfFuture(*scored, scene, scene.target);
    for (std::size_t m = 0; m < scored->names().size(); ++m) {
      const auto found = std::find(stored.begin(), stored.end(), scored->names()[m]);
      const auto index = static_cast<std::size_t>(found - stored.begin());
      if (found != stored.end() && index < scene.metrics.size()) values[m] = scene.metrics[index];
    }
    return values;
  }

  void scoreMetrics(SceneDeviation& row, const model::Prediction& prediction, const vector::VectorizedScene& scene,
                    const std::vector<std::string>& stored) const {
    const auto& names = scored->names();
    std::vector<std::vector<double>> draws(names.size());
    for (const auto& future : prediction.samples) {
      const auto values = pipeline::metricsOfFuture(*scored, scene, future.positions, future.states);
      for (std::size_t m = 0; m < names.size(); ++m) draws[m].push_back(values[m]);
    }
    const auto reference = recorded(scene, stored);
    const auto likely = pipeline::metricsOfFuture(*scored, scene, prediction.mostLikely.positions,
                                                  prediction.mostLikely.states);
    const auto& calibration = predictor.info().metricIntervals;
    for (std::size_t m = 0; m < names.size(); ++m) {
      const auto* widening = calibration.find(scene.label, names[m]);
      MetricTail tail;
      tail.recorded = reference[m];
      tail.median = model::sampleQuantile(draws[m], 0.5);
      const auto interval = model::centralInterval(draws[m], 0.9, widening);
      tail.p05 = interval[0];
      tail.p95 = interval[1];
      tail.p = tailProbability(draws[m], reference[m], widening);
      tail.mostLikely = likely[m];
      row.metrics.push_back(tail);
    }
    combine(row);
    if (std::isnan(row.p)) {
      row.status = SceneStatus::NotScored;
      row.reason = "no metric is defined on both the recorded and the predicted futures";
    }
  }
};

DeviationScorer::DeviationScorer(const model::Predictor& predictor, const std::string& model_name,
                                 const std::vector<std::string>& metrics, const metrics::Availability& available,
                                 std::uint64_t seed)
    : impl_(new Impl{predictor, nullptr, seed}) {
  if (!predictor.probabilistic()) {
    throw ModelError(fmt::format("--model {}: the '{}' predictor draws no futures: deviations needs a probabilistic "
                                 "model (e.g. --decoder kinematic) trained with --decoder-option calibrate=1",
                                 model_name, predictor.name()));
  }
  const auto& calibration = predictor.info().metricIntervals;
  const auto pooled = calibration.byLabel.find("");
  if (pooled == calibration.byLabel.end()) {
    throw ModelError(fmt::format("--model {}: its metric intervals are not calibrated: train it with "
                                 "--decoder-option calibrate=1 (docs/deviations.md)",
                                 model_name));
  }
  std::vector<std::string> names;
  for (const auto& name : metrics) {
    if (pooled->second.count(name) != 0) names.push_back(name);
  }
  if (names.empty()) {
    std::vector<std::string> calibrated;
    for (const auto& [name, widening] : pooled->second) calibrated.push_back(name);
    throw ModelError(fmt::format("--model {}: none of the field data's metrics ({}) is calibrated in the model ({})",
                                 model_name, fmt::join(metrics, ", "), fmt::join(calibrated, ", ")));
  }
  impl_->scored = std::make_unique<metrics::MetricSet>(names, available, "--data");
}

DeviationScorer::~DeviationScorer() = default;

const std::vector<std::string>& DeviationScorer::metricNames() const { return impl_->scored->names(); }
std::vector<std::string> DeviationScorer::metricUnits() const { return impl_->scored->units(); }

bool DeviationScorer::trainedOn(const std::string& label) const {
  const auto& labels = impl_->predictor.info().labels;
  return labels.empty() || std::find(labels.begin(), labels.end(), label) != labels.end();
}

std::vector<SceneDeviation> DeviationScorer::score(const std::vector<vector::VectorizedScene>& scenes,
                                                   const std::vector<std::string>& stored,
                                                   const std::string& source) const {
  const auto& labels = impl_->predictor.info().labels;
  std::vector<SceneDeviation> rows(scenes.size());
  std::vector<vector::VectorizedScene> to_predict;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    auto& row = rows[i];
    const auto& scene = scenes[i];
    row.source = source;
    row.sample = scene.sample;
    row.label = scene.label;
    row.features = scene.inputs;
    row.features.push_back(scene.egoInitialState().speed);
    if (!trainedOn(scene.label)) {
      row.status = SceneStatus::OutOfDistribution;
      row.reason = fmt::format("label '{}': the model never trained on it (it trained on {})", scene.label,
                               fmt::join(labels, ", "));
    } else if (std::none_of(scene.targetValid.begin(), scene.targetValid.end(), [](std::uint8_t v) { return v != 0; })) {
      row.status = SceneStatus::NotScored;
      row.reason = "no recorded future (the Ego left the map at once)";
    } else {
      which.push_back(i);
      to_predict.push_back(scene);
    }
  }
  model::PredictOptions options;
  options.samples = model::kCalibrationDraws;  // the draws the calibration was fitted for
  options.seed = impl_->seed;
  const auto predictions = impl_->predictor.predictDistribution(to_predict, options);
  for (std::size_t j = 0; j < which.size(); ++j) {
    throwIfInterrupted();
    auto& row = rows[which[j]];
    impl_->scoreMetrics(row, predictions[j], to_predict[j], stored);
    scorePath(row, predictions[j], to_predict[j]);
  }
  return rows;
}

}  // namespace vsd::compare
