#include "vsd/bench/model_bench.hpp"

#include <fmt/format.h>

#include <chrono>
#include <tuple>

#include "vsd/compare/compare.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/experiment/experiment.hpp"
#include "vsd/model/presets.hpp"
#include "vsd/model/predictor.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

/// Scenes predicted per call, as `evaluate` does.
constexpr std::size_t kPredictionChunk = 4096;

std::vector<vector::VectorizedScene> readScenes(const std::vector<fs::path>& data) {
  std::vector<vector::VectorizedScene> scenes;
  for (const auto& path : data) {
    const vector::DatasetReader reader(vector::resolveDatasetPath(path));
    for (std::size_t i = 0; i < reader.size(); ++i) scenes.push_back(reader.scene(i));
  }
  return scenes;
}

}  // namespace

struct ModelBench::Work {
  std::optional<TemporaryDirectory> temporary;
  fs::path folder;
  model::VectorNetConfig config;  ///< of every training (preset and overrides)
  std::vector<fs::path> validation;  ///< validation data per label (kValidationDataSeed)
  std::string suffix;           ///< of every model file: decoder, frame, decoder options
};

const std::vector<std::string>& modelBenchLabels() {
  static const std::vector<std::string> labels = {"acc", "lk", "acc_lk"};
  return labels;
}

namespace {

/// The preset with the options' overrides: another decoder starts from its own defaults.
model::VectorNetConfig resolvedConfig(const ModelBenchOptions& options) {
  const auto& preset = model::findModelPreset(options.preset, "--preset");
  const auto given = model::parseDecoderOptions(options.decoderOptions);
  model::VectorNetConfig config;
  model::applyPreset(preset, given, config);
  if (!options.decoder.empty() && options.decoder != preset.decoder) {
    config.decoder = options.decoder;
    config.decoderOptions = given;
  }
  if (!options.frame.empty()) config.frame = options.frame;
  if (options.laneSmoothing) config.laneSmoothing = *options.laneSmoothing;
  config.validate();
  return config;
}

}  // namespace

ModelBench::ModelBench(ModelBenchOptions options) : options_(std::move(options)), work_(std::make_unique<Work>()) {
  work_->folder = options_.work;
  if (work_->folder.empty()) {
    work_->temporary.emplace("vsd-bench");
    work_->folder = work_->temporary->path();
  }
  ensureDirectory(work_->folder);
  if (options_.scenarios.empty()) options_.scenarios = fs::path(VSD_SOURCE_DIR) / "scenarios";
  for (const auto& label : modelBenchLabels()) work_->validation.push_back(work_->folder / ("validation_" + label));
  work_->config = resolvedConfig(options_);
  work_->suffix = fmt::format("_{}_{}", work_->config.decoder, work_->config.frame);
  for (const auto& [name, value] : work_->config.decoderOptions) work_->suffix += fmt::format("_{}={}", name, value);
  if (options_.laneSmoothing) work_->suffix += fmt::format("_smoothing={}", *options_.laneSmoothing);
  work_->suffix += ".pt";
}

ModelBench::~ModelBench() = default;

const model::VectorNetConfig& ModelBench::modelConfig() const { return work_->config; }

fs::path ModelBench::modelPath(const std::string& name) const { return work_->folder / (name + work_->suffix); }

double ModelBench::generateData() {
  double simulation_rate = 0.0;
  for (const auto& name : modelBenchLabels()) {
    for (const auto& [kind, samples, seed] : {std::tuple{std::string("train"), options_.samples, kTrainingDataSeed},
                                               std::tuple{std::string("validation"), options_.validationSamples, kValidationDataSeed}}) {
      const fs::path out = work_->folder / fmt::format("{}_{}", kind, name);
      if (fs::exists(out / "dataset.h5")) continue;
      const auto result = options_.tool.run({"run", (options_.scenarios / (name + ".yaml")).string(), "--samples",
                                             std::to_string(samples), "--seed", std::to_string(seed), "--out",
                                             out.string()},
                                            work_->folder);
      if (name == "acc_lk") simulation_rate = static_cast<double>(samples) / result.result.seconds;
    }
  }
  return simulation_rate;
}

MixResult ModelBench::trainAndEvaluate(const std::string& mix, const std::vector<std::string>& labels,
                                       const std::string& name) {
  model::TrainOptions train_options;
  for (const auto& label : labels) train_options.data.push_back(work_->folder / ("train_" + label));
  train_options.mix = model::Mix::parse(mix);
  train_options.output = modelPath(name);
  train_options.threads = options_.threads;
  train_options.steps = options_.steps;
  train_options.config = work_->config;
  train_options.resume = options_.resume && fs::exists(train_options.output.string() + ".last");
  experiment::bindCalibrationMetrics(train_options);
  // A finished training leaves its model and no <model>.last: with --resume it is reused as it is.
  const bool finished = options_.resume && !train_options.resume && fs::exists(train_options.output);
  MixResult result;
  result.mix = mix;
  result.summary = finished ? model::TrainSummary{} : model::train(train_options);
  const model::Predictor predictor(train_options.output, options_.threads);
  result.evaluation = model::evaluate(predictor, work_->validation);
  return result;
}

MixResult ModelBench::trainAll() {
  return trainAndEvaluate(fmt::format("acc={0},lk={0},acc_lk={0}", options_.samples), modelBenchLabels(), "all");
}

MixResult ModelBench::trainSingle(const std::string& label) {
  return trainAndEvaluate(fmt::format("{}={}", label, options_.samples), {label}, label);
}

MixResult ModelBench::trainRow4() {
  return trainAndEvaluate(fmt::format("acc={0},lk={0}", options_.samples), {"acc", "lk"}, "row4");
}

std::vector<MetricAccuracy> ModelBench::metricAccuracy() const {
  const model::Predictor predictor(modelPath("all"), options_.threads);
  std::vector<MetricAccuracy> accuracy;
  for (const auto& label : modelBenchLabels()) {
    // `vsd-sumo compare`'s scenario mode on the validation run's scenarios (same file, seed and
    // count): fresh SUMO runs, the metric registry on the trace and on the prediction.
    compare::CompareOptions options;
    options.scenarioFile = options_.scenarios / (label + ".yaml");
    options.samples = options_.validationSamples;
    options.seed = kValidationDataSeed;
    options.threads = options_.threads;
    options.draws = options_.draws;
    const auto comparison = compare::compareScenarioPredictions(options, predictor);
    accuracy.push_back({label, report::computeStatistics(comparison)});
  }
  return accuracy;
}

std::optional<double> ModelBench::samplingRate() const {
  const model::Predictor predictor(modelPath("all"), options_.threads);
  if (!predictor.probabilistic() || options_.draws <= 0) return std::nullopt;
  const auto scenes = readScenes(work_->validation);
  model::PredictOptions options;
  options.samples = options_.draws;
  const auto start = std::chrono::steady_clock::now();
  std::size_t predicted = 0;
  for (std::size_t first = 0; first < scenes.size(); first += kPredictionChunk) {
    const std::vector<vector::VectorizedScene> chunk(
        scenes.begin() + static_cast<std::ptrdiff_t>(first),
        scenes.begin() + static_cast<std::ptrdiff_t>(std::min(scenes.size(), first + kPredictionChunk)));
    predicted += predictor.predictDistribution(chunk, options).size();
  }
  return static_cast<double>(predicted) / secondsSince(start);
}

}  // namespace vsd::bench
