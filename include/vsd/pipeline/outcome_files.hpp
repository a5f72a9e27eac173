#pragma once
// traces.h5 and dataset.h5 of simulated outcomes, written as `run` writes them: one
// trace per outcome (an all-invalid one for a scenario that failed before simulating),
// one vectorized scene per completed outcome. Used by `run` and by `search`, so that a
// search's executions can train a model like a run's.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/sim/trace_file.hpp"
#include "vsd/vector/dataset.hpp"

namespace vsd::pipeline {

class OutcomeFiles {
 public:
  /// Opens both files for writing (IoError / DatasetError naming the path on failure).
  /// `compression`: deflate level of the dataset's vectors (0 = none). `traces`/`dataset`
  /// are where to write (e.g. staged files); errors name `tracesName`/`datasetName` if given
  /// (the final paths), else the paths written.
  OutcomeFiles(const scenario::LogicalScenario& logical, const std::vector<std::string>& metric_names,
               int compression, const std::filesystem::path& traces, const std::filesystem::path& dataset,
               const std::filesystem::path& tracesName = {}, const std::filesystem::path& datasetName = {});
  OutcomeFiles(const OutcomeFiles&) = delete;
  OutcomeFiles& operator=(const OutcomeFiles&) = delete;

  /// Appends the outcome under its sample index (outcome.index).
  void write(const ScenarioOutcome& outcome);
  /// Completes and closes both files.
  void close();

 private:
  vector::VectorizedScene sceneOf(const ScenarioOutcome& outcome) const;

  const scenario::LogicalScenario& logical_;
  std::string scenarioSha256_;
  std::optional<sim::TraceFileWriter> traces_;
  std::optional<vector::DatasetWriter> dataset_;
  Trace emptyTrace_;
};

/// Joins trace files of one functional scenario (same vehicles, step and horizon) into
/// `target`, rows in the given order. No file: nothing is written. Throws DatasetError /
/// IoError naming the file.
void concatenateTraces(const std::vector<std::filesystem::path>& files, const std::filesystem::path& target);

/// Joins datasets with one header into `target` (the first file's header, this
/// compression), samples in the given order. No file: nothing is written.
void concatenateDatasets(const std::vector<std::filesystem::path>& files, const std::filesystem::path& target,
                         int compression);

}  // namespace vsd::pipeline
