#include "vsd/compare/compare.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <optional>

#include "vsd/core/criterion_syntax.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/provenance.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/scenario/expression.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene_svg.hpp"

namespace fs = std::filesystem;

namespace vsd::compare {

namespace {

/// Scenes predicted per call: bounds the memory of the padded batch tensors.
constexpr std::size_t kPredictChunk = 4096;

/// Pass/fail criteria compiled against the metric names.
class Criteria {
 public:
  Criteria(const std::vector<report::CriterionSpec>& specs, const std::vector<std::string>& where,
           const std::vector<std::string>& metric_names) {
    for (std::size_t c = 0; c < specs.size(); ++c) {
      const auto checked = checkCriterion(specs[c].expression, where[c]);  // one syntax: comparisons
      expressions_.push_back(scenario::Expression::compile(checked.expression, metric_names, where[c]));
    }
  }
  /// Per criterion: 1 fails, 0 passes, -1 when a metric is NaN (not computable).
  std::vector<int> evaluate(const std::vector<double>& metric_values) const {
    std::vector<int> result;
    const bool any_nan = std::any_of(metric_values.begin(), metric_values.end(), [](double v) { return std::isnan(v); });
    for (const auto& expression : expressions_) {
      const double value = expression.evaluate(metric_values);
      result.push_back(any_nan || std::isnan(value) ? -1 : (value != 0.0 ? 1 : 0));
    }
    return result;
  }

 private:
  std::vector<scenario::Expression> expressions_;
};

/// The criteria of a comparison: the scenario's own (scenario mode), then those of
/// --criterion ("criterion" or "name: criterion", the syntax `search` takes too).
void addCriteria(const CompareOptions& options, const scenario::LogicalScenario* logical,
                 report::Comparison& comparison, std::vector<std::string>& where) {
  if (logical != nullptr) {
    for (const auto& criterion : logical->criteria) {
      comparison.criteria.push_back({criterion.name, criterion.expression});
      where.push_back(criterion.where);
    }
  }
  for (const auto& text : options.criteria) {
    const bool named = logical != nullptr && std::any_of(logical->criteria.begin(), logical->criteria.end(),
                                                         [&](const auto& c) { return c.name == text; });
    if (named) continue;  // a name of the scenario's criteria: compared already
    const auto split = splitNamedCriterion(text, "command line: --criterion");
    comparison.criteria.push_back({split.name, split.criterion});
    where.push_back("command line: --criterion");
  }
}

/// Scenarios of labels the model never trained on are out of its distribution: said in
/// the report and on stderr (a bias of metres per second squared otherwise passes silently).
void warnAboutUnseenLabels(const model::Predictor& predictor, report::Comparison& comparison) {
  const auto& info = predictor.info();
  if (!info.trained || info.labels.empty()) return;
  std::map<std::string, std::size_t> unseen;
  for (const auto& row : comparison.scenarios) {
    if (std::find(info.labels.begin(), info.labels.end(), row.label) == info.labels.end()) ++unseen[row.label];
  }
  for (const auto& [label, count] : unseen) {
    const std::string warning = fmt::format(
        "the model never trained on label '{}' (it trained on {}): its predictions for these {} scenarios are out of "
        "its training distribution",
        label, fmt::join(info.labels, ", "), count);
    spdlog::warn("{}", warning);
    comparison.warnings.push_back(warning);
  }
}

/// What a comparison is about (its output folder's subject, docs/output-policy.md).
std::string comparisonSubject(const CompareOptions& options) {
  std::vector<std::string> inputs;
  if (!options.scenarioFile.empty()) inputs.push_back(options.scenarioFile.stem().string());
  for (const auto& path : options.data) inputs.push_back(path.filename().string());
  return fmt::format("{} with {}", fmt::join(inputs, ", "), options.model.filename().string());
}


/// The two futures of a compared scenario; its scene is fetched again only to draw it.
struct Futures {
  Polyline prediction;
  Polyline reference;
  std::vector<std::uint8_t> referenceValid;
};
using SceneSource = std::function<vector::VectorizedScene(std::size_t)>;

/// Predictions (with the options' sampled futures) of scenes[i] for i in `which`, a
/// bounded chunk at a time (no full copy).
std::vector<model::Prediction> predictInChunks(const model::Predictor& predictor,
                                               const std::vector<vector::VectorizedScene>& scenes,
                                               const std::vector<std::size_t>& which, const model::PredictOptions& options) {
  std::vector<model::Prediction> predictions;
  predictions.reserve(which.size());
  for (std::size_t first = 0; first < which.size(); first += kPredictChunk) {
    throwIfInterrupted();
    std::vector<vector::VectorizedScene> chunk;
    for (std::size_t i = first; i < std::min(which.size(), first + kPredictChunk); ++i) chunk.push_back(scenes[which[i]]);
    auto part = predictor.predictDistribution(chunk, options);
    for (auto& prediction : part) predictions.push_back(std::move(prediction));
  }
  return predictions;
}

model::PredictOptions drawOptions(const CompareOptions& options, const model::Predictor& predictor) {
  model::PredictOptions predict;
  predict.samples = predictor.probabilistic() ? options.draws : 0;
  predict.seed = options.drawSeed;
  return predict;
}

/// Scores a prediction against the row's reference (set before): the metrics of the most
/// likely future, and for sampled futures the metric intervals and the share of futures
/// failing each criterion. Every future goes through the same metric code.
class PredictionScorer {
 public:
  /// `calibration`: the model's metric calibration (README "Calibration"; empty: plain intervals).
  PredictionScorer(const metrics::MetricSet& metric_set, const Criteria& criteria,
                   const model::IntervalCalibration& calibration)
      : metricSet_(metric_set), criteria_(criteria), calibration_(calibration) {}

  std::vector<double> metricsOf(const vector::VectorizedScene& scene, const model::Trajectory& future) const {
    return pipeline::metricsOfFuture(metricSet_, scene, future.positions, future.states);
  }

  void score(report::ComparedScenario& row, const vector::VectorizedScene& scene, const model::Prediction& prediction) const {
    const auto errors = model::displacementErrors(prediction.mostLikely.positions, scene);
    row.ade = errors.ade;
    row.fde = errors.fde;
    row.predicted = metricsOf(scene, prediction.mostLikely);
    row.predictedFails = criteria_.evaluate(row.predicted);
    row.referenceFails = criteria_.evaluate(row.reference);
    if (prediction.samples.empty()) return;
    const std::size_t metrics = row.predicted.size();
    std::vector<std::vector<double>> draws(metrics);
    std::vector<std::size_t> failing(row.predictedFails.size(), 0);
    std::vector<std::size_t> defined(row.predictedFails.size(), 0);
    for (const auto& future : prediction.samples) {
      const auto values = metricsOf(scene, future);
      for (std::size_t m = 0; m < metrics; ++m) draws[m].push_back(values[m]);
      const auto fails = criteria_.evaluate(values);
      for (std::size_t c = 0; c < fails.size(); ++c) {
        defined[c] += fails[c] >= 0 ? 1 : 0;
        failing[c] += fails[c] == 1 ? 1 : 0;
      }
    }
    for (std::size_t m = 0; m < metrics; ++m) {
      const auto* widening = calibration_.find(scene.label, metricSet_.names()[m]);
      const auto interval = model::intervalOf(draws[m], widening);
      row.intervals.push_back({interval.draws, interval.p05, interval.p25, interval.median, interval.p75, interval.p95,
                               model::containingLevel(draws[m], row.reference.at(m), widening)});
    }
    for (std::size_t c = 0; c < failing.size(); ++c) {
      row.failShare.push_back(defined[c] == 0 ? std::nan("")
                                              : static_cast<double>(failing[c]) / static_cast<double>(defined[c]));
    }
  }

 private:
  const metrics::MetricSet& metricSet_;
  const Criteria& criteria_;
  const model::IntervalCalibration& calibration_;
};

std::string metricCaption(const report::Comparison& comparison, const report::ComparedScenario& row) {
  std::string caption;
  for (std::size_t m = 0; m < comparison.metricNames.size(); ++m) {
    caption += fmt::format("{}{} {:.2f} predicted / {:.2f} {}", m ? "; " : "", comparison.metricNames[m],
                           row.predicted[m], row.reference[m], comparison.referenceName);
  }
  return caption;
}

/// Draws the `count` scenarios with the largest ADE.
std::vector<report::SceneDrawing> drawWorst(const report::Comparison& comparison,
                                            const std::vector<std::optional<Futures>>& futures, int count,
                                            const SceneSource& scene_of) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < comparison.scenarios.size(); ++i) {
    if (comparison.scenarios[i].ok() && futures[i]) order.push_back(i);
  }
  const auto shown = std::min(order.size(), static_cast<std::size_t>(count));
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(shown), order.end(),
                    [&](std::size_t a, std::size_t b) { return comparison.scenarios[a].ade > comparison.scenarios[b].ade; });
  std::vector<report::SceneDrawing> drawings;
  for (std::size_t r = 0; r < shown; ++r) {
    const auto& row = comparison.scenarios[order[r]];
    const auto& future = *futures[order[r]];
    auto scene = scene_of(order[r]);
    scene.target = future.reference;
    scene.targetValid = future.referenceValid;
    const std::string title = fmt::format("{} sample {}: ADE {:.2f} m, FDE {:.2f} m", row.label, row.sample, row.ade, row.fde);
    std::vector<vector::TrajectoryOverlay> overlays = {{"VectorNet prediction", {}, "#e31a1c", true}};
    overlays[0].points.push_back(scene.egoInitialState().position());
    for (const auto& p : future.prediction) overlays[0].points.push_back(p);
    drawings.push_back({row.sample, metricCaption(comparison, row),
                        vector::renderSceneSvg(scene, overlays, title, 560, comparison.referenceName + " future",
                                               /*focus_margin_m=*/8.0)});
  }
  return drawings;
}

struct Run {
  report::Comparison comparison;
  std::vector<report::SceneDrawing> worst;
};

/// Scenes built from the concrete scenarios before simulation (what the model sees).
struct PlannedScenes {
  std::vector<vector::VectorizedScene> scenes;
  std::vector<std::string> failure;  ///< per scenario: why it could not be planned ("" if it could)
};

PlannedScenes planScenes(const std::shared_ptr<const scenario::LogicalScenario>& logical, const CompareOptions& options) {
  PlannedScenes planned;
  planned.failure.resize(options.samples);
  planned.scenes.reserve(options.samples);
  for (std::uint64_t index = 0; index < options.samples; ++index) {
    throwIfInterrupted();
    const auto concrete = scenario::sampleConcreteScenario(logical, options.seed, index);
    try {
      planned.scenes.push_back(pipeline::plannedScene(concrete));
    } catch (const ConfigError& error) {  // e.g. a vehicle starting off its road: SUMO fails it too
      planned.failure[index] = error.what();
      planned.scenes.emplace_back();
    }
  }
  return planned;
}

/// Predictions of every scene that could be planned; `indexOf[i]` is scenario i's.
struct PlannedPredictions {
  std::vector<model::Prediction> predictions;
  std::vector<std::size_t> indexOf;
};

PlannedPredictions predictPlanned(const model::Predictor& predictor, const PlannedScenes& planned,
                                  const CompareOptions& options) {
  PlannedPredictions result;
  std::vector<std::size_t> to_predict;
  result.indexOf.assign(planned.scenes.size(), std::numeric_limits<std::size_t>::max());
  for (std::size_t i = 0; i < planned.scenes.size(); ++i) {
    if (!planned.failure[i].empty()) continue;
    result.indexOf[i] = to_predict.size();
    to_predict.push_back(i);
  }
  result.predictions = predictInChunks(predictor, planned.scenes, to_predict, drawOptions(options, predictor));
  return result;
}

/// How far the scenes the model saw are from the ones SUMO produced (m, largest coordinate difference).
struct PlanDeviation {
  double lanes = 0.0;     ///< lane boundaries
  double vehicles = 0.0;  ///< other road users (the Ego's future is what is predicted)

  void add(const vector::VectorizedScene& planned, const vector::VectorizedScene& simulated) {
    for (std::size_t p = 0; p < std::min(planned.polylines.size(), simulated.polylines.size()); ++p) {
      const auto& a = planned.polylines[p];
      const auto& b = simulated.polylines[p];
      if (a.type == vector::ObjectType::Ego || a.vectors.size() != b.vectors.size()) continue;
      double& worst = a.type == vector::ObjectType::LaneBoundary ? lanes : vehicles;
      for (std::size_t v = 0; v < a.vectors.size(); ++v) {
        for (std::size_t f = 0; f < 4; ++f) worst = std::max(worst, std::abs(a.vectors[v][f] - b.vectors[v][f]));
      }
    }
  }
};

/// The comparison's headings for a logical scenario: title, inputs, metrics and criteria.
report::Comparison comparisonOf(const scenario::LogicalScenario& logical, const metrics::MetricSet& metric_set,
                                const CompareOptions& options, std::vector<std::string>& criteria_where) {
  report::Comparison comparison;
  comparison.title = fmt::format("{}, {} fresh scenarios (seed {})", logical.name, options.samples, options.seed);
  comparison.referenceName = "simulated";
  comparison.inputNames = logical.inputNames();
  comparison.metricNames = metric_set.names();
  comparison.metricUnits = metric_set.units();
  addCriteria(options, &logical, comparison, criteria_where);
  return comparison;
}

void addScenarioProvenance(const CompareOptions& options, report::Comparison& comparison) {
  comparison.provenance.push_back({"scenario file", options.scenarioFile.string()});
  comparison.provenance.push_back({"scenario SHA-256", sha256OfFile(options.scenarioFile)});
  comparison.provenance.push_back({"seed", std::to_string(options.seed)});
  comparison.provenance.push_back({"scenarios", std::to_string(options.samples)});
  comparison.provenance.push_back({"SUMO", pipeline::provenance().sumoVersion});
}

Run compareScenario(const CompareOptions& options, const model::Predictor& predictor) {
  const auto logical = scenario::loadLogicalScenario(options.scenarioFile);
  vector::DatasetHeader header;
  header.step = logical->step;
  header.horizon = logical->steps();
  predictor.checkCompatible(header, options.scenarioFile.string());
  const metrics::MetricSet metric_set(logical->metrics, pipeline::scenarioAvailability(*logical),
                                      logical->sourceFile.string() + ": metrics");
  Run run;
  std::vector<std::string> where;
  run.comparison = comparisonOf(*logical, metric_set, options, where);
  auto& comparison = run.comparison;
  const Criteria criteria(comparison.criteria, where, comparison.metricNames);

  // 1. Scenes before simulation.
  auto start = std::chrono::steady_clock::now();
  const auto planned = planScenes(logical, options);
  comparison.timings.push_back({"vectorize", secondsSince(start)});
  spdlog::info("vectorized {} scenarios without simulating them", options.samples);

  // 2. Predictions of every scene that could be planned.
  start = std::chrono::steady_clock::now();
  const auto predicted = predictPlanned(predictor, planned, options);
  comparison.timings.push_back({"predict", secondsSince(start)});
  const PredictionScorer scorer(metric_set, criteria, predictor.info().metricIntervals);
  spdlog::info("predicted the Ego in {} scenarios", predicted.predictions.size());

  // 3. Simulation of the same concrete scenarios, compared as they arrive.
  pipeline::RunOptions run_options;
  run_options.scenarioFile = options.scenarioFile;
  run_options.samples = options.samples;
  run_options.seed = options.seed;
  run_options.jobs = options.jobs;
  run_options.batch = options.batch;
  run_options.writeFiles = false;
  std::vector<std::optional<Futures>> futures(options.samples);
  comparison.scenarios.resize(options.samples);
  PlanDeviation deviation;
  start = std::chrono::steady_clock::now();
  pipeline::runScenarios(logical, run_options, [&](const pipeline::ScenarioOutcome& outcome) {
    auto& row = comparison.scenarios[outcome.index];
    row.sample = outcome.index;
    row.label = logical->name;
    row.inputs = outcome.inputs;
    const auto& plan_failure = planned.failure[outcome.index];
    if (!plan_failure.empty()) {
      row.failure = outcome.ok() ? "could not be vectorized: " + plan_failure : outcome.failure;
      return;
    }
    if (!outcome.ok()) {
      row.failure = outcome.failure;
      return;
    }
    const auto& scene = planned.scenes[outcome.index];
    const auto& prediction = predicted.predictions[predicted.indexOf[outcome.index]];
    auto simulated = pipeline::simulatedScene(*logical, outcome);
    deviation.add(scene, simulated);
    // The scene the model saw, now with the future the simulation produced.
    vector::VectorizedScene scored = scene;
    scored.target = simulated.target;
    scored.targetValid = simulated.targetValid;
    row.reference = outcome.metrics;
    row.fromReferencePositions = pipeline::metricsOfFuture(metric_set, scored, simulated.target);
    scorer.score(row, scored, prediction);
    futures[outcome.index] = Futures{prediction.mostLikely.positions, simulated.target, simulated.targetValid};
  });
  comparison.timings.push_back({"simulate", secondsSince(start)});
  comparison.notes.push_back(fmt::format(
      "The model saw scenes built before simulation; they deviate from the simulated scenes by at most {:.3f} m "
      "(lane boundaries) and {:.3f} m (other vehicles): netconvert stores coordinates to 0.01 m.",
      deviation.lanes, deviation.vehicles));
  addScenarioProvenance(options, comparison);
  run.worst = drawWorst(comparison, futures, options.worst, [&](std::size_t i) { return planned.scenes[i]; });
  return run;
}

Run compareDatasets(const CompareOptions& options, const model::Predictor& predictor) {
  vector::DatasetCollection collection;
  for (const auto& path : options.data) collection.add(path);
  for (std::size_t f = 0; f < collection.files(); ++f) {
    predictor.checkCompatible(collection.reader(f).header(), collection.reader(f).path().string());
  }
  auto refs = collection.all();
  if (options.samples > 0 && refs.size() > options.samples) refs.resize(options.samples);
  if (refs.empty()) throw DatasetError(fmt::format("{}: no samples to compare", options.data.front().string()));

  const auto& first_header = collection.reader(0).header();
  std::vector<std::string> names = options.metrics;
  if (names.empty() && first_header.kind == "generated") names = first_header.metricNames;
  const metrics::MetricSet metric_set(names, pipeline::sceneAvailability(first_header.kind), "--metrics");

  Run run;
  auto& comparison = run.comparison;
  std::string files;
  for (const auto& path : options.data) files += (files.empty() ? "" : ", ") + path.filename().string();
  comparison.title = fmt::format("{} samples of {}", refs.size(), files);
  comparison.referenceName = "recorded";
  comparison.metricNames = metric_set.names();
  comparison.metricUnits = metric_set.units();
  std::vector<std::string> where;
  addCriteria(options, nullptr, comparison, where);
  const Criteria criteria(comparison.criteria, where, comparison.metricNames);
  const PredictionScorer scorer(metric_set, criteria, predictor.info().metricIntervals);
  const auto predict_options = drawOptions(options, predictor);

  double read_seconds = 0.0;
  double predict_seconds = 0.0;
  auto start = std::chrono::steady_clock::now();
  std::vector<std::optional<Futures>> futures(refs.size());
  comparison.scenarios.resize(refs.size());
  for (std::size_t first = 0; first < refs.size(); first += kPredictChunk) {
    auto stage = std::chrono::steady_clock::now();
    std::vector<vector::VectorizedScene> scenes;
    for (std::size_t i = first; i < std::min(refs.size(), first + kPredictChunk); ++i) scenes.push_back(collection.scene(refs[i]));
    read_seconds += secondsSince(stage);
    stage = std::chrono::steady_clock::now();
    std::vector<std::size_t> all(scenes.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    const auto predictions = predictInChunks(predictor, scenes, all, predict_options);
    predict_seconds += secondsSince(stage);
    for (std::size_t j = 0; j < scenes.size(); ++j) {
      const auto& scene = scenes[j];
      auto& row = comparison.scenarios[first + j];
      row.sample = first + j;
      row.label = scene.label;
      if (std::none_of(scene.targetValid.begin(), scene.targetValid.end(), [](std::uint8_t v) { return v != 0; })) {
        row.failure = "no recorded future (the Ego left the map at once)";
        continue;
      }
      row.reference = pipeline::metricsOfFuture(metric_set, scene, scene.target);
      scorer.score(row, scene, predictions[j]);
      futures[first + j] = Futures{predictions[j].mostLikely.positions, scene.target, scene.targetValid};
    }
  }
  comparison.timings.push_back({"read", read_seconds});
  comparison.timings.push_back({"predict", predict_seconds});
  comparison.timings.push_back({"compare", secondsSince(start) - read_seconds - predict_seconds});
  comparison.notes.push_back(
      "Both sides go through the same metric code: the recorded and the predicted Ego positions, speeds and "
      "accelerations reconstructed from positions; vehicle sizes as the dataset stores them.");
  for (std::size_t f = 0; f < collection.files(); ++f) {
    if (collection.reader(f).header().vehicleSizesAssumed) {
      comparison.notes.push_back(fmt::format("{} is a {} file without vehicle sizes: every vehicle was assumed "
                                             "{} m x {} m.",
                                             collection.reader(f).path().string(), vector::kDatasetSchemaVersion1,
                                             vector::kAssumedVehicleLength, vector::kAssumedVehicleWidth));
    }
  }
  for (std::size_t f = 0; f < collection.files(); ++f) {
    const auto& path = collection.reader(f).path();
    comparison.provenance.push_back({"dataset", path.string()});
    comparison.provenance.push_back({"dataset SHA-256", sha256OfFile(path)});
  }
  run.worst = drawWorst(comparison, futures, options.worst, [&](std::size_t i) { return collection.scene(refs[i]); });
  return run;
}

}  // namespace

void CompareOptions::validate() const {
  if (scenarioFile.empty() == data.empty()) {
    throw ConfigError("compare: give either a logical scenario (SCENARIO) or datasets (--data), not both or neither");
  }
  if (samples > 10'000'000) {
    throw ConfigError::field("command line", "--samples", std::to_string(samples), "0 (default) .. 10000000");
  }
  if (jobs < 1 || jobs > 256) throw ConfigError::field("command line", "--jobs", std::to_string(jobs), "1 .. 256");
  if (threads < 1 || threads > 256) throw ConfigError::field("command line", "--threads", std::to_string(threads), "1 .. 256");
  if (worst < 0 || worst > 50) throw ConfigError::field("command line", "--worst", std::to_string(worst), "0 .. 50");
  if (draws < 0 || draws > 10000) throw ConfigError::field("command line", "--futures", std::to_string(draws), "0 .. 10000");
  if (!(confidence >= 0.5 && confidence <= 1.0)) {
    throw ConfigError::field("command line", "--confidence", formatValue(confidence), "0.5 .. 1");
  }
  if (batch < 1 || batch > 4096) throw ConfigError::field("command line", "--batch", std::to_string(batch), "1 .. 4096");
  if (!scenarioFile.empty() && !metrics.empty()) {
    throw ConfigError("command line: compare: --metrics is for datasets; a scenario file defines its own 'metrics'");
  }
}

report::Comparison compareScenarioPredictions(const CompareOptions& options_in, const model::Predictor& predictor) {
  CompareOptions options = options_in;
  options.validate();
  if (options.scenarioFile.empty()) throw ConfigError("compare: scenario mode needs a logical scenario file");
  if (options.samples == 0) options.samples = CompareOptions::kDefaultScenarios;
  options.worst = 0;  // nothing is drawn
  Run run = compareScenario(options, predictor);
  run.comparison.draws = drawOptions(options, predictor).samples;
  run.comparison.confidence = options.confidence;
  return std::move(run.comparison);
}

CompareSummary runComparison(const CompareOptions& options_in) {
  const auto start = std::chrono::steady_clock::now();
  CompareOptions options = options_in;
  options.validate();
  if (!options.scenarioFile.empty() && options.samples == 0) options.samples = CompareOptions::kDefaultScenarios;
  if (options.output.empty()) {
    options.output = fs::path("reports") / (options.scenarioFile.empty() ? vector::resolveDatasetPath(options.data.front()).stem()
                                                                          : options.scenarioFile.stem());
  }
  refuseDirtyCommittedResults(options.output, options.allowDirty, "--allow-dirty");
  const bool builtin = model::Predictor::isBuiltin(options.model);  // cv, ca: no file
  if (!builtin && !fs::is_regular_file(options.model)) {
    throw ModelError(fmt::format("--model {}: no such file", options.model.string()));
  }
  std::vector<std::pair<std::string, fs::path>> inputs = {{"--model", options.model}, {"scenario", options.scenarioFile}};
  for (const auto& path : options.data) inputs.emplace_back("--data", path);
  const std::string subject = comparisonSubject(options);
  checkOutput({options.output, &output_kinds::comparisonFolder(), subject, options.force, "--out", "--force", inputs});
  const model::Predictor predictor(options.model, options.threads);
  OutputFolder folder(options.output);

  Run run = options.scenarioFile.empty() ? compareDatasets(options, predictor) : compareScenario(options, predictor);
  auto& comparison = run.comparison;
  warnAboutUnseenLabels(predictor, comparison);
  comparison.draws = drawOptions(options, predictor).samples;
  comparison.confidence = options.confidence;
  const auto& info = predictor.info();
  comparison.provenance.insert(
      comparison.provenance.begin(),
      {{"model file", options.model.string()},
       {"model SHA-256", builtin ? std::string("-") : sha256OfFile(options.model)},
       {"model", info.trained ? fmt::format("{} decoder, trained on {} (labels {}), seed {}, epoch {}, validation ADE "
                                            "{:.3f} m",
                                            predictor.name(), info.mix, fmt::join(info.labels, ", "), info.seed,
                                            info.epoch, info.validationAde)
                              : fmt::format("{} (no training)", predictor.name())}});
  if (comparison.draws > 0) {
    comparison.provenance.push_back({"sampled futures", fmt::format("{} per scenario, seed {}", comparison.draws,
                                                                    options.drawSeed)});
  }
  comparison.provenance.push_back({"vsd-sumo", pipeline::provenance().toolVersion});
  comparison.provenance.push_back({"libtorch threads", std::to_string(options.threads)});
  comparison.provenance.push_back({"command line", options.commandLine});
  comparison.provenance.push_back({"written", utcTimestamp()});

  CompareSummary summary;
  summary.statistics = report::computeStatistics(comparison);
  if (summary.statistics.compared == 0) {
    throw Error(fmt::format("compare: no scenario could be compared ({} failed); first reason: {}",
                                summary.statistics.failed, comparison.scenarios.front().failure));
  }
  report::writeComparisonCsv(comparison, folder.stage("comparison.csv"));
  folder.staged("comparison.csv");
  folder.stageText("report.html", report::renderHtmlReport(comparison, summary.statistics, run.worst));
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  manifest["kind"] = "comparison";
  manifest["subject"] = subject;
  for (const auto& [key, value] : comparison.provenance) manifest["provenance"][key] = value;
  folder.commit(manifest);

  summary.output = options.output;
  summary.files = {options.output / "report.html", options.output / "comparison.csv"};
  summary.seconds = secondsSince(start);
  summary.comparison = std::move(comparison);
  return summary;
}

std::string CompareSummary::report() const {
  std::string text = report::textSummary(comparison, statistics);
  text += fmt::format("  total {:.1f} s\nreport: {}\n", seconds, (output / "report.html").string());
  text += fmt::format("table:  {}\n", (output / "comparison.csv").string());
  return text;
}

}  // namespace vsd::compare
