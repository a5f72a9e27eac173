#include "vsd/bench/deviations_bench.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "vsd/compare/deviations.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/experiment/experiment.hpp"
#include "vsd/model/predictor.hpp"
#include "vsd/model/presets.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/expression.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

using Logical = std::shared_ptr<const scenario::LogicalScenario>;

/// The logical scenario with the factor: the Ego's controller brakes at most `max_decel`.
Logical withFrictionLimit(const scenario::LogicalScenario& logical, double max_decel) {
  auto variant = std::make_shared<scenario::LogicalScenario>(logical);
  auto& params = variant->ego.controller.params;
  const auto found = std::find_if(params.begin(), params.end(), [](const auto& p) { return p.first == "max_decel"; });
  if (found != params.end()) {
    found->second = scenario::Expression::constant(max_decel);
  } else {
    params.emplace_back("max_decel", scenario::Expression::constant(max_decel));
  }
  return variant;
}

/// Simulated scenes of samples 0 .. n-1 of `seed` (failed ones empty), with the names of their stored metrics.
struct SimulatedScenes {
  std::vector<vector::VectorizedScene> scenes;
  std::vector<std::string> metricNames;
};

SimulatedScenes simulate(const Logical& logical, std::uint64_t samples, std::uint64_t seed, int jobs) {
  pipeline::RunOptions options;
  options.scenarioFile = logical->sourceFile;
  options.samples = samples;
  options.seed = seed;
  options.jobs = jobs;
  options.writeFiles = false;
  SimulatedScenes simulated;
  simulated.scenes.resize(samples);
  const auto summary = pipeline::runScenarios(logical, options, [&](const pipeline::ScenarioOutcome& outcome) {
    if (outcome.ok()) simulated.scenes[outcome.index] = pipeline::simulatedScene(*logical, outcome);
  });
  simulated.metricNames = summary.metricNames;
  return simulated;
}

/// Does the factor move the path beyond the model's calibrated 90 % region at some step?
bool beyondRegion(const compare::SceneDeviation& scored, const vector::VectorizedScene& clean,
                  const vector::VectorizedScene& factor) {
  for (std::size_t k = 0; k < scored.region90.size() && k < clean.target.size(); ++k) {
    if (!clean.targetValid[k] || !factor.targetValid[k]) continue;
    const auto& [a, b, angle] = scored.region90[k];
    const Vec2 d = factor.target[k] - clean.target[k];
    const double u = d.x() * std::cos(angle) + d.y() * std::sin(angle);
    const double v = -d.x() * std::sin(angle) + d.y() * std::cos(angle);
    if ((u / a) * (u / a) + (v / b) * (v / b) > 1.0) return true;
  }
  return false;
}

/// The field of one seed: each scene clean or (with probability `share`) carrying the factor.
struct Field {
  std::vector<vector::VectorizedScene> scenes;
  std::vector<int> injected;        ///< per field scene: 1 injected, 0 clean
  std::vector<std::size_t> sample;  ///< per field scene: its sample index
};

Field drawField(const SimulatedScenes& clean, const SimulatedScenes& factor, double share, std::uint64_t seed) {
  Rng rng(seed);  // which scenes carry the factor: a function of the seed only
  Field field;
  for (std::size_t i = 0; i < clean.scenes.size(); ++i) {
    const bool inject = rng.uniform01() < share;
    if (clean.scenes[i].polylines.empty() || factor.scenes[i].polylines.empty()) continue;  // SUMO failed one
    field.scenes.push_back(inject ? factor.scenes[i] : clean.scenes[i]);
    field.injected.push_back(inject ? 1 : 0);
    field.sample.push_back(i);
  }
  return field;
}

void countScored(DeviationCounts& counts, const compare::DeviationResult& result, const Field& field,
                 const SimulatedScenes& clean, const SimulatedScenes& factor) {
  for (std::size_t j = 0; j < field.scenes.size(); ++j) {
    const auto& row = result.scenes[j];
    if (row.status != compare::SceneStatus::Scored) continue;
    const double flagged = row.flagged ? 1.0 : 0.0;
    if (field.injected[j] == 0) {
      counts.clean += 1.0;
      counts.cleanFlagged += flagged;
      continue;
    }
    counts.injected += 1.0;
    counts.injectedFlagged += flagged;
    if (beyondRegion(row, clean.scenes[field.sample[j]], factor.scenes[field.sample[j]])) {
      counts.beyond += 1.0;
      counts.beyondFlagged += flagged;
    }
  }
  for (std::size_t j = field.scenes.size(); j < result.scenes.size(); ++j) {
    counts.ood += result.scenes[j].status == compare::SceneStatus::OutOfDistribution ? 1.0 : 0.0;
    counts.oodFlagged += result.scenes[j].flagged ? 1.0 : 0.0;
  }
}

/// Flags `result` and counts it against the field's truth.
DeviationCounts countFlags(compare::DeviationResult& result, const Field& field, const SimulatedScenes& clean,
                           const SimulatedScenes& factor) {
  compare::rankDeviations(result);
  DeviationCounts counts;
  countScored(counts, result, field, clean, factor);
  return counts;
}

}  // namespace

struct DeviationsBench::State {
  Logical clean;
  Logical factor;
  Logical ood;
  std::unique_ptr<model::Predictor> predictor;
  std::unique_ptr<compare::DeviationScorer> scorer;
  std::optional<compare::RunCalibration> calibration;
};

void DeviationsBenchOptions::validate() const {
  if (!(share > 0.0 && share < 1.0)) {
    throw ConfigError::field("command line", "--share", formatValue(share), "a share in (0, 1)");
  }
  if (!(level > 0.0 && level < 1.0)) {
    throw ConfigError::field("command line", "--level", formatValue(level), "a share in (0, 1)");
  }
  const auto needed = compare::RunCalibration::runsNeeded(metrics.size(), level);
  if (calibrationSamples > 0 && calibrationSamples < needed) {
    throw ConfigError::field("command line", "--calibration-samples", std::to_string(calibrationSamples),
                             fmt::format("0 or at least {} (fewer cannot flag a scene on one of {} p-values at --level "
                                         "{:g})",
                                         needed, metrics.size() + 1, level));
  }
}

std::pair<double, double> wilsonInterval(double k, double n) {
  if (n == 0.0) return {std::nan(""), std::nan("")};
  const auto interval = vsd::wilsonInterval(k / n, static_cast<std::size_t>(n));
  return {interval.low, interval.high};
}

DeviationsBench::DeviationsBench(DeviationsBenchOptions options)
    : options_(std::move(options)), state_(std::make_unique<State>()) {
  options_.validate();
  state_->clean = scenario::loadLogicalScenario(options_.scenario);
  state_->factor = withFrictionLimit(*state_->clean, options_.maxDecel);
  state_->ood = scenario::loadLogicalScenario(options_.oodScenario);
}

DeviationsBench::~DeviationsBench() = default;

const std::string& DeviationsBench::scenarioName() const { return state_->clean->name; }

const std::string& DeviationsBench::oodScenarioName() const { return state_->ood->name; }

DeviationsModel DeviationsBench::prepareModel() {
  fs::create_directories(options_.work);
  DeviationsModel prepared;
  prepared.path = options_.model.empty() ? options_.work / "model.pt" : options_.model;
  if (options_.model.empty() && !fs::exists(prepared.path)) {
    const fs::path data = options_.work / "train";
    pipeline::RunOptions run;
    run.scenarioFile = state_->clean->sourceFile;
    run.outputDir = data;
    run.samples = options_.trainSamples;
    run.seed = options_.trainSeed;
    run.jobs = options_.jobs;
    run.force = true;
    pipeline::runScenarios(state_->clean, run);
    model::TrainOptions train;
    train.data = {data};
    train.output = prepared.path;
    model::applyPreset(model::findModelPreset("recommended", "bench deviations"), {}, train.config);
    train.seed = options_.trainSeed;
    train.threads = options_.threads;
    train.steps = options_.steps;
    experiment::bindCalibrationMetrics(train);
    prepared.training = model::train(train);
  }
  options_.model = prepared.path;
  state_->predictor = std::make_unique<model::Predictor>(prepared.path, options_.threads);
  return prepared;
}

void DeviationsBench::prepareCalibration() {
  if (!state_->predictor) throw Error("internal: bench deviations calibrated before its model was prepared");
  state_->scorer = std::make_unique<compare::DeviationScorer>(*state_->predictor, options_.model.string(),
                                                              options_.metrics, pipeline::sceneAvailability("generated"),
                                                              /*seed=*/1);
  if (options_.calibrationSamples == 0) return;
  const auto runs = simulate(state_->clean, options_.calibrationSamples, options_.calibrationSeed, options_.jobs);
  std::vector<vector::VectorizedScene> scenes;
  for (const auto& scene : runs.scenes) {
    if (!scene.polylines.empty()) scenes.push_back(scene);
  }
  const auto start = std::chrono::steady_clock::now();
  state_->calibration.emplace(state_->scorer->score(scenes, runs.metricNames, "calibration"),
                              state_->scorer->metricNames().size(),
                              fmt::format("(bench runs of seed {})", options_.calibrationSeed), options_.level);
  calibrationSeconds_ = secondsSince(start);
}

std::size_t DeviationsBench::calibrationRuns() const { return state_->calibration ? state_->calibration->runs() : 0; }

DeviationSeedCounts DeviationsBench::scoreSeed(std::uint64_t seed) {
  if (!state_->scorer) throw Error("internal: bench deviations scored before its model and calibration were prepared");
  const auto clean = simulate(state_->clean, options_.fieldSamples, seed, options_.jobs);
  const auto factor = simulate(state_->factor, options_.fieldSamples, seed, options_.jobs);
  SimulatedScenes ood;
  if (options_.oodSamples > 0) ood = simulate(state_->ood, options_.oodSamples, seed, options_.jobs);
  const Field field = drawField(clean, factor, options_.share, seed);
  const auto& scorer = *state_->scorer;
  compare::DeviationResult result;
  result.level = options_.level;
  result.metricNames = scorer.metricNames();
  result.metricUnits = scorer.metricUnits();
  const auto start = std::chrono::steady_clock::now();
  result.scenes = scorer.score(field.scenes, factor.metricNames, "field");
  const double seconds = secondsSince(start);
  std::vector<vector::VectorizedScene> ood_field;
  for (const auto& scene : ood.scenes) {
    if (!scene.polylines.empty()) ood_field.push_back(scene);
  }
  for (auto& row : scorer.score(ood_field, ood.metricNames, "ood")) result.scenes.push_back(std::move(row));
  DeviationSeedCounts counts;
  counts.model = countFlags(result, field, clean, factor);
  counts.model.seconds = seconds;
  counts.model.scenes = static_cast<double>(field.scenes.size());
  if (state_->calibration) {
    auto ranked = result;
    ranked.calibrationRuns = state_->calibration->runs();
    const auto ranking = std::chrono::steady_clock::now();
    for (auto& scene : ranked.scenes) state_->calibration->apply(scene);  // unseen labels stay apart
    const double ranking_seconds = secondsSince(ranking);
    counts.runs = countFlags(ranked, field, clean, factor);
    counts.runs->seconds = seconds + ranking_seconds;  // scoring, then ranking among the runs
    counts.runs->scenes = static_cast<double>(field.scenes.size());
  }
  return counts;
}

}  // namespace vsd::bench
