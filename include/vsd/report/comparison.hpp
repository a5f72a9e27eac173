#pragma once
// Comparison of predicted against reference Ego behaviour (reference = fresh SUMO
// runs of the same concrete scenarios, or the recorded future of dataset samples):
// per-scenario rows, the statistics a validation engineer reads first, and the
// outputs: comparison.csv and one self-contained HTML report (inline SVG, inline
// CSS and a few lines of inline JavaScript; no network access needed to view it).
//
// Sign convention: error and bias are predicted minus reference.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vsd::report {

/// A pass/fail criterion, e.g. {close_approach, "d_min < 2"}: true = the scenario fails it.
struct CriterionSpec {
  std::string name;
  std::string expression;
};

/// What the sampled futures of a probabilistic prediction say about one metric of one
/// scenario: quantiles over the draws (vsd::model::intervalOf; calibrated when the model
/// is) and the smallest central interval holding the reference (vsd::model::containingLevel).
struct MetricInterval {
  std::size_t draws = 0;  ///< sampled futures with a value (0: no interval)
  double p05 = 0.0;
  double p25 = 0.0;
  double median = 0.0;
  double p75 = 0.0;
  double p95 = 0.0;
  /// The reference lies in the central interval of level L exactly when containingLevel <= L
  /// (0..1; NaN: no reference value).
  double containingLevel = 0.0;
};

/// One compared scenario.
struct ComparedScenario {
  std::uint64_t sample = 0;      ///< sample index (scenario mode) or dataset row (dataset mode)
  std::string label;             ///< functional scenario or map label
  std::string failure;           ///< non-empty: no reference (e.g. SUMO failed); nothing else is compared
  std::vector<double> inputs;    ///< concrete inputs (CompareData::inputNames order), may be empty
  double ade = 0.0;              ///< m, mean displacement over the valid future steps
  double fde = 0.0;              ///< m, displacement at the last valid step
  std::vector<double> predicted;  ///< metrics from the predicted trajectory (metricNames order)
  std::vector<double> reference;  ///< metrics of the reference run
  /// Metrics from the reference *positions* through the same code as `predicted`:
  /// the error that reconstructing speeds and accelerations from positions alone
  /// causes (empty when the reference metrics already come from positions).
  std::vector<double> fromReferencePositions;
  /// Per criterion: 1 fails, 0 passes, -1 undefined (a metric it uses is NaN).
  std::vector<int> predictedFails;
  std::vector<int> referenceFails;
  /// Probabilistic models only (empty otherwise): per metric, the interval of its sampled
  /// futures; per criterion, the share of sampled futures that fail it (NaN: undefined).
  std::vector<MetricInterval> intervals;
  std::vector<double> failShare;
  bool ok() const { return failure.empty(); }
};

/// Everything a report shows, filled by `vsd-sumo compare`.
struct Comparison {
  std::string title;                       ///< e.g. "acc_lk: 500 fresh scenarios"
  std::string referenceName = "simulated";  ///< "simulated" or "recorded"
  std::vector<std::string> inputNames;
  std::vector<std::string> metricNames;
  std::vector<std::string> metricUnits;     ///< per metric
  std::vector<CriterionSpec> criteria;
  std::vector<ComparedScenario> scenarios;
  /// Seconds spent per stage, in order (e.g. {"vectorize", 0.1}, {"predict", 0.05}, {"simulate", 2.1}).
  std::vector<std::pair<std::string, double>> timings;
  /// Key/value lines: model file and SHA-256, scenario file and SHA-256, seed, versions, command line.
  std::vector<std::pair<std::string, std::string>> provenance;
  /// Notes shown under the summary (e.g. how far planned scenes deviate from simulated ones).
  std::vector<std::string> notes;
  /// Warnings shown first and printed (e.g. scenarios of a label the model never trained on).
  std::vector<std::string> warnings;
  /// Sampled futures per scenario (0: a deterministic model, no intervals).
  int draws = 0;
  /// A criterion's verdict is confident when at least this share of the sampled futures agree.
  double confidence = 0.9;
};

/// Summary statistics of a sample of values (finite values only).
struct Distribution {
  std::size_t count = 0;
  double mean = 0.0;
  double median = 0.0;
  double p90 = 0.0;
  double max = 0.0;
};
Distribution describe(std::vector<double> values);

struct MetricStatistics {
  std::string name;
  std::string unit;
  std::size_t pairs = 0;            ///< scenarios with both values finite
  std::size_t bothInfinite = 0;     ///< e.g. ttc_min = inf on both sides: agreement
  std::size_t finitenessMismatch = 0;  ///< one side finite, the other infinite or NaN
  double mae = 0.0;                 ///< mean |predicted - reference| over the pairs
  double bias = 0.0;                ///< mean (predicted - reference)
  double medianAbsoluteError = 0.0;  ///< robust against a few huge errors (e.g. ttc_min near zero closing speed)
  double p90AbsoluteError = 0.0;
  std::optional<double> floorMae;   ///< MAE of fromReferencePositions vs reference, if given
  /// Calibration (probabilistic models): scenarios with an interval and a reference value,
  /// the share of them whose reference lies in the central 50 % / 90 % interval, the mean
  /// width of the 90 % interval, and the observed coverage at each kReliabilityLevels level.
  std::size_t intervalPairs = 0;
  double coverage50 = 0.0;
  double coverage90 = 0.0;
  double meanWidth90 = 0.0;
  /// Mean |median of the sampled futures' values - reference| over the intervalPairs where
  /// it is finite (NaN if none): the
  /// error of the draws' median as a point estimate, next to `mae` of the most likely future.
  double medianDrawMae = 0.0;
  std::vector<double> reliability;
};

/// Nominal levels of the reliability diagram (central intervals).
inline const std::vector<double> kReliabilityLevels = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.98};

struct CriterionStatistics {
  std::string name;
  std::string expression;
  std::size_t bothFail = 0;        ///< predicted fail, reference fail (critical scenario found)
  std::size_t falseAlarm = 0;      ///< predicted fail, reference pass
  std::size_t missed = 0;          ///< predicted pass, reference fail (critical scenario missed)
  std::size_t bothPass = 0;
  std::size_t undefined = 0;       ///< either side undefined
  /// Probabilistic models: verdicts at least Comparison::confidence of the sampled futures
  /// agree on, how many of them the reference contradicts, the other (uncertain) verdicts,
  /// and how many of those the most likely future got wrong.
  std::size_t confident = 0;
  std::size_t confidentWrong = 0;
  std::size_t uncertain = 0;
  std::size_t uncertainPointWrong = 0;
  double agreement() const;        ///< (bothFail + bothPass) / defined; NaN if none defined
  double recall() const;           ///< bothFail / (bothFail + missed); NaN if no reference failure
};

struct ComparisonStatistics {
  std::size_t compared = 0;
  std::size_t failed = 0;
  Distribution ade;
  Distribution fde;
  std::vector<MetricStatistics> metrics;
  std::vector<CriterionStatistics> criteria;
};
ComparisonStatistics computeStatistics(const Comparison& comparison);

/// One row per scenario: sample, label, status, failure, inputs, ade_m, fde_m, then per
/// metric <name>_predicted, <name>_<referenceName>, <name>_error (and with intervals
/// <name>_p05, _p25, _median, _p75, _p95), then per criterion <name>_predicted_fail,
/// <name>_<referenceName>_fail (1/0, empty when undefined) (and with intervals
/// <name>_fail_share). Written atomically.
void writeComparisonCsv(const Comparison& comparison, const std::filesystem::path& path);

/// A scene drawing for the "worst scenarios" section (an <svg> element).
struct SceneDrawing {
  std::uint64_t sample = 0;
  std::string caption;
  std::string svg;
};

/// The complete HTML document. `worst` is shown in the given order.
std::string renderHtmlReport(const Comparison& comparison, const ComparisonStatistics& statistics,
                             const std::vector<SceneDrawing>& worst);

/// Multi-line text summary for the terminal (the report's summary table).
std::string textSummary(const Comparison& comparison, const ComparisonStatistics& statistics);

}  // namespace vsd::report
