// `vsd-sumo experiment`: the stages of the paper's experiments with an artefact
// cache (cache.hpp). Stages, in order:
//   data     per functional scenario a training pool and a test set (vsd-sumo run)
//   models   one VectorNet per ADE row (its training mix)
//   eval     every model on every test set (a leave-one-out row on its held-out one):
//            ADE/FDE, and the sample of median ADE
//   mae      extra trees, BNN (on concrete inputs) and VectorNet (metrics of the
//            predicted trajectory) against the simulated metrics of the test set
//   held_out the same per held-out scenario of `leave_one_out` (held_out.cpp writes it)
//   figures  example predictions like the paper's figures 6-8
//   results  tables, findings and manifest (results.cpp)
#include "vsd/experiment/experiment.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <exception>
#include <thread>
#include <chrono>
#include <cmath>
#include <limits>

#include "cache.hpp"
#include "results.hpp"
#include "spec.hpp"
#include "vsd/baseline/baseline.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/core/svg.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vsd::experiment {

namespace {

/// A functional scenario's data: where its runs are and what they were built from.
struct LabelData {
  std::string label;
  fs::path trainRun;
  fs::path testRun;
  std::string trainDigest;
  std::string testDigest;
};

double mean(double sum, std::size_t count) {
  return count == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(count);
}

struct RowModel {
  fs::path file;
  std::string digest;
  std::uint64_t seed = 0;  ///< the training seed
};

/// One trained model: a row of one of the spec's models with one seed.
struct TrainedRun {
  std::string model;
  int row = 0;
  std::uint64_t seed = 0;
  RowModel modelFile;
  json training;  ///< training.json
};

/// One metric's errors of one model as vectornetErrors writes them.
VectorNetMetricError metricError(const json& model, const std::string& metric) {
  const auto& errors = model.at("metrics").at(metric);
  VectorNetMetricError error;
  error.model = model.at("model").get<std::string>();
  error.mae = errors.at("mae").get<double>();
  error.bias = errors.at("bias").get<double>();
  error.samples = errors.at("samples").get<std::size_t>();
  error.intervalSamples = errors.at("interval_samples").get<std::size_t>();
  if (!errors.at("coverage50").is_null()) error.coverage50 = errors.at("coverage50").get<double>();
  if (!errors.at("coverage90").is_null()) error.coverage90 = errors.at("coverage90").get<double>();
  return error;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One metric's errors of one model over its seeds (vectornetErrors' entries of that model):
/// means, the MAE's sample standard deviation, and per coverage the span of the seeds' Wilson
/// 95 % intervals.
VectorNetMetricError metricErrorOverSeeds(const std::vector<const json*>& seeds, const std::string& metric) {
  std::vector<VectorNetMetricError> errors;
  for (const auto* seed : seeds) errors.push_back(metricError(*seed, metric));
  auto combined = errors.front();
  combined.seeds = errors.size();
  const auto valuesOf = [&](double VectorNetMetricError::*field) {
    std::vector<double> values;
    for (const auto& error : errors) values.push_back(error.*field);
    return values;
  };
  combined.mae = sampleMean(valuesOf(&VectorNetMetricError::mae));
  combined.bias = sampleMean(valuesOf(&VectorNetMetricError::bias));
  combined.coverage50 = sampleMean(valuesOf(&VectorNetMetricError::coverage50));
  combined.coverage90 = sampleMean(valuesOf(&VectorNetMetricError::coverage90));
  if (errors.size() > 1) combined.maeStd = sampleStd(valuesOf(&VectorNetMetricError::mae));
  const auto span = [&](double VectorNetMetricError::*coverage) {
    std::array<double, 2> bounds{1.0, 0.0};  // widened to every seed's interval below
    for (const auto& error : errors) {
      if (!std::isfinite(error.*coverage) || error.intervalSamples == 0) return std::array<double, 2>{kNaN, kNaN};
      const auto interval = wilsonInterval(error.*coverage, error.intervalSamples);
      bounds = {std::min(bounds[0], interval.low), std::max(bounds[1], interval.high)};
    }
    return bounds;
  };
  combined.coverage50Interval = span(&VectorNetMetricError::coverage50);
  combined.coverage90Interval = span(&VectorNetMetricError::coverage90);
  return combined;
}

json readJson(const fs::path& path) {
  try {
    return json::parse(readTextFile(path));
  } catch (const json::exception& error) {
    throw IoError(fmt::format("{}: not valid JSON ({})", path.string(), error.what()));
  }
}

void writeJson(const fs::path& path, const json& value) { writeTextFileAtomically(path, value.dump(2) + "\n"); }



class ExperimentRunner {
 public:
  ExperimentRunner(const ExperimentOptions& options, Spec spec, fs::path output)
      : options_(options), spec_(std::move(spec)), output_(std::move(output)), cache_(output_ / "cache") {}

  ExperimentSummary run() {
    const auto start = std::chrono::steady_clock::now();
    const auto logical_scenarios = checkSources();
    // The result files change as one set, at the end; the cache inside the
    // folder is not part of the set (each artefact is its own unit).
    folder_.emplace(output_);

    prepareData(logical_scenarios);
    trainModels();
    evaluateModels();
    compareMetrics();
    compareHeldOut();
    drawFigures();
    summary_.output = output_;
    std::vector<AdeRow> main_rows;  // the findings are the main model's
    for (const auto& row : summary_.ade) {
      if (row.model == spec_.models.front().name) main_rows.push_back(row);
    }
    summary_.findings = checkFindings(spec_, main_rows);
    summary_.seconds = secondsSince(start);
    writeResults(spec_, options_, summary_, artefacts_, *folder_);
    return summary_;
  }

 private:
  // --- bookkeeping -------------------------------------------------------------
  bool reuse(const fs::path& artefact, const CacheKey& key, const std::string& what) {
    const bool valid = cache_.valid(artefact, key);
    artefacts_.push_back({fs::relative(artefact, output_).string(), key.digest(), valid});
    if (valid) {
      ++summary_.artefactsReused;
      spdlog::info("{}: cached ({})", what, fs::relative(artefact, output_).string());
    } else {
      ++summary_.artefactsBuilt;
    }
    return valid;
  }

  /// A key naming the code an artefact is built by: the identities of the modules it
  /// depends on (core/provenance.hpp), so a change elsewhere reuses it.
  CacheKey key(const std::string& kind, const std::vector<std::string>& modules) const {
    CacheKey key(kind);
    key.add("code", codeIdentity(modules));
    return key;
  }

  // The modules each kind of artefact depends on (src/CMakeLists.txt's link graph).
  static const std::vector<std::string>& simulationModules() {
    static const std::vector<std::string> modules = {"core", "run_folder", "scenario", "road", "sim", "metrics", "vector", "pipeline"};
    return modules;
  }
  static const std::vector<std::string>& modelModules() {
    static const std::vector<std::string> modules = {"core", "run_folder", "vector", "model"};
    return modules;
  }
  static const std::vector<std::string>& maeModules() {
    static const std::vector<std::string> modules = {"core", "run_folder", "vector", "model", "baseline", "metrics", "pipeline"};
    return modules;
  }

  const LabelData& data(const std::string& label) const {
    const auto found = data_.find(label);
    if (found == data_.end()) throw ConfigError(fmt::format("{}: no functional scenario '{}'", spec_.file.string(), label));
    return found->second;
  }

  const std::vector<vector::VectorizedScene>& testScenes(const std::string& label) {
    auto& scenes = testScenes_[label];
    if (scenes.empty()) {
      const vector::DatasetReader reader(vector::resolveDatasetPath(data(label).testRun));
      Progress progress(fmt::format("loading {} test scenes", label), reader.size(), "scenes");
      scenes.reserve(reader.size());
      for (std::size_t i = 0; i < reader.size(); ++i) {
        scenes.push_back(reader.scene(i));
        progress.advance();
      }
      if (scenes.empty()) throw DatasetError(fmt::format("{}: the test set holds no sample", reader.path().string()));
    }
    return scenes;
  }

  // --- data ----------------------------------------------------------------------
  /// Checks every source before anything runs, so a bad spec fails in a second.
  std::map<std::string, std::shared_ptr<const scenario::LogicalScenario>> checkSources() const {
    std::map<std::string, std::shared_ptr<const scenario::LogicalScenario>> logical_scenarios;
    for (const auto& source : spec_.sources) {
      if (!source.scenario.empty()) {
        auto logical = scenario::loadLogicalScenario(source.scenario);
        if (logical->name != source.label) {
          throw ConfigError(fmt::format(
              "{}: scenarios.{}: '{}' describes functional scenario '{}', expected '{}' (the label names its samples)",
              spec_.file.string(), source.label, source.scenario.string(), logical->name, source.label));
        }
        logical_scenarios[source.label] = std::move(logical);
        continue;
      }
      for (const bool train : {true, false}) {
        const auto& run_folder = train ? source.trainRun : source.testRun;
        const auto found = baseline::functionalScenarioOf(run_folder);
        if (found != source.label) {
          throw ConfigError(fmt::format("{}: scenarios.{}.{}: '{}' holds functional scenario '{}', expected '{}'",
                                        spec_.file.string(), source.label, train ? "train" : "test",
                                        run_folder.string(), found, source.label));
        }
      }
    }
    return logical_scenarios;
  }

  void prepareData(const std::map<std::string, std::shared_ptr<const scenario::LogicalScenario>>& logical_scenarios) {
    for (const auto& source : spec_.sources) {
      throwIfInterrupted();
      LabelData label_data;
      label_data.label = source.label;
      if (!source.scenario.empty()) {
        const auto& logical = logical_scenarios.at(source.label);
        const std::string scenario_hash = sha256OfFile(source.scenario);
        for (const bool train : {true, false}) {
          const auto samples = train ? spec_.trainSamples : spec_.testSamples;
          const auto seed = train ? spec_.trainSeed : spec_.testSeed;
          const auto folder = cache_.folder(fmt::format("data/{}_{}", source.label, train ? "train" : "test"));
          auto run_key = key("run", simulationModules());
          run_key.add("scenario_sha256", scenario_hash).add("samples", samples).add("seed", seed);
          const std::string what = fmt::format("{} {} data ({} scenarios, seed {})", source.label,
                                               train ? "training" : "test", samples, seed);
          if (!reuse(folder, run_key, what)) {
            spdlog::info("{}: simulating", what);
            cache_.clear(folder);
            pipeline::RunOptions run_options;
            run_options.scenarioFile = source.scenario;
            run_options.outputDir = folder;
            run_options.samples = samples;
            run_options.seed = seed;
            run_options.jobs = spec_.jobs;
            run_options.commandLine = options_.commandLine;
            const auto run = pipeline::runScenarios(logical, run_options);
            if (run.ok == 0) {
              throw SumoError(fmt::format("{}: every one of the {} scenarios failed (see {}/concrete.csv)",
                                          source.scenario.string(), samples, folder.string()));
            }
            cache_.commit(folder, run_key);
          }
          (train ? label_data.trainRun : label_data.testRun) = folder;
          (train ? label_data.trainDigest : label_data.testDigest) = run_key.digest();
        }
      } else {
        // Existing runs (of another tool version, say) are identified by their contents.
        for (const bool train : {true, false}) {
          const auto& run_folder = train ? source.trainRun : source.testRun;
          auto run_key = key("existing run", {"core", "vector"});
          run_key.add("dataset_sha256", sha256OfFile(vector::resolveDatasetPath(run_folder)))
              .add("concrete_sha256", sha256OfFile(run_folder / "concrete.csv"));
          (train ? label_data.trainRun : label_data.testRun) = run_folder;
          (train ? label_data.trainDigest : label_data.testDigest) = run_key.digest();
        }
      }
      data_[source.label] = label_data;
    }
  }

  // --- models ------------------------------------------------------------------
  /// The seeds a row of a model is trained with: the model's own `seeds`, else several for
  /// the main model's `seeds.rows`.
  std::vector<std::uint64_t> seedsOf(std::size_t model_index, int row) const {
    const bool repeated = model_index == 0 &&
                          std::find(spec_.seedRows.begin(), spec_.seedRows.end(), row) != spec_.seedRows.end();
    const int own = spec_.models[model_index].seeds;
    const int count = own > 0 ? own : (repeated ? spec_.seedCount : 1);
    std::vector<std::uint64_t> seeds;
    for (int i = 0; i < count; ++i) seeds.push_back(spec_.seed + static_cast<std::uint64_t>(i));
    return seeds;
  }

  static model::Mix mixOf(const AdeSpec& row) {
    model::Mix mix;
    for (const auto& [label, count] : row.mix) {
      if (count > 0) mix.counts.emplace_back(label, count);
    }
    return mix;
  }

  /// One training of the experiment: a row of a model with one seed, and its cache entry.
  struct TrainingJob {
    const ModelSpec* model = nullptr;
    model::Mix mix;
    std::uint64_t seed = 0;
    std::string what;
    fs::path folder;
    CacheKey key{"model"};
    int row = 0;
  };

  void trainModels() {
    std::vector<TrainingJob> jobs;
    for (std::size_t m = 0; m < spec_.models.size(); ++m) {
      const auto& model_spec = spec_.models[m];
      for (const auto& row : spec_.ade) {
        if (!model_spec.trains(row.row)) continue;
        const auto mix = mixOf(row);
        if (mix.counts.empty()) {
          throw ConfigError(fmt::format("{}: ade row {}: the mix holds no sample", spec_.file.string(), row.row));
        }
        for (const auto seed : seedsOf(m, row.row)) jobs.push_back(trainingJob(model_spec, row, mix, seed));
      }
    }
    std::vector<const TrainingJob*> pending;
    for (const auto& job : jobs) {
      if (!reuse(job.folder, job.key, job.what)) pending.push_back(&job);
    }
    trainInParallel(pending);
    for (const auto& job : jobs) {
      runs_.push_back({job.model->name, job.row, job.seed, {job.folder / "model.pt", job.key.digest(), job.seed},
                       readJson(job.folder / "training.json")});
    }
  }

  TrainingJob trainingJob(const ModelSpec& model_spec, const AdeSpec& row, const model::Mix& mix, std::uint64_t seed) {
    TrainingJob job;
    job.model = &model_spec;
    job.mix = mix;
    job.seed = seed;
    job.row = row.row;
    job.folder = cache_.folder(fmt::format("models/{}/row{}_seed{}", model_spec.name, row.row, seed));
    job.key = key("model", modelModules());
    job.key.add("mix", mix.str());
    for (const auto& [label, count] : mix.counts) job.key.add("data_" + label, data(label).trainDigest);
    job.key.add("decoder", model_spec.decoder).add("frame", model_spec.frame);
    for (const auto& [option, value] : model_spec.options) job.key.add("decoder_option_" + option, value);
    job.key.add("seed", seed)
        .add("steps", spec_.steps)
        .add("batch", spec_.batch)
        .add("learning_rate", spec_.learningRate)
        .add("threads", spec_.threads);
    job.what = fmt::format("{} row {} seed {} model ({})", model_spec.name, row.row, seed, mix.str());
    return job;
  }

  /// Runs the trainings `training.parallel` at a time, each on `training.threads` threads.
  /// A training's result depends on its own options only (model::train seeds its
  /// initialisation under a lock), so the order in which they finish changes nothing. After
  /// a failure no new training starts; the first error is rethrown once the others ended.
  void trainInParallel(const std::vector<const TrainingJob*>& pending) {
    std::atomic<std::size_t> next{0};
    std::atomic<bool> failed{false};
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(spec_.parallel));
    auto work = [&](std::size_t worker) {
      try {
        for (std::size_t i = next++; i < pending.size() && !failed; i = next++) {
          throwIfInterrupted();
          const auto& job = *pending[i];
          train(job.what, job.folder, *job.model, job.mix, job.seed, job.key);
        }
      } catch (...) {
        errors[worker] = std::current_exception();
        failed = true;
      }
    };
    std::vector<std::thread> workers;
    const auto count = std::min(pending.size(), static_cast<std::size_t>(spec_.parallel));
    for (std::size_t w = 1; w < count; ++w) workers.emplace_back(work, w);
    work(0);
    for (auto& worker : workers) worker.join();
    for (const auto& error : errors) {
      if (error) std::rethrow_exception(error);
    }
  }

  void train(const std::string& what, const fs::path& folder, const ModelSpec& model_spec, const model::Mix& mix,
             std::uint64_t seed, const CacheKey& model_key) {
    // A training interrupted earlier with the same key continues from its last state.
    const fs::path pending(folder.string() + ".pending");
    bool resume = false;
    try {
      resume = fs::is_regular_file(pending) && readTextFile(pending) == model_key.text() &&
               fs::is_regular_file(folder / "model.pt.last");
    } catch (const IoError&) {
      resume = false;
    }
    if (!resume) {
      cache_.clear(folder);
      writeTextFileAtomically(pending, model_key.text());
    }
    model::TrainOptions train_options;
    for (const auto& [label, count] : mix.counts) train_options.data.push_back(data(label).trainRun);
    train_options.mix = mix;
    train_options.output = folder / "model.pt";
    train_options.config.decoder = model_spec.decoder;
    train_options.config.decoderOptions = model_spec.options;
    train_options.config.frame = model_spec.frame;
    train_options.seed = seed;
    train_options.threads = spec_.threads;
    train_options.steps = spec_.steps;
    train_options.batchSize = spec_.batch;
    train_options.learningRate = spec_.learningRate;
    train_options.resume = resume;
    bindCalibrationMetrics(train_options);
    spdlog::info("{}: training{}", what, resume ? " (resuming)" : "");
    auto last_line = std::chrono::steady_clock::now();
    const auto trained = model::train(train_options, [&](const model::EpochRecord& record) {
      // One line every 20 s keeps logs short; the best epochs are what matters.
      if (secondsSince(last_line) < 20.0 && record.epoch != record.plannedEpochs) return;
      last_line = std::chrono::steady_clock::now();
      spdlog::info("{}: epoch {}/{}, train loss {:.3f} m, validation ADE {:.3f} m", what, record.epoch,
                   record.plannedEpochs, record.trainLoss, record.validationAde);
    });
    json record;
    record["seconds"] = trained.seconds;
    record["epochs"] = static_cast<int>(trained.epochs.size());
    record["best_epoch"] = trained.bestEpoch;
    record["best_validation_ade"] = trained.bestValidationAde;
    record["samples_per_second"] = trained.samplesPerSecond;
    record["stop_reason"] = trained.stopReason;
    writeJson(folder / "training.json", record);
    spdlog::info("{}: best validation ADE {:.3f} m at epoch {} ({:.0f} s, {})", what, trained.bestValidationAde,
                 trained.bestEpoch, trained.seconds, trained.stopReason);
    cache_.commit(folder, model_key);
    std::error_code ignored;
    fs::remove(pending, ignored);
  }

  // --- evaluation ----------------------------------------------------------------
  /// ADE/FDE of every trained model and every predictor on every test set, then the
  /// table's rows: per (model, row) the mean and spread over the seeds.
  void evaluateModels() {
    std::map<std::pair<std::string, int>, std::vector<json>> errors_by_row;
    for (const auto& run : runs_) {
      throwIfInterrupted();
      const auto errors = evaluate(run.modelFile.file, run.modelFile.digest,
                                   fmt::format("eval/{}/row{}_seed{}", run.model, run.row, run.seed),
                                   fmt::format("{} row {} seed {}", run.model, run.row, run.seed),
                                   testLabelsOf(spec_.row(run.row)));
      errors_by_row[{run.model, run.row}].push_back(errors);
      if (run.seed == spec_.seed) rowModels_[{run.model, run.row}] = run.modelFile;
      if (run.model == spec_.models.front().name && run.seed == spec_.seed) {
        for (const auto& [label, entry] : errors.items()) {
          medianSample_[{run.row, label}] = {entry.at("median_sample").get<std::size_t>(),
                                             entry.at("median_ade").get<double>()};
        }
      }
    }
    for (const auto& model_spec : spec_.models) {
      for (const auto& row : spec_.ade) {
        const auto found = errors_by_row.find({model_spec.name, row.row});
        if (found != errors_by_row.end()) summary_.ade.push_back(adeRow(model_spec.name, row, found->second));
      }
    }
    for (const auto& predictor : spec_.predictors) {
      throwIfInterrupted();
      AdeSpec no_training;
      summary_.ade.push_back(
          adeRow(predictor, no_training, {evaluate(predictor, "", "eval/" + predictor, predictor, allLabels())}));
    }
  }

  std::vector<std::string> allLabels() const {
    std::vector<std::string> labels;
    for (const auto& source : spec_.sources) labels.push_back(source.label);
    return labels;
  }

  /// The test sets a row is evaluated on: a leave-one-out row's held-out one, else all.
  std::vector<std::string> testLabelsOf(const AdeSpec& row) const {
    return row.heldOut.empty() ? allLabels() : std::vector<std::string>{row.heldOut};
  }

  /// errors.json of one model file or predictor ("cv", "ca") on the test sets of `labels`, cached.
  json evaluate(const fs::path& model, const std::string& model_digest, const std::string& relative,
                const std::string& what, const std::vector<std::string>& labels) {
    const auto folder = cache_.folder(relative);
    auto eval_key = key("evaluation", modelModules());
    eval_key.add("model", model_digest.empty() ? model.string() : model_digest);
    for (const auto& label : labels) eval_key.add("test_" + label, data(label).testDigest);
    if (!reuse(folder, eval_key, what + " evaluation")) {
      cache_.clear(folder);
      const model::Predictor predictor(model, spec_.cores());
      json errors;
      for (const auto& label : labels) errors[label] = displacementSummary(predictor, label, what);
      writeJson(folder / "errors.json", errors);
      cache_.commit(folder, eval_key);
    }
    return readJson(folder / "errors.json");
  }

  json displacementSummary(const model::Predictor& predictor, const std::string& label, const std::string& what) {
    const auto& scenes = testScenes(label);
    const auto predictions = predictor.predict(scenes);
    std::vector<double> per_sample;
    double ade_sum = 0.0;
    double fde_sum = 0.0;
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      const auto sample = model::displacementErrors(predictions[i], scenes[i]);
      ade_sum += sample.ade;
      fde_sum += sample.fde;
      per_sample.push_back(sample.ade);
    }
    const std::size_t median_sample = upperMedianIndex(per_sample);
    spdlog::info("{} on {}: ADE {:.3f} m over {} scenes", what, label, mean(ade_sum, scenes.size()), scenes.size());
    return {{"samples", scenes.size()},
            {"ade", mean(ade_sum, scenes.size())},
            {"fde", mean(fde_sum, scenes.size())},
            {"median_ade", per_sample[median_sample]},
            {"median_sample", median_sample}};
  }

  /// A table row from the evaluations of its seeds (one for predictors).
  AdeRow adeRow(const std::string& model_name, const AdeSpec& row, const std::vector<json>& evaluations) const {
    AdeRow ade_row;
    ade_row.row = row.row;
    ade_row.model = model_name;
    for (const auto& [label, count] : row.mix) ade_row.mix[label] = count;
    ade_row.paper = row.paper;
    if (!row.heldOut.empty()) {
      ade_row.heldOut = row.heldOut;
      ade_row.training = heldOutTrainingId(row.training);
    }
    for (const auto& source : spec_.sources) {
      if (!evaluations.front().contains(source.label)) continue;  // a leave-one-out row's other labels
      std::vector<double> ade;
      std::vector<double> fde;
      for (const auto& errors : evaluations) {
        ade.push_back(errors.at(source.label).at("ade").get<double>());
        fde.push_back(errors.at(source.label).at("fde").get<double>());
      }
      ade_row.ade[source.label] = sampleMean(ade);
      ade_row.fde[source.label] = sampleMean(fde);
      if (ade.size() > 1) ade_row.adeStd[source.label] = sampleStd(ade);
    }
    bool first = true;
    for (const auto& run : runs_) {
      if (run.model != model_name || run.row != row.row) continue;
      ade_row.seeds.push_back(run.seed);
      ade_row.trainSeconds += run.training.at("seconds").get<double>();
      if (first) {
        ade_row.epochs = run.training.at("epochs").get<int>();
        ade_row.stopReason = run.training.at("stop_reason").get<std::string>();
        first = false;
      }
    }
    if (!ade_row.seeds.empty()) ade_row.trainSeconds /= static_cast<double>(ade_row.seeds.size());
    return ade_row;
  }

  // --- metric MAE ------------------------------------------------------------------
  /// The models predicting a functional scenario in the MAE table: every model of the spec
  /// that trains its `mae.vectornet_rows` row, each with every seed it is trained with, the
  /// main model first.
  std::vector<std::pair<std::string, RowModel>> maeModels(const std::string& label) const {
    std::vector<std::pair<std::string, RowModel>> models;
    const int row = spec_.vectornetRows.at(label);
    for (const auto& model_spec : spec_.models) {
      for (const auto& run : runs_) {
        if (run.model == model_spec.name && run.row == row) models.emplace_back(model_spec.name, run.modelFile);
      }
    }
    return models;
  }

  /// Extra trees and the BNN are fitted with as many seeds as the rows that carry findings.
  std::size_t baselineSeeds() const { return static_cast<std::size_t>(std::max(1, spec_.seedCount)); }

  /// The key of a functional scenario's metric errors: its data, the baselines' settings and
  /// training rows (`rows`: field and value), the draws and every VectorNet model scored.
  CacheKey metricErrorsKey(const std::string& kind, int format, const std::string& label,
                           const std::vector<std::string>& names, const std::pair<std::string, std::string>& rows,
                           const std::vector<std::pair<std::string, RowModel>>& models) const {
    auto errors_key = key(kind, maeModules());
    if (format > 0) errors_key.add("format", format);
    errors_key.add("metrics", fmt::format("{}", fmt::join(names, ",")))
        .add("train", data(label).trainDigest)
        .add("test", data(label).testDigest)
        .add(rows.first, rows.second)
        .add("et", fmt::format("trees {} max_features {} min_samples_split {} seed {}", spec_.extraTrees.trees,
                               spec_.extraTrees.maxFeatures, spec_.extraTrees.minSamplesSplit, spec_.extraTrees.seed))
        .add("bnn", fmt::format("hidden {} layers {} epochs {} samples {} seed {}", spec_.bnn.hidden, spec_.bnn.layers,
                                spec_.bnn.epochs, spec_.bnn.samples, spec_.bnn.seed))
        .add("draws", fmt::format("{} seed {}", spec_.maeDraws, spec_.seed));
    for (const auto& [name, row_model] : models) {
      // The first seed's entry keeps its name, so keys of single-seed studies stay as they were.
      const auto entry = row_model.seed == spec_.seed ? name : fmt::format("{}_seed{}", name, row_model.seed);
      errors_key.add("vectornet_model_" + entry, row_model.digest);
    }
    return errors_key;
  }

  void compareMetrics() {
    std::vector<std::string> labels;
    for (const auto& item : spec_.maeMetrics) {
      if (std::find(labels.begin(), labels.end(), item.label) == labels.end()) labels.push_back(item.label);
    }
    for (const auto& label : labels) {
      throwIfInterrupted();
      std::vector<std::string> names;
      for (const auto& item : spec_.maeMetrics) {
        if (item.label == label) names.push_back(item.metric);
      }
      const auto models = maeModels(label);
      const auto folder = cache_.folder("mae/" + label);
      // format 3: every model's errors, bias and interval coverage per seed; the baselines per seed
      auto mae_key = metricErrorsKey("metric mae", 3, label, names,
                                     {"train_rows", fmt::format("{}", spec_.maeSamples)}, models);
      mae_key.add("baseline_seeds", baselineSeeds());
      if (!reuse(folder, mae_key, fmt::format("{} metric MAE", label))) {
        cache_.clear(folder);
        writeJson(folder / "mae.json", computeMae(label, names, models));
        cache_.commit(folder, mae_key);
      }
      addMaeRows(label, names, readJson(folder / "mae.json"));
    }
  }

  void addMaeRows(const std::string& label, const std::vector<std::string>& names, const json& results) {
    for (const auto& name : names) {
      const auto& entry = results.at("metrics").at(name);
      MaeRow mae_row;
      mae_row.label = label;
      mae_row.metric = name;
      mae_row.unit = metrics::findMetric(name)->unit;
      const auto et = entry.at("et").get<std::vector<double>>();
      const auto bnn = entry.at("bnn").get<std::vector<double>>();
      mae_row.baselineSeeds = et.size();
      mae_row.et = sampleMean(et);
      mae_row.bnn = sampleMean(bnn);
      if (et.size() > 1) {
        mae_row.etSpread = sampleStd(et);
        mae_row.bnnSpread = sampleStd(bnn);
      }
      mae_row.bnnStd = entry.at("bnn_std").get<double>();
      mae_row.fromTruePositions = entry.at("from_true_positions").get<double>();
      for (const auto& model_spec : spec_.models) {
        std::vector<const json*> seeds;
        for (const auto& model : results.at("vectornet")) {
          if (model.at("model").get<std::string>() == model_spec.name) seeds.push_back(&model);
        }
        if (!seeds.empty()) mae_row.vectornet.push_back(metricErrorOverSeeds(seeds, name));
      }
      mae_row.etSeconds = results.at("et_seconds").get<double>();
      mae_row.bnnSeconds = results.at("bnn_seconds").get<double>();
      mae_row.trainRows = results.at("train_rows").get<std::size_t>();
      for (const auto& item : spec_.maeMetrics) {
        if (item.label == label && item.metric == name) mae_row.paper = item.paper;
      }
      summary_.mae.push_back(mae_row);
    }
  }

  /// The regression metamodels on the concrete inputs of `label`: extra trees and the BNN
  /// fitted on its first `train_rows` training rows (with the spec's seeds + `seed_offset`),
  /// scored on its test set.
  std::pair<baseline::BaselineReport, baseline::BaselineReport> fitBaselines(const std::string& label,
                                                                             const std::vector<std::string>& names,
                                                                             std::size_t train_rows,
                                                                             std::uint64_t seed_offset = 0) const {
    const auto& label_data = data(label);
    baseline::BaselineOptions baseline_options;
    baseline_options.train = label_data.trainRun;
    baseline_options.test = label_data.testRun;
    baseline_options.targets = names;
    baseline_options.maxTrainRows = train_rows;
    baseline_options.extraTrees = spec_.extraTrees;
    baseline_options.extraTrees.seed += seed_offset;
    baseline_options.bnn = spec_.bnn;
    baseline_options.bnn.seed += seed_offset;
    baseline_options.bnn.threads = spec_.cores();
    baseline_options.model = "et";
    auto et = baseline::runBaseline(baseline_options);
    baseline_options.model = "bnn";
    auto bnn = baseline::runBaseline(baseline_options);
    spdlog::info("{}: extra trees {:.1f} s, BNN {:.1f} s (fit + predict, {} training rows, {} test rows)", label,
                 et.fitSeconds + et.predictSeconds, bnn.fitSeconds + bnn.predictSeconds, et.trainRows, et.testRows);
    return {std::move(et), std::move(bnn)};
  }

  json computeMae(const std::string& label, const std::vector<std::string>& names,
                  const std::vector<std::pair<std::string, RowModel>>& models) {
    const auto& label_data = data(label);
    json results;
    // Per metric the MAE of every baseline seed; times are means over the seeds.
    std::vector<std::vector<double>> et_mae(names.size());
    std::vector<std::vector<double>> bnn_mae(names.size());
    std::vector<double> bnn_std(names.size(), 0.0);
    double et_seconds = 0.0;
    double bnn_seconds = 0.0;
    for (std::uint64_t offset = 0; offset < baselineSeeds(); ++offset) {
      const auto [et, bnn] = fitBaselines(label, names, spec_.maeSamples, offset);
      et_seconds += et.fitSeconds + et.predictSeconds;
      bnn_seconds += bnn.fitSeconds + bnn.predictSeconds;
      for (std::size_t m = 0; m < names.size(); ++m) {
        et_mae[m].push_back(et.mae[m]);
        bnn_mae[m].push_back(bnn.mae[m]);
        if (offset == 0 && !bnn.meanStd.empty()) bnn_std[m] = bnn.meanStd[m];
      }
      results["train_rows"] = et.trainRows;
      results["test_rows"] = et.testRows;
    }
    results["et_seconds"] = et_seconds / static_cast<double>(baselineSeeds());
    results["bnn_seconds"] = bnn_seconds / static_cast<double>(baselineSeeds());

    // VectorNet: the metric code of simulated runs on the predicted Ego trajectory,
    // with the recorded trajectories of the other vehicles.
    const auto& scenes = testScenes(label);
    const vector::DatasetReader reader(vector::resolveDatasetPath(label_data.testRun));
    const auto simulated = simulatedMetrics(reader, names);
    const metrics::MetricSet metric_set(names, pipeline::sceneAvailability(reader.header().kind),
                                        fmt::format("{}: mae.metrics.{}", spec_.file.string(), label));
    std::vector<double> true_sum(names.size(), 0.0);
    std::vector<std::size_t> true_counted(names.size(), 0);
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      const auto from_truth = pipeline::metricsOfFuture(metric_set, scenes[i], scenes[i].target);
      for (std::size_t m = 0; m < names.size(); ++m) {
        // Infinite values (e.g. ttc_min without closing in) and NaN have no error to average.
        if (!std::isfinite(simulated[i][m]) || !std::isfinite(from_truth[m])) continue;
        true_sum[m] += std::abs(from_truth[m] - simulated[i][m]);
        ++true_counted[m];
      }
    }
    for (std::size_t m = 0; m < names.size(); ++m) {
      results["metrics"][names[m]] = {{"et", et_mae[m]},
                                      {"bnn", bnn_mae[m]},
                                      {"bnn_std", bnn_std[m]},
                                      {"from_true_positions", mean(true_sum[m], true_counted[m])}};
    }
    results["vectornet"] = json::array();
    for (const auto& [model_name, row_model] : models) {
      results["vectornet"].push_back(vectornetErrors(model_name, row_model, scenes, simulated, metric_set));
      for (std::size_t m = 0; m < names.size(); ++m) {
        const auto& errors = results["vectornet"].back()["metrics"][names[m]];
        spdlog::info("{} {}: MAE extra trees {:.3f}, BNN {:.3f}, VectorNet {} seed {} {:.3f} (true positions {:.3f})",
                     label, names[m], et_mae[m].front(), bnn_mae[m].front(), model_name, row_model.seed,
                     errors["mae"].get<double>(), mean(true_sum[m], true_counted[m]));
      }
    }
    return results;
  }

  // --- leave one functional scenario out --------------------------------------------------
  /// The leave-one-out rows of `held_out` in HeldOutTraining order.
  std::vector<const AdeSpec*> heldOutRows(const std::string& held_out) const {
    std::vector<const AdeSpec*> rows;
    for (const auto& row : spec_.ade) {
      if (row.heldOut == held_out) rows.push_back(&row);
    }
    return rows;
  }

  /// Own training samples of a held-out row (its mix's count of the held-out label).
  static std::size_t ownSamples(const AdeSpec& row) {
    for (const auto& [label, count] : row.mix) {
      if (label == row.heldOut) return count;
    }
    return 0;
  }

  /// The study's metrics that the held-out scenario's test set stores.
  std::vector<std::string> heldOutMetricNames(const std::string& label) const {
    const vector::DatasetReader reader(vector::resolveDatasetPath(data(label).testRun));
    const auto& stored = reader.header().metricNames;
    std::vector<std::string> names;
    for (const auto& name : spec_.leaveOneOut.metrics) {
      if (std::find(stored.begin(), stored.end(), name) != stored.end()) names.push_back(name);
    }
    return names;
  }

  /// Per held-out scenario: the metric errors of the main model of each of its rows, and of
  /// extra trees and the BNN fitted on as many of its own samples as the own-data rows use.
  void compareHeldOut() {
    for (const auto& label : spec_.leaveOneOut.heldOut) {
      throwIfInterrupted();
      const auto names = heldOutMetricNames(label);
      if (names.empty()) continue;
      std::vector<std::pair<std::string, RowModel>> models;
      std::vector<std::size_t> own_sizes;
      for (const auto* row : heldOutRows(label)) {
        models.emplace_back(heldOutTrainingId(row->training), rowModels_.at({spec_.models.front().name, row->row}));
        if (row->training == HeldOutTraining::FewOwn || row->training == HeldOutTraining::AllOwn) {
          own_sizes.push_back(ownSamples(*row));
        }
      }
      const auto folder = cache_.folder("held_out/" + label);
      const auto held_key = metricErrorsKey("held-out metric errors", 0, label, names,
                                            {"own_rows", fmt::format("{}", fmt::join(own_sizes, ","))}, models);
      if (!reuse(folder, held_key, fmt::format("{} held-out metric errors", label))) {
        cache_.clear(folder);
        writeJson(folder / "errors.json", heldOutErrors(label, names, models, own_sizes));
        cache_.commit(folder, held_key);
      }
      addHeldOutMetrics(label, names, readJson(folder / "errors.json"));
    }
  }

  json heldOutErrors(const std::string& label, const std::vector<std::string>& names,
                     const std::vector<std::pair<std::string, RowModel>>& models,
                     const std::vector<std::size_t>& own_sizes) {
    json results;
    for (const auto rows : own_sizes) {
      const auto [et, bnn] = fitBaselines(label, names, rows);
      for (std::size_t m = 0; m < names.size(); ++m) {
        results["baselines"].push_back({{"train_rows", et.trainRows}, {"metric", names[m]}, {"et", et.mae[m]},
                                        {"bnn", bnn.mae[m]}});
      }
    }
    const auto& scenes = testScenes(label);
    const vector::DatasetReader reader(vector::resolveDatasetPath(data(label).testRun));
    const auto simulated = simulatedMetrics(reader, names);
    const metrics::MetricSet metric_set(names, pipeline::sceneAvailability(reader.header().kind),
                                        fmt::format("{}: leave_one_out.metrics ({})", spec_.file.string(), label));
    results["vectornet"] = json::array();
    for (const auto& [training, row_model] : models) {
      results["vectornet"].push_back(vectornetErrors(training, row_model, scenes, simulated, metric_set));
    }
    return results;
  }

  void addHeldOutMetrics(const std::string& label, const std::vector<std::string>& names, const json& results) {
    for (const auto& name : names) {
      HeldOutMetric metric;
      metric.label = label;
      metric.metric = name;
      metric.unit = metrics::findMetric(name)->unit;
      for (const auto& model : results.at("vectornet")) metric.vectornet.push_back(metricError(model, name));
      for (const auto& entry : results.at("baselines")) {
        if (entry.at("metric").get<std::string>() != name) continue;
        const auto rows = entry.at("train_rows").get<std::size_t>();
        metric.et[rows] = entry.at("et").get<double>();
        metric.bnn[rows] = entry.at("bnn").get<double>();
      }
      summary_.heldOut.push_back(std::move(metric));
    }
  }

  /// The simulated value of every metric of `names` per test scene (the stored metrics).
  static std::vector<std::vector<double>> simulatedMetrics(const vector::DatasetReader& reader,
                                                          const std::vector<std::string>& names) {
    const auto& stored = reader.header().metricNames;
    std::vector<std::size_t> stored_index;
    for (const auto& name : names) {
      const auto found = std::find(stored.begin(), stored.end(), name);
      if (found == stored.end()) {
        throw DatasetError(fmt::format("{}: the test set has no metric '{}' (it has: {})", reader.path().string(), name,
                                       fmt::join(stored, ", ")));
      }
      stored_index.push_back(static_cast<std::size_t>(found - stored.begin()));
    }
    std::vector<std::vector<double>> values;
    values.reserve(reader.size());
    for (std::size_t i = 0; i < reader.size(); ++i) {
      const auto scene = reader.scene(i);
      std::vector<double> row;
      for (const auto index : stored_index) row.push_back(scene.metrics.at(index));
      values.push_back(std::move(row));
    }
    return values;
  }

  /// One model's metric errors on a test set: MAE and bias of the most likely future's
  /// metrics (its own states where it has them), and for a probabilistic model the coverage
  /// of the metrics' intervals over mae.draws sampled futures.
  json vectornetErrors(const std::string& model_name, const RowModel& row_model,
                       const std::vector<vector::VectorizedScene>& scenes,
                       const std::vector<std::vector<double>>& simulated, const metrics::MetricSet& metric_set) const {
    const model::Predictor predictor(row_model.file, spec_.cores());
    model::PredictOptions draw_options;
    draw_options.samples = predictor.probabilistic() ? spec_.maeDraws : 0;
    draw_options.seed = spec_.seed;
    const auto metrics_of = [&](const vector::VectorizedScene& scene, const model::Trajectory& future) {
      return pipeline::metricsOfFuture(metric_set, scene, future.positions, future.states);
    };
    const std::size_t count = metric_set.names().size();
    std::vector<double> error_sum(count, 0.0);
    std::vector<double> signed_sum(count, 0.0);
    std::vector<std::size_t> scored(count, 0);
    std::vector<std::array<std::size_t, 2>> covered(count, {0, 0});
    std::vector<std::size_t> with_interval(count, 0);
    // Chunks keep the sampled futures of a 10,000-scene test set out of memory at once.
    constexpr std::size_t kChunk = 512;
    for (std::size_t first = 0; first < scenes.size(); first += kChunk) {
      throwIfInterrupted();
      const std::vector<vector::VectorizedScene> chunk(
          scenes.begin() + static_cast<std::ptrdiff_t>(first),
          scenes.begin() + static_cast<std::ptrdiff_t>(std::min(scenes.size(), first + kChunk)));
      const auto predictions = predictor.predictDistribution(chunk, draw_options);
      for (std::size_t i = 0; i < chunk.size(); ++i) {
        const auto& truth = simulated[first + i];
        const auto predicted = metrics_of(chunk[i], predictions[i].mostLikely);
        const auto draws = model::metricDraws(chunk[i], predictions[i], metrics_of, count);
        for (std::size_t m = 0; m < count; ++m) {
          if (!std::isfinite(truth[m]) || !std::isfinite(predicted[m])) continue;
          error_sum[m] += std::abs(predicted[m] - truth[m]);
          signed_sum[m] += predicted[m] - truth[m];
          ++scored[m];
          if (draws[m].empty()) continue;
          const auto interval =
              model::intervalOf(draws[m], predictor.info().metricIntervals.find(chunk[i].label, metric_set.names()[m]));
          if (interval.draws == 0) continue;
          ++with_interval[m];
          covered[m][0] += interval.contains(truth[m], 0.5) ? 1 : 0;
          covered[m][1] += interval.contains(truth[m], 0.9) ? 1 : 0;
        }
      }
    }
    json errors;
    errors["model"] = model_name;
    errors["seed"] = row_model.seed;
    errors["decoder"] = predictor.name();
    for (std::size_t m = 0; m < count; ++m) {
      const bool has_intervals = with_interval[m] > 0;
      errors["metrics"][metric_set.names()[m]] = {
          {"mae", mean(error_sum[m], scored[m])},
          {"bias", mean(signed_sum[m], scored[m])},
          {"samples", scored[m]},
          {"interval_samples", with_interval[m]},
          {"coverage50", has_intervals ? json(mean(static_cast<double>(covered[m][0]), with_interval[m])) : json()},
          {"coverage90", has_intervals ? json(mean(static_cast<double>(covered[m][1]), with_interval[m])) : json()}};
    }
    return errors;
  }

  // --- figures ----------------------------------------------------------------------
  void drawFigures() {
    if (spec_.figures.empty()) return;
    for (const auto& figure : spec_.figures) {
      const model::Predictor predictor(rowModels_.at({spec_.models.front().name, figure.row}).file, spec_.cores());
      std::vector<std::string> panels;
      for (const auto& source : spec_.sources) {
        const auto [sample, ade] = medianSample_.at({figure.row, source.label});
        const vector::DatasetReader reader(vector::resolveDatasetPath(data(source.label).testRun));
        const auto scene = reader.scene(sample);
        const auto prediction = predictor.predict({scene}).front();
        panels.push_back(vector::renderSceneSvg(
            scene, {{"VectorNet prediction", prediction, "#d62728", true}},
            fmt::format("{}: test sample {} (median ADE {:.2f} m)", source.label, scene.sample, ade), 560));
      }
      const auto relative = fs::path("figures") / (figure.name + ".svg");
      const std::string title = fmt::format("{} (row {}; test scenes of median ADE)",
                                            figure.title.empty() ? figure.name : figure.title, figure.row);
      folder_->stageText(relative, composeSvgRow(panels, title));
      summary_.files.push_back(output_ / relative);
    }
  }

  const ExperimentOptions& options_;
  Spec spec_;
  fs::path output_;
  std::optional<OutputFolder> folder_;
  ArtefactCache cache_;
  ExperimentSummary summary_;
  std::vector<ArtefactRecord> artefacts_;
  std::map<std::string, LabelData> data_;
  std::vector<TrainedRun> runs_;
  /// The first seed's model file per (model name, row): the MAE table and the figures use them.
  std::map<std::pair<std::string, int>, RowModel> rowModels_;
  std::map<std::string, std::vector<vector::VectorizedScene>> testScenes_;
  std::map<std::pair<int, std::string>, std::pair<std::size_t, double>> medianSample_;
};

}  // namespace

ExperimentSummary runExperiment(const ExperimentOptions& options) {
  auto spec = parseSpec(options.spec, options.quick);
  fs::path output = options.output;
  if (output.empty()) output = fs::path("results") / (spec.name + (options.quick ? "-quick" : ""));
  refuseDirtyCommittedResults(output, options.allowDirty, "--allow-dirty");
  // The output policy (docs/output-policy.md): a re-run of the same experiment resumes from its cache.
  checkOutput({output, &output_kinds::experimentFolder(), spec.name, options.force, "--out", "--force",
               {{"spec", options.spec}}});
  return ExperimentRunner(options, std::move(spec), output).run();
}

std::shared_ptr<const model::MetricBinding> futureMetricBinding(const fs::path& data) {
  const vector::DatasetReader reader(vector::datasetFiles(data).front());
  const auto metric_set = std::make_shared<const metrics::MetricSet>(
      std::vector<std::string>{}, pipeline::sceneAvailability(reader.header().kind), data.string());
  auto binding = std::make_shared<model::MetricBinding>();
  binding->names = metric_set->names();
  binding->compute = [metric_set](const vector::VectorizedScene& scene, const model::Trajectory& future) {
    return pipeline::metricsOfFuture(*metric_set, scene, future.positions, future.states);
  };
  return binding;
}

void bindCalibrationMetrics(model::TrainOptions& options) {
  const auto calibrate = options.config.decoderOptions.find("calibrate");
  if (calibrate == options.config.decoderOptions.end() || calibrate->second == 0.0 || options.data.empty()) return;
  options.metrics = futureMetricBinding(options.data.front());
}

}  // namespace vsd::experiment
