// `vsd-sumo experiment`: the stages of the paper's experiments with an artefact
// cache (cache.hpp). Stages, in order:
//   data     per functional scenario a training pool and a test set (vsd-sumo run)
//   models   one VectorNet per ADE row (its training mix)
//   eval     every model on every test set: ADE/FDE, and the sample of median ADE
//   mae      extra trees, BNN (on concrete inputs) and VectorNet (metrics of the
//            predicted trajectory) against the simulated metrics of the test set
//   figures  example predictions like the paper's figures 6-8
//   results  tables, findings and manifest (results.cpp)
#include "vsd/experiment/experiment.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
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
#include "vsd/core/progress.hpp"
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

struct RowModel {
  fs::path file;
  std::string digest;
};

json readJson(const fs::path& path) {
  try {
    return json::parse(readTextFile(path));
  } catch (const json::exception& error) {
    throw IoError(fmt::format("{}: not valid JSON ({})", path.string(), error.what()));
  }
}

void writeJson(const fs::path& path, const json& value) { writeTextFileAtomically(path, value.dump(2) + "\n"); }

double mean(double sum, std::size_t count) {
  return count == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(count);
}

class ExperimentRunner {
 public:
  ExperimentRunner(const ExperimentOptions& options, Spec spec, fs::path output)
      : options_(options), spec_(std::move(spec)), output_(std::move(output)), cache_(output_ / "cache") {}

  ExperimentSummary run() {
    const auto start = std::chrono::steady_clock::now();
    const auto logical_scenarios = checkSources();
    ensureDirectory(output_);
    // The manifest marks a complete result set: gone until this run completes.
    std::error_code ignored;
    fs::remove(output_ / "manifest.json", ignored);

    prepareData(logical_scenarios);
    trainModels();
    evaluateModels();
    compareMetrics();
    drawFigures();
    summary_.output = output_;
    summary_.findings = checkFindings(summary_.ade);
    summary_.seconds = secondsSince(start);
    writeResults(spec_, options_, summary_, artefacts_);
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

  CacheKey key(const std::string& kind) const {
    CacheKey key(kind);
    key.add("tool_version", toolVersion());
    return key;
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
          auto run_key = key("run");
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
          auto run_key = key("existing run");
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
  void trainModels() {
    for (const auto& row : spec_.ade) {
      throwIfInterrupted();
      model::Mix mix;
      for (const auto& [label, count] : row.mix) {
        if (count > 0) mix.counts.emplace_back(label, count);
      }
      if (mix.counts.empty()) {
        throw ConfigError(fmt::format("{}: ade row {}: the mix holds no sample", spec_.file.string(), row.row));
      }
      const auto folder = cache_.folder(fmt::format("models/row{}", row.row));
      auto model_key = key("model");
      model_key.add("mix", mix.str());
      for (const auto& [label, count] : mix.counts) model_key.add("data_" + label, data(label).trainDigest);
      model_key.add("seed", spec_.seed)
          .add("steps", spec_.steps)
          .add("batch", spec_.batch)
          .add("learning_rate", spec_.learningRate)
          .add("threads", spec_.threads);
      const std::string what = fmt::format("row {} model ({})", row.row, mix.str());
      if (!reuse(folder, model_key, what)) train(row.row, folder, mix, model_key);
      models_[row.row] = {folder / "model.pt", model_key.digest()};

      const auto record = readJson(folder / "training.json");
      AdeRow ade_row;
      ade_row.row = row.row;
      for (const auto& [label, count] : row.mix) ade_row.mix[label] = count;
      ade_row.paper = row.paper;
      ade_row.trainSeconds = record.at("seconds").get<double>();
      ade_row.epochs = record.at("epochs").get<int>();
      ade_row.stopReason = record.at("stop_reason").get<std::string>();
      summary_.ade.push_back(ade_row);
    }
  }

  void train(int row, const fs::path& folder, const model::Mix& mix, const CacheKey& model_key) {
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
    train_options.seed = spec_.seed;
    train_options.threads = spec_.threads;
    train_options.steps = spec_.steps;
    train_options.batchSize = spec_.batch;
    train_options.learningRate = spec_.learningRate;
    train_options.resume = resume;
    spdlog::info("row {} model ({}): training{}", row, mix.str(), resume ? " (resuming)" : "");
    auto last_line = std::chrono::steady_clock::now();
    const auto trained = model::train(train_options, [&](const model::EpochRecord& record) {
      // One line every 20 s keeps logs short; the best epochs are what matters.
      if (secondsSince(last_line) < 20.0 && record.epoch != record.plannedEpochs) return;
      last_line = std::chrono::steady_clock::now();
      spdlog::info("row {}: epoch {}/{}, train loss {:.3f} m, validation ADE {:.3f} m", row, record.epoch,
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
    spdlog::info("row {} model: best validation ADE {:.3f} m at epoch {} ({:.0f} s, {})", row,
                 trained.bestValidationAde, trained.bestEpoch, trained.seconds, trained.stopReason);
    cache_.commit(folder, model_key);
    std::error_code ignored;
    fs::remove(pending, ignored);
  }

  // --- evaluation ----------------------------------------------------------------
  void evaluateModels() {
    for (auto& ade_row : summary_.ade) {
      throwIfInterrupted();
      const auto& row_model = models_.at(ade_row.row);
      const auto folder = cache_.folder(fmt::format("eval/row{}", ade_row.row));
      auto eval_key = key("evaluation");
      eval_key.add("model", row_model.digest);
      for (const auto& source : spec_.sources) eval_key.add("test_" + source.label, data(source.label).testDigest);
      if (!reuse(folder, eval_key, fmt::format("row {} evaluation", ade_row.row))) {
        cache_.clear(folder);
        const model::Predictor predictor(row_model.file, spec_.threads);
        json errors;
        for (const auto& source : spec_.sources) {
          const auto& scenes = testScenes(source.label);
          const auto predictions = predictor.predict(scenes);
          std::vector<std::pair<double, std::size_t>> per_sample;
          double ade_sum = 0.0;
          double fde_sum = 0.0;
          for (std::size_t i = 0; i < scenes.size(); ++i) {
            const auto sample = model::displacementErrors(predictions[i], scenes[i]);
            ade_sum += sample.ade;
            fde_sum += sample.fde;
            per_sample.emplace_back(sample.ade, i);
          }
          const auto median = per_sample.begin() + static_cast<std::ptrdiff_t>(per_sample.size() / 2);
          std::nth_element(per_sample.begin(), median, per_sample.end());
          errors[source.label] = {{"samples", scenes.size()},
                                  {"ade", mean(ade_sum, scenes.size())},
                                  {"fde", mean(fde_sum, scenes.size())},
                                  {"median_ade", median->first},
                                  {"median_sample", median->second}};
          spdlog::info("row {} on {}: ADE {:.3f} m over {} scenes", ade_row.row, source.label,
                       mean(ade_sum, scenes.size()), scenes.size());
        }
        writeJson(folder / "errors.json", errors);
        cache_.commit(folder, eval_key);
      }
      const auto errors = readJson(folder / "errors.json");
      for (const auto& source : spec_.sources) {
        const auto& entry = errors.at(source.label);
        ade_row.ade[source.label] = entry.at("ade").get<double>();
        ade_row.fde[source.label] = entry.at("fde").get<double>();
        medianSample_[{ade_row.row, source.label}] = {entry.at("median_sample").get<std::size_t>(),
                                                      entry.at("median_ade").get<double>()};
      }
    }
  }

  // --- metric MAE ------------------------------------------------------------------
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
      const auto& label_data = data(label);
      const int vectornet_row = spec_.vectornetRows.at(label);
      const auto& row_model = models_.at(vectornet_row);
      const auto folder = cache_.folder("mae/" + label);
      auto mae_key = key("metric mae");
      mae_key.add("metrics", fmt::format("{}", fmt::join(names, ",")))
          .add("train", label_data.trainDigest)
          .add("test", label_data.testDigest)
          .add("train_rows", spec_.maeSamples)
          .add("et", fmt::format("trees {} max_features {} min_samples_split {} seed {}", spec_.extraTrees.trees,
                                 spec_.extraTrees.maxFeatures, spec_.extraTrees.minSamplesSplit, spec_.extraTrees.seed))
          .add("bnn", fmt::format("hidden {} layers {} epochs {} samples {} seed {}", spec_.bnn.hidden,
                                  spec_.bnn.layers, spec_.bnn.epochs, spec_.bnn.samples, spec_.bnn.seed))
          .add("vectornet_model", row_model.digest);
      if (!reuse(folder, mae_key, fmt::format("{} metric MAE", label))) {
        cache_.clear(folder);
        writeJson(folder / "mae.json", computeMae(label, names, row_model));
        cache_.commit(folder, mae_key);
      }
      const auto results = readJson(folder / "mae.json");
      for (const auto& name : names) {
        const auto& entry = results.at("metrics").at(name);
        MaeRow mae_row;
        mae_row.label = label;
        mae_row.metric = name;
        mae_row.unit = metrics::findMetric(name)->unit;
        mae_row.et = entry.at("et").get<double>();
        mae_row.bnn = entry.at("bnn").get<double>();
        mae_row.bnnStd = entry.at("bnn_std").get<double>();
        mae_row.vectornet = entry.at("vectornet").get<double>();
        mae_row.fromTruePositions = entry.at("from_true_positions").get<double>();
        mae_row.testSamples = entry.at("vectornet_samples").get<std::size_t>();
        mae_row.etSeconds = results.at("et_seconds").get<double>();
        mae_row.bnnSeconds = results.at("bnn_seconds").get<double>();
        mae_row.trainRows = results.at("train_rows").get<std::size_t>();
        for (const auto& item : spec_.maeMetrics) {
          if (item.label == label && item.metric == name) mae_row.paper = item.paper;
        }
        summary_.mae.push_back(mae_row);
      }
    }
  }

  json computeMae(const std::string& label, const std::vector<std::string>& names, const RowModel& row_model) {
    const auto& label_data = data(label);
    json results;
    // Regression metamodels on the concrete inputs.
    baseline::BaselineOptions baseline_options;
    baseline_options.train = label_data.trainRun;
    baseline_options.test = label_data.testRun;
    baseline_options.targets = names;
    baseline_options.maxTrainRows = spec_.maeSamples;
    baseline_options.extraTrees = spec_.extraTrees;
    baseline_options.bnn = spec_.bnn;
    baseline_options.bnn.threads = spec_.threads;
    baseline_options.model = "et";
    const auto et = baseline::runBaseline(baseline_options);
    baseline_options.model = "bnn";
    const auto bnn = baseline::runBaseline(baseline_options);
    spdlog::info("{}: extra trees {:.1f} s, BNN {:.1f} s (fit + predict, {} training rows, {} test rows)", label,
                 et.fitSeconds + et.predictSeconds, bnn.fitSeconds + bnn.predictSeconds, et.trainRows, et.testRows);
    results["et_seconds"] = et.fitSeconds + et.predictSeconds;
    results["bnn_seconds"] = bnn.fitSeconds + bnn.predictSeconds;
    results["train_rows"] = et.trainRows;
    results["test_rows"] = et.testRows;

    // VectorNet: the metric code of simulated runs on the predicted Ego trajectory,
    // with the recorded trajectories of the other vehicles.
    const auto& scenes = testScenes(label);
    const vector::DatasetReader reader(vector::resolveDatasetPath(label_data.testRun));
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
    const metrics::MetricSet metric_set(names, pipeline::sceneAvailability(reader.header().kind),
                                        fmt::format("{}: mae.metrics.{}", spec_.file.string(), label));
    const model::Predictor predictor(row_model.file, spec_.threads);
    const auto predictions = predictor.predict(scenes);

    std::vector<double> predicted_sum(names.size(), 0.0);
    std::vector<double> true_sum(names.size(), 0.0);
    std::vector<std::size_t> counted(names.size(), 0);
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      const auto& scene = scenes[i];
      const auto from_prediction = pipeline::metricsOfFuture(metric_set, scene, predictions[i]);
      const auto from_truth = pipeline::metricsOfFuture(metric_set, scene, scene.target);
      for (std::size_t m = 0; m < names.size(); ++m) {
        const double simulated = scene.metrics.at(stored_index[m]);
        // Infinite values (e.g. ttc_min without closing in) and NaN have no error to average.
        if (!std::isfinite(simulated) || !std::isfinite(from_prediction[m]) || !std::isfinite(from_truth[m])) continue;
        predicted_sum[m] += std::abs(from_prediction[m] - simulated);
        true_sum[m] += std::abs(from_truth[m] - simulated);
        ++counted[m];
      }
    }
    for (std::size_t m = 0; m < names.size(); ++m) {
      results["metrics"][names[m]] = {{"et", et.mae[m]},
                                      {"bnn", bnn.mae[m]},
                                      {"bnn_std", bnn.meanStd.empty() ? 0.0 : bnn.meanStd[m]},
                                      {"vectornet", mean(predicted_sum[m], counted[m])},
                                      {"from_true_positions", mean(true_sum[m], counted[m])},
                                      {"vectornet_samples", counted[m]}};
      spdlog::info("{} {}: MAE extra trees {:.3f}, BNN {:.3f}, VectorNet {:.3f} (true positions {:.3f})", label,
                   names[m], et.mae[m], bnn.mae[m], mean(predicted_sum[m], counted[m]), mean(true_sum[m], counted[m]));
    }
    return results;
  }

  // --- figures ----------------------------------------------------------------------
  void drawFigures() {
    if (spec_.figures.empty()) return;
    ensureDirectory(output_ / "figures");
    for (const auto& figure : spec_.figures) {
      const model::Predictor predictor(models_.at(figure.row).file, spec_.threads);
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
      const auto path = output_ / "figures" / (figure.name + ".svg");
      const std::string title = fmt::format("{} (row {}; test scenes of median ADE)",
                                            figure.title.empty() ? figure.name : figure.title, figure.row);
      writeTextFileAtomically(path, composeSvgRow(panels, title));
      summary_.files.push_back(path);
    }
  }

  const ExperimentOptions& options_;
  Spec spec_;
  fs::path output_;
  ArtefactCache cache_;
  ExperimentSummary summary_;
  std::vector<ArtefactRecord> artefacts_;
  std::map<std::string, LabelData> data_;
  std::map<int, RowModel> models_;
  std::map<std::string, std::vector<vector::VectorizedScene>> testScenes_;
  std::map<std::pair<int, std::string>, std::pair<std::size_t, double>> medianSample_;
};

}  // namespace

ExperimentSummary runExperiment(const ExperimentOptions& options) {
  auto spec = parseSpec(options.spec, options.quick);
  fs::path output = options.output;
  if (output.empty()) output = fs::path("results") / (spec.name + (options.quick ? "-quick" : ""));
  refuseDirtyCommittedResults(output, options.allowDirty, "--allow-dirty");
  return ExperimentRunner(options, std::move(spec), output).run();
}

}  // namespace vsd::experiment
