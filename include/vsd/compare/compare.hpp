#pragma once
// `vsd-sumo compare`: does a trained model's prediction hold up?
//
// Scenario mode: samples fresh concrete scenarios from a logical scenario, builds
// their scenes *without simulating* (pipeline::plannedScene), predicts the Ego with
// VectorNet, then simulates the same scenarios with SUMO and compares trajectories,
// metrics and pass/fail criteria.
// Dataset mode: predicts the samples of existing datasets (e.g. exported from a real
// map) and compares against their recorded future.
//
// Writes <out>/index.html (self-contained report) and <out>/comparison.csv, into a
// temporary folder renamed into place when complete.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vsd/report/comparison.hpp"

namespace vsd::model {
class Predictor;
}

namespace vsd::compare {

struct CompareOptions {
  std::filesystem::path model;                 ///< VectorNet model file (.pt)
  std::filesystem::path scenarioFile;          ///< scenario mode: logical scenario (YAML)
  std::vector<std::filesystem::path> data;     ///< dataset mode: dataset files or run folders
  std::filesystem::path output;                ///< default: reports/<scenario name> or reports/<first dataset stem>
  bool force = false;                          ///< replace an existing output folder
  bool allowDirty = false;                     ///< write into the repository's results/ from a dirty build
  static constexpr std::uint64_t kDefaultScenarios = 500;
  /// Scenario mode: scenarios to sample (0: kDefaultScenarios); dataset mode: the first N samples (0: all).
  std::uint64_t samples = 0;
  std::uint64_t seed = 1;                      ///< scenario mode: sampling seed
  int jobs = 1;                                ///< scenario mode: SUMO worker processes
  std::size_t batch = 250;                     ///< scenario mode: scenarios per SUMO network
  int threads = 2;                             ///< libtorch threads
  int worst = 6;                               ///< scenarios drawn in the report (largest ADE), 0..50
  /// Futures drawn per scenario from a probabilistic model for metric intervals and
  /// confident verdicts (0: none; ignored for deterministic models), 0 .. 10000.
  int draws = 32;
  std::uint64_t drawSeed = 1;                  ///< seed of the drawn futures
  double confidence = 0.9;                     ///< a verdict is confident when this share of futures agrees, 0.5 .. 1
  /// Dataset mode: metrics to compare (default: the dataset's metrics for generated data,
  /// else every metric that applies to a map, metrics::defaultMetrics) and criteria "name: expression" (scenario mode
  /// takes both from the scenario file).
  std::vector<std::string> metrics;
  std::vector<std::string> criteria;
  std::string commandLine;                     ///< recorded in the report's provenance

  /// Throws ConfigError naming the flag and what is accepted.
  void validate() const;
};

struct CompareSummary {
  report::Comparison comparison;
  report::ComparisonStatistics statistics;
  std::filesystem::path output;
  std::vector<std::filesystem::path> files;
  double seconds = 0.0;
  std::string report() const;  ///< what the CLI prints
};

/// Runs the comparison. Throws ConfigError (options, scenario, criteria, existing output),
/// ModelError (model file, feature schema, step/horizon mismatch), DatasetError, SumoError
/// (for faults of the whole run; a scenario SUMO fails on is listed in the report).
CompareSummary runComparison(const CompareOptions& options);

/// Scenario mode without a report: samples `options.samples` (0: kDefaultScenarios) fresh
/// scenarios of `options.scenarioFile` with `options.seed`, predicts them with `predictor`
/// (`options.draws` sampled futures), simulates them with SUMO and scores both through the
/// metric registry exactly as `runComparison` does (`options.model` and `options.output`
/// are not used). For benchmarks that need the simulated metrics (`vsd-sumo bench model`).
/// Throws as runComparison.
report::Comparison compareScenarioPredictions(const CompareOptions& options, const model::Predictor& predictor);

}  // namespace vsd::compare
