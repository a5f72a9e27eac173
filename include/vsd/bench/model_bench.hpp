#pragma once
// `vsd-sumo bench model`: VectorNet trained on the three functional scenarios (acc, lk,
// acc_lk) and measured on fresh scenarios of each, of the validation seed (core/seeds.hpp:
// where configurations are chosen, never the sealed test seeds): training and inference
// throughput, validation ADE per label, and the metrics of the predictions against fresh
// SUMO runs (as `vsd-sumo compare`). The steps are separate calls so that their results can
// be shown as they come.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/bench/measure.hpp"
#include "vsd/core/seeds.hpp"
#include "vsd/model/evaluation.hpp"
#include "vsd/model/model.hpp"
#include "vsd/model/options.hpp"
#include "vsd/report/comparison.hpp"

namespace vsd::bench {

struct ModelBenchOptions {
  std::filesystem::path work;  ///< keeps the generated data and models here (default: a temporary folder)
  std::filesystem::path scenarios;  ///< folder of acc.yaml, lk.yaml, acc_lk.yaml (default: the repository's)
  std::uint64_t samples = 2000;
  std::uint64_t validationSamples = 2000;  ///< fresh scenarios of the validation seed per label
  bool singles = false;        ///< also train one model per functional scenario
  bool row4 = false;           ///< also train on acc + lk only and measure on acc_lk (the paper's row 4)
  bool resume = false;         ///< continue trainings from <model>.last where it exists
  int threads = 2;
  int steps = 6000;            ///< optimizer steps of every training
  /// The configuration trained (model/presets.hpp): the one `train --preset` gives and the
  /// docs report. `decoder`, `frame` and `decoderOptions` change parts of it.
  std::string preset = "recommended";
  std::string decoder;                      ///< empty: the preset's; another decoder drops the preset's options
  std::vector<std::string> decoderOptions;  ///< name=value, on top of the preset's
  std::string frame;                        ///< empty: the preset's
  /// m, the lane frame's smoothing half-width (VectorNetConfig::laneSmoothing); unset: its default.
  std::optional<double> laneSmoothing;
  int draws = 32;              ///< sampled futures per scene for the inference and interval benchmarks
  Tool tool;
};

/// The functional scenarios of the benchmark, in the order they are reported.
const std::vector<std::string>& modelBenchLabels();

/// One trained model and its test errors.
struct MixResult {
  std::string mix;  ///< e.g. "acc=2000,lk=2000"
  model::TrainSummary summary;  ///< empty if a finished model was reused (--resume)
  model::Evaluation evaluation;
};

/// The metrics of one label's predictions against fresh SUMO runs.
struct MetricAccuracy {
  std::string label;
  report::ComparisonStatistics statistics;
};

class ModelBench {
 public:
  explicit ModelBench(ModelBenchOptions options);
  ~ModelBench();

  const ModelBenchOptions& options() const { return options_; }
  /// The model configuration every training of the benchmark uses (preset and overrides).
  const model::VectorNetConfig& modelConfig() const;
  /// Simulates the training and test data that is not in the work folder yet; returns
  /// acc_lk's simulation throughput (scenarios/s; 0 when its data was there).
  double generateData();
  /// The model on all three scenarios (the benchmark's main model).
  MixResult trainAll();
  /// One model on `label` alone.
  MixResult trainSingle(const std::string& label);
  /// The paper's row 4: acc + lk only.
  MixResult trainRow4();
  /// The main model's metrics against fresh SUMO runs of each label's test scenarios.
  std::vector<MetricAccuracy> metricAccuracy() const;
  /// Scenes/s of predicting `draws` sampled futures of every test scene with the main
  /// model; none if its decoder is not probabilistic or draws is 0.
  std::optional<double> samplingRate() const;

 private:
  MixResult trainAndEvaluate(const std::string& mix, const std::vector<std::string>& labels, const std::string& name);
  std::filesystem::path modelPath(const std::string& name) const;

  ModelBenchOptions options_;
  struct Work;
  std::unique_ptr<Work> work_;
};

}  // namespace vsd::bench
