#pragma once
// `vsd-sumo deviations`: recorded Ego behaviour that a model trained on test data did not
// expect - the hint at factors of reality the tests never had (SOTIF area 3) that the paper
// names as the use of combining test data (docs/deviations.md).
//
// For every recorded scene (run folders or datasets: "field" data) the model draws
// model::kCalibrationDraws futures; each metric is computed on every future by the same
// metric code as the recorded run's. A metric's tail probability is 1 - the smallest
// *calibrated* central level (model::containingLevel with the model's conformal widening)
// holding the recorded value: for scenes exchangeable with the model's held-out scenes it
// is uniform, so "p < level" happens to a share `level` of clean scenes. A scene's tail
// probability combines its metrics' by Simes' rule (valid for independent and for
// positively dependent metrics, exact when they are identical). Where it deviates is read
// from the recorded path against the predicted position distribution: the step where the
// path leaves its calibrated 90 % region furthest, split along and across the predicted
// heading. Scenes of a label the model never trained on are out of its distribution: listed
// apart, never flagged (compare's warning, as a verdict).
//
// With clean recorded runs the model never trained on (`--calibration`, RunCalibration) the
// p-values are split-conformal ranks instead: per label, a metric's score is its distance
// from the most likely future's value and the path's score its mean region excess (below), and a
// field scene's p is (1 + calibration scenes scoring at least as high) / (n + 1). For clean
// field scenes exchangeable with the calibration runs "p < level" then happens to at most a
// share `level` of them, whatever the model's own calibration; the intervals are narrower
// where the most likely future is better than the spread of the sampled ones says.
//
// Writes <out>/deviations.csv and <out>/report.html (report module), manifest last.

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "vsd/metrics/metrics.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::model {
class Predictor;
}

namespace vsd::compare {

/// What the calibrated prediction says about one metric of one recorded scene (metric unit).
struct MetricTail {
  double recorded = std::numeric_limits<double>::quiet_NaN();  ///< the recorded run's metric
  double median = std::numeric_limits<double>::quiet_NaN();    ///< of the sampled futures' metric
  double p05 = std::numeric_limits<double>::quiet_NaN();       ///< calibrated central 90 % interval
  double p95 = std::numeric_limits<double>::quiet_NaN();
  /// Two-sided tail probability in [0, 1]: 1 - the smallest calibrated central level holding
  /// the recorded value. 0 beyond the calibrated 99 % interval (the highest level fitted);
  /// NaN when the recorded value or every draw is NaN.
  double p = std::numeric_limits<double>::quiet_NaN();
  /// The metric of the model's most likely future (what calibration runs centre on).
  double mostLikely = std::numeric_limits<double>::quiet_NaN();
};

enum class SceneStatus {
  Scored,             ///< compared with the model's calibrated prediction
  OutOfDistribution,  ///< a label the model never trained on: not scored, listed apart
  NotScored           ///< no recorded future, or no metric defined
};
const char* statusName(SceneStatus status);

/// One recorded scene.
struct SceneDeviation {
  std::string source;          ///< the dataset file it came from
  std::size_t row = 0;         ///< its row in that file
  std::uint64_t sample = 0;    ///< its sample (window) number
  std::string label;
  SceneStatus status = SceneStatus::Scored;
  std::string reason;          ///< why not scored / out of distribution; why flagged
  std::vector<double> features;  ///< DeviationResult::featureNames order
  std::vector<MetricTail> metrics;  ///< DeviationResult::metricNames order
  /// Simes combination of the metrics' p (and the path's, where calibration runs give it).
  double p = std::numeric_limits<double>::quiet_NaN();
  bool flagged = false;        ///< p < level
  std::size_t worstMetric = 0;  ///< the metric with the smallest p
  /// The path's conformal p (regionMeanExcess ranked among the calibration runs'); NaN without them.
  double pathP = std::numeric_limits<double>::quiet_NaN();
  bool pathWorst = false;       ///< pathP is smaller than every metric's p
  /// Max over valid steps of d^2 / r^2_90: the recorded position's squared Mahalanobis
  /// distance over the calibrated 90 % region's (> 1: outside that region). NaN: no valid step.
  double regionExcess = std::numeric_limits<double>::quiet_NaN();
  /// Mean over valid steps of the same d^2 / r^2_90: the path's score among calibration runs
  /// (a lasting deviation, such as a lag that grows, outscores a brief one of the same peak).
  double regionMeanExcess = std::numeric_limits<double>::quiet_NaN();
  int regionStep = 0;           ///< 1-based future step of that maximum
  double longitudinal = 0.0;    ///< m, recorded - predicted mean there, along the predicted heading
  double lateral = 0.0;         ///< m, across it (left positive)
  /// "longitudinal" or "lateral": the larger of the two in units of the predicted standard
  /// deviation along that axis.
  std::string axis;
  /// Flagged scenes: "<label>: <axis>, <metric> <below|above> its interval".
  std::string group;
  /// For drawing: the most likely future and per step the 90 % region's ellipse parameters.
  Polyline predicted;
  std::vector<std::array<double, 3>> region90;  ///< per step: semi-axes a >= b (m) and the angle of a (rad)
};

/// The scores of a set of recorded scenes.
struct DeviationResult {
  std::vector<std::string> metricNames;
  std::vector<std::string> metricUnits;
  std::vector<std::string> featureNames;  ///< the data's inputs, then v0_ego
  std::vector<std::string> featureUnits;
  double level = 0.05;
  double step = 0.0;  ///< s between future steps (the data's and the model's)
  /// Calibration runs the p-values were ranked among (RunCalibration); 0: the model's own
  /// calibration, intervals around the draws' median.
  std::size_t calibrationRuns = 0;
  std::vector<SceneDeviation> scenes;
};

/// The value a metric's interval is around: the draws' median (the model's calibration) or
/// the most likely future's value (calibration runs).
double intervalCentre(const DeviationResult& result, const MetricTail& tail);

/// Scores recorded scenes against a calibrated probabilistic model.
class DeviationScorer {
 public:
  /// `metrics`: the metrics the field data provides (`available` what its scenes hold); those
  /// the model's calibration covers are scored. Throws ModelError (naming the model) for a
  /// deterministic model, one without calibrated metric intervals (train with
  /// --decoder-option calibrate=1) or without any of `metrics` calibrated. `seed` seeds the
  /// sampled futures.
  DeviationScorer(const model::Predictor& predictor, const std::string& model_name,
                  const std::vector<std::string>& metrics, const metrics::Availability& available, std::uint64_t seed);
  ~DeviationScorer();
  DeviationScorer(const DeviationScorer&) = delete;
  DeviationScorer& operator=(const DeviationScorer&) = delete;

  const std::vector<std::string>& metricNames() const;
  std::vector<std::string> metricUnits() const;
  /// Whether the model trained on `label` (true for every label when its file does not say):
  /// scenes of other labels are out of its distribution.
  bool trainedOn(const std::string& label) const;
  /// Scores `scenes` (one source). `stored`: the names of the metrics the scenes carry
  /// (scene.metrics; the recorded run's values, what the calibration's references were),
  /// empty: every metric from the recorded future. `input_count`: leading scene.inputs used
  /// as features. Scenes of labels the model never trained on come back OutOfDistribution.
  std::vector<SceneDeviation> score(const std::vector<vector::VectorizedScene>& scenes,
                                    const std::vector<std::string>& stored, const std::string& source) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Split-conformal calibration on clean recorded runs of the field's labels that the model
/// never trained on (`deviations --calibration`, docs/deviations.md).
class RunCalibration {
 public:
  /// `scenes`: the calibration runs as DeviationScorer::score returns them (those with a
  /// metric or a path to rank count; out-of-distribution ones not), `metrics` entries each.
  /// `source` names them in errors; `level` is the level p is compared with (apply refuses a
  /// label with too few runs for one p-value alone to flag a scene below it).
  RunCalibration(const std::vector<SceneDeviation>& scenes, std::size_t metrics, std::string source, double level);
  /// Calibration runs of `label` (0: none).
  std::size_t runs(const std::string& label) const;
  /// Calibration runs of every label.
  std::size_t runs() const;
  /// The fewest runs of a label with which one of the metrics' and the path's p-values alone
  /// can flag a scene at `level`: the smallest n with (metrics + 1) / (n + 1) < level (Simes'
  /// rule with one extreme p = 1 / (n + 1)).
  static std::size_t runsNeeded(std::size_t metrics, double level);
  /// Throws ConfigError naming `source` unless `label` has the runs `metrics` scored metrics need
  /// (runsNeeded): checked before a field scene of a trained label is scored, and by apply.
  void requireRuns(const std::string& label, std::size_t metrics) const;
  /// Ranks `row` among its label's runs: each metric's p (and its 90 % interval: the most likely
  /// value +- the runs' 90 % score), the path's p, and their Simes combination; a scene the
  /// model's calibration could not score but whose path is ranked becomes Scored. Throws
  /// ConfigError naming `source` for a label with fewer runs than (metrics + 1) / level.
  void apply(SceneDeviation& row) const;

 private:
  struct Scores {
    std::vector<std::vector<double>> metrics;  ///< per metric: sorted finite scores
    std::vector<double> path;                  ///< sorted finite mean region excesses
    std::size_t runs = 0;
  };
  std::map<std::string, Scores> byLabel_;
  std::string source_;
  double level_;
};

/// Flags, explains and groups the scored scenes of `result`: sets `flagged` (p < level),
/// `reason` and `group`, and returns the indices of the flagged scenes, most surprising
/// (smallest p, then largest region excess) first.
std::vector<std::size_t> rankDeviations(DeviationResult& result);

struct DeviationOptions {
  std::filesystem::path model;              ///< a calibrated probabilistic model (.pt)
  std::vector<std::filesystem::path> data;  ///< field data: dataset files or run folders
  /// Clean recorded runs of the field's labels the model never trained on (dataset files or
  /// run folders): p-values by conformal rank among them (RunCalibration). Empty: the
  /// model's own calibration.
  std::vector<std::filesystem::path> calibration;
  std::filesystem::path output;             ///< required
  double level = 0.05;                      ///< flag scenes with p < level; in (0, 1)
  /// Metrics to score (those the model's calibration covers are kept). Empty: the metrics
  /// the field data stores (generated runs: the scenario's list), else every metric that
  /// applies to it. Fewer metrics keep Simes' combination sharp (docs/deviations.md).
  std::vector<std::string> metrics;
  bool force = false;
  bool allowDirty = false;
  int threads = 2;                          ///< libtorch threads, 1 .. 256
  std::uint64_t seed = 1;                   ///< seed of the sampled futures
  int drawn = 12;                           ///< flagged scenes drawn in the report, 0 .. 100
  std::string commandLine;
  /// Throws ConfigError naming the flag and what is accepted.
  void validate() const;
};

struct DeviationSummary {
  DeviationResult result;
  std::vector<std::size_t> ranked;  ///< flagged scenes, most surprising first
  std::filesystem::path output;
  double seconds = 0.0;
  double scoringSeconds = 0.0;      ///< predicting and scoring (no reading, no writing)
  std::vector<std::string> warnings;  ///< shown first in the report and printed
  std::size_t scored() const;
  std::size_t outOfDistribution() const;
  std::string report() const;       ///< what the CLI prints
};

/// Reads the field data, scores it and writes <output>/deviations.csv and report.html.
/// Checks everything before any work and writes nothing on failure: ConfigError (options,
/// output policy), ModelError (model; another step or horizon than the data's; road-user
/// kinds the model never saw), DatasetError (no samples, unreadable data).
DeviationSummary findDeviations(const DeviationOptions& options);

}  // namespace vsd::compare
