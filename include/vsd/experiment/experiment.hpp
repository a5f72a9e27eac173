#pragma once
// `vsd-sumo experiment`: the paper's experiments end to end, from one YAML file
// (scenarios/experiments/paper.yaml): data generation, the training mixes of its
// ADE table, the metric-MAE comparison of extra trees, BNN and VectorNet, example
// figures, and a check of the paper's findings. Every artefact (runs, models,
// evaluations) is cached under <out>/cache with a key of everything it depends on,
// written atomically, so a re-run only does what changed and an interrupted run
// never leaves a corrupt artefact.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace vsd::experiment {

struct ExperimentOptions {
  std::filesystem::path spec;
  std::filesystem::path output;  ///< default: results/<name> (results/<name>-quick with quick)
  bool quick = false;            ///< the spec's small sizes: minutes instead of most of an hour
  bool allowDirty = false;       ///< write into the repository's results/ from a dirty build
  std::string commandLine;
};

struct AdeRow {
  int row = 0;
  std::map<std::string, std::size_t> mix;
  std::map<std::string, double> ade;    ///< ours, per test label (m)
  std::map<std::string, double> paper;  ///< the paper's, per test label (m)
  std::map<std::string, double> fde;    ///< ours, per test label (m)
  double trainSeconds = 0.0;
  int epochs = 0;
  std::string stopReason;
};

struct MaeRow {
  std::string label;
  std::string metric;
  std::string unit;
  double et = 0.0;
  double bnn = 0.0;
  double vectornet = 0.0;
  double fromTruePositions = 0.0;  ///< MAE of the metric computed from the true future positions (the
                                   ///< reconstruction's own error: a floor for VectorNet's)
  double bnnStd = 0.0;             ///< mean predictive standard deviation of the BNN
  std::size_t testSamples = 0;     ///< test scenarios scored by VectorNet
  std::size_t trainRows = 0;       ///< training rows of extra trees and the BNN
  double etSeconds = 0.0;          ///< extra trees fit + predict (all metrics of the scenario)
  double bnnSeconds = 0.0;         ///< BNN fit + predict
  std::map<std::string, double> paper;  ///< et, bnn, vectornet
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
  std::vector<AdeRow> ade;
  std::vector<MaeRow> mae;
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

}  // namespace vsd::experiment
