#pragma once
// `vsd-sumo experiment`: the paper's experiments end to end, from one YAML file
// (scenarios/experiments/paper.yaml): data generation, the training mixes of its
// ADE table, the metric-MAE comparison of extra trees, BNN and VectorNet, example
// figures, and a check of the paper's findings. Every artefact (runs, models,
// evaluations) is cached under <out>/cache with a key of everything it depends on,
// written atomically, so a re-run only does what changed and an interrupted run
// never leaves a corrupt artefact.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "vsd/model/predictor.hpp"

namespace vsd::experiment {

struct ExperimentOptions {
  std::filesystem::path spec;
  std::filesystem::path output;  ///< default: results/<name> (results/<name>-quick with quick)
  bool quick = false;            ///< the spec's small sizes: minutes instead of most of an hour
  bool allowDirty = false;       ///< write into the repository's results/ from a dirty build
  bool force = false;            ///< replace the results folder of another experiment (docs/output-policy.md)
  std::string commandLine;
};

/// One row of the ADE table: a training mix trained one way (over one or more seeds), or a
/// predictor without training (row 0, empty mix).
struct AdeRow {
  int row = 0;                           ///< the paper's row number; 0 for a predictor without training
  std::string model;                     ///< the spec's model name, or the predictor ("cv", "ca")
  std::map<std::string, std::size_t> mix;
  std::map<std::string, double> ade;     ///< ours, per test label (m): the mean over the seeds
  std::map<std::string, double> adeStd;  ///< sample standard deviation over the seeds (m); empty with one seed
  std::map<std::string, double> paper;   ///< the paper's, per test label (m)
  std::map<std::string, double> fde;     ///< ours, per test label (m): the mean over the seeds
  std::vector<std::uint64_t> seeds;      ///< training seeds (empty for predictors without training)
  double trainSeconds = 0.0;             ///< mean over the seeds
  int epochs = 0;                        ///< of the first seed
  std::string stopReason;                ///< of the first seed
  /// A leave-one-out row: the held-out functional scenario (the only test label it has) and
  /// what it trained on ("others", "others_and_few_own", "few_own", "all_own"); empty otherwise.
  std::string heldOut;
  std::string training;
};

/// A metric of one VectorNet model of the spec (every seed of the ADE row that predicts the
/// functional scenario: means over the seeds) against the simulated values of the test set.
struct VectorNetMetricError {
  std::string model;          ///< the spec's model name
  double mae = 0.0;           ///< of the metric of the most likely future (mean over the seeds)
  double maeStd = std::numeric_limits<double>::quiet_NaN();  ///< sample std over the seeds; NaN for one seed
  std::size_t seeds = 1;      ///< trainings averaged
  double bias = 0.0;          ///< mean of predicted - simulated (mean over the seeds)
  std::size_t samples = 0;    ///< test scenarios scored (finite simulated and predicted values), per seed
  std::size_t intervalSamples = 0;  ///< of them, those with a finite interval: the coverages' denominator
  /// Share of the simulated values inside the central 50 % / 90 % interval of the metric over
  /// the model's sampled futures (mae.draws per scene; mean over the seeds); NaN for
  /// deterministic decoders.
  double coverage50 = std::numeric_limits<double>::quiet_NaN();
  double coverage90 = std::numeric_limits<double>::quiet_NaN();
  /// The binomial 95 % confidence interval (Wilson) of each coverage: over several seeds, from
  /// the lowest seed's lower bound to the highest seed's upper bound.
  std::array<double, 2> coverage50Interval{std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::quiet_NaN()};
  std::array<double, 2> coverage90Interval{std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::quiet_NaN()};
};

struct MaeRow {
  std::string label;
  std::string metric;
  std::string unit;
  double et = 0.0;                 ///< MAE, mean over the baseline seeds
  double bnn = 0.0;                ///< MAE, mean over the baseline seeds
  double etSpread = std::numeric_limits<double>::quiet_NaN();   ///< sample std over the seeds; NaN for one
  double bnnSpread = std::numeric_limits<double>::quiet_NaN();  ///< sample std over the seeds; NaN for one
  std::size_t baselineSeeds = 1;   ///< fits of extra trees and of the BNN averaged (seeds seed, seed + 1, ...)
  std::vector<VectorNetMetricError> vectornet;  ///< every model that trains the row; the main model first
  double fromTruePositions = 0.0;  ///< MAE of the metric computed from the true future positions (the
                                   ///< reconstruction's own error: a floor for VectorNet's)
  double bnnStd = 0.0;             ///< mean predictive standard deviation of the BNN
  std::size_t trainRows = 0;       ///< training rows of extra trees and the BNN
  double etSeconds = 0.0;          ///< extra trees fit + predict (all metrics of the scenario)
  double bnnSeconds = 0.0;         ///< BNN fit + predict
  std::map<std::string, double> paper;  ///< et, bnn, vectornet
};

/// A metric of a held-out functional scenario (the leave-one-out study): the main model of
/// each of its rows (first seed; `model` names the row's training) and the regression
/// baselines fitted on its own inputs, which have nothing to learn from the other scenarios.
struct HeldOutMetric {
  std::string label;                            ///< the held-out functional scenario
  std::string metric;
  std::string unit;
  std::vector<VectorNetMetricError> vectornet;  ///< one per training, in HeldOutTraining order
  std::map<std::size_t, double> et;             ///< own training rows -> MAE of extra trees
  std::map<std::size_t, double> bnn;            ///< own training rows -> MAE of the BNN
};

/// One of the paper's findings, checked on our numbers with the thresholds in its
/// `rule` (README "Findings"): "holds", "does not hold" or "inconclusive" (between
/// the "generalises" and "does not generalise" thresholds).
struct Finding {
  std::string id;        ///< a, b, c, d
  std::string claim;     ///< the paper's statement
  std::string rule;      ///< how it is decided from ADE values
  std::string verdict;
  std::string evidence;  ///< the numbers used
};

struct ExperimentSummary {
  std::filesystem::path output;
  std::vector<AdeRow> ade;  ///< the main model's rows first, then other models', then predictors
  std::vector<MaeRow> mae;
  std::vector<HeldOutMetric> heldOut;  ///< the leave-one-out study's metrics (empty without one)
  std::vector<Finding> findings;
  std::vector<std::filesystem::path> files;
  double seconds = 0.0;
  std::size_t artefactsReused = 0;
  std::size_t artefactsBuilt = 0;
  std::string report() const;
};

/// Runs (or completes) the experiment. Throws ConfigError naming the file, line and
/// field for a bad spec or missing scenario/run folders.
ExperimentSummary runExperiment(const ExperimentOptions& options);

/// Every metric that applies to the scenes of a dataset (file, run or sweep folder), bound
/// for predicted futures (pipeline::metricsOfFuture, on a predictor's own states where it
/// has them): what `predict --samples` writes and the decoder option `calibrate` calibrates.
std::shared_ptr<const model::MetricBinding> futureMetricBinding(const std::filesystem::path& data);

/// Binds futureMetricBinding(the first data) to a training whose decoder options set
/// `calibrate`, so that its metric intervals are calibrated too; leaves others unchanged.
void bindCalibrationMetrics(model::TrainOptions& options);

}  // namespace vsd::experiment
