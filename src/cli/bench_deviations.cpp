// `vsd-sumo bench deviations`: the deviations finder on field data with known answers.
// Field scenes of a logical scenario are simulated twice - as tested, and with a factor the
// tests never had (a friction limit on the Ego's deceleration: the controller's max_decel)
// - and a known share of the field takes the factor's run. A model trained (and calibrated)
// on clean test data of other seeds scores the field; the benchmark reports the false-alarm
// rate on clean scenes against the nominal level, precision and recall of the flagged
// scenes against the injected ones (recall also among the injected scenes whose path the
// factor moves beyond the model's calibrated 90 % region), scenes of a label the model never
// trained on (reported apart), and the scoring throughput. docs/deviations.md.

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/compare/deviations.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/experiment/experiment.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/expression.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

struct DeviationsBenchOptions {
  fs::path scenario = "scenarios/acc_lk.yaml";
  fs::path oodScenario = "scenarios/lk.yaml";  ///< scenes of a label the model never trained on
  fs::path work = "out/bench_deviations";      ///< training run and model (reused when present)
  fs::path model;                              ///< given: no training
  std::uint64_t trainSamples = 2000;
  std::uint64_t trainSeed = 1;
  int steps = 2000;
  std::uint64_t fieldSamples = 2900;  ///< per seed; about 2,000 clean ones at share 0.3
  std::uint64_t oodSamples = 100;
  std::vector<std::uint64_t> validationSeeds = {101};
  std::vector<std::uint64_t> testSeeds = {201};
  double share = 0.3;        ///< of the field scenes that carry the factor
  double maxDecel = 3.0;     ///< m/s^2: the friction limit (the controller's max_decel)
  double level = 0.05;
  /// Scored metrics: along the road (a_min, d_min) and across it (lane_offset_max).
  std::vector<std::string> metrics = {"a_min", "d_min", "lane_offset_max"};
  int threads = 1;  ///< on a loaded machine, libtorch's second thread spins against other processes
  int jobs = 1;
};

/// The logical scenario with the factor: the Ego's controller brakes at most `max_decel`.
std::shared_ptr<const scenario::LogicalScenario> withFrictionLimit(const scenario::LogicalScenario& logical,
                                                                   double max_decel) {
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
std::vector<vector::VectorizedScene> simulate(const std::shared_ptr<const scenario::LogicalScenario>& logical,
                                              std::uint64_t samples, std::uint64_t seed, int jobs,
                                              std::vector<std::string>& metric_names) {
  pipeline::RunOptions options;
  options.scenarioFile = logical->sourceFile;
  options.samples = samples;
  options.seed = seed;
  options.jobs = jobs;
  options.writeFiles = false;
  std::vector<vector::VectorizedScene> scenes(samples);
  const auto summary = pipeline::runScenarios(logical, options, [&](const pipeline::ScenarioOutcome& outcome) {
    if (outcome.ok()) scenes[outcome.index] = pipeline::simulatedScene(*logical, outcome);
  });
  metric_names = summary.metricNames;
  return scenes;
}

fs::path trainModel(const DeviationsBenchOptions& options, const std::shared_ptr<const scenario::LogicalScenario>& logical) {
  const fs::path model = options.work / "model.pt";
  if (fs::exists(model)) {
    fmt::print("  model: {} (exists: reused; remove it to train afresh)\n", model.string());
    return model;
  }
  const fs::path data = options.work / "train";
  pipeline::RunOptions run;
  run.scenarioFile = logical->sourceFile;
  run.outputDir = data;
  run.samples = options.trainSamples;
  run.seed = options.trainSeed;
  run.jobs = options.jobs;
  run.force = true;
  pipeline::runScenarios(logical, run);
  model::TrainOptions train;
  train.data = {data};
  train.output = model;
  train.config.decoder = "kinematic";
  train.config.frame = "lane";
  train.config.decoderOptions = {{"accel_weight", 10.0}, {"calibrate", 1.0}};
  train.seed = options.trainSeed;
  train.threads = options.threads;
  train.steps = options.steps;
  experiment::bindCalibrationMetrics(train);
  const auto summary = model::train(train);
  fmt::print("  model: {} trained on {} clean scenes (seed {}), {} steps, validation ADE {:.3f} m, {:.0f} s\n",
             model.string(), options.trainSamples, options.trainSeed, options.steps, summary.bestValidationAde,
             summary.seconds);
  return model;
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

/// Wilson's 95 % interval of k successes in n.
std::pair<double, double> wilson(double k, double n) {
  if (n == 0.0) return {std::nan(""), std::nan("")};
  const double z = 1.959964;
  const double p = k / n;
  const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n);
  return {centre - half, centre + half};
}

std::string share(double k, double n) {
  const auto [low, high] = wilson(k, n);
  return fmt::format("{:.0f}/{:.0f} = {:.1f} % [{:.1f}, {:.1f}]", k, n, 100.0 * k / n, 100.0 * low, 100.0 * high);
}

struct Counts {
  double clean = 0, cleanFlagged = 0, injected = 0, injectedFlagged = 0, beyond = 0, beyondFlagged = 0;
  double ood = 0, oodFlagged = 0, scenes = 0, seconds = 0;
};

void printCounts(const std::string& name, const Counts& c, double level) {
  fmt::print("  {}:\n", name);
  fmt::print("    false alarms on clean scenes:  {} (nominal {:.1f} %)\n", share(c.cleanFlagged, c.clean), 100.0 * level);
  fmt::print("    precision of flagged scenes:   {}\n", share(c.injectedFlagged, c.injectedFlagged + c.cleanFlagged));
  fmt::print("    recall, all injected scenes:   {}\n", share(c.injectedFlagged, c.injected));
  fmt::print("    recall, injected scenes moved beyond the 90 % region: {} ({:.0f} of {:.0f} injected moved)\n",
             share(c.beyondFlagged, c.beyond), c.beyond, c.injected);
  fmt::print("    out of distribution (unseen label): {:.0f} reported apart, {:.0f} of them flagged\n", c.ood, c.oodFlagged);
  fmt::print("    scoring throughput: {:.0f} scenes/s ({:.0f} scenes in {:.2f} s, 32 futures each)\n",
             c.scenes / c.seconds, c.scenes, c.seconds);
}

Counts benchSeed(const DeviationsBenchOptions& options, std::uint64_t seed, const model::Predictor& predictor,
                 const std::shared_ptr<const scenario::LogicalScenario>& clean,
                 const std::shared_ptr<const scenario::LogicalScenario>& factor,
                 const std::shared_ptr<const scenario::LogicalScenario>& ood) {
  std::vector<std::string> stored;
  const auto clean_scenes = simulate(clean, options.fieldSamples, seed, options.jobs, stored);
  const auto factor_scenes = simulate(factor, options.fieldSamples, seed, options.jobs, stored);
  std::vector<std::string> ood_stored;
  std::vector<vector::VectorizedScene> ood_scenes;
  if (options.oodSamples > 0) ood_scenes = simulate(ood, options.oodSamples, seed, options.jobs, ood_stored);
  Rng rng(seed);  // which scenes carry the factor: a function of the seed only
  std::vector<vector::VectorizedScene> field;
  std::vector<int> injected;  // per field scene: 1 injected, 0 clean
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < clean_scenes.size(); ++i) {
    const bool inject = rng.uniform01() < options.share;
    if (clean_scenes[i].polylines.empty() || factor_scenes[i].polylines.empty()) continue;  // SUMO failed one
    field.push_back(inject ? factor_scenes[i] : clean_scenes[i]);
    injected.push_back(inject ? 1 : 0);
    index.push_back(i);
  }
  const compare::DeviationScorer scorer(predictor, options.model.string(), options.metrics,
                                        pipeline::sceneAvailability("generated"), /*seed=*/1);
  compare::DeviationResult result;
  result.level = options.level;
  result.metricNames = scorer.metricNames();
  result.metricUnits = scorer.metricUnits();
  const auto start = std::chrono::steady_clock::now();
  result.scenes = scorer.score(field, stored, "field");
  Counts counts;
  counts.seconds = secondsSince(start);
  counts.scenes = static_cast<double>(field.size());
  std::vector<vector::VectorizedScene> ood_field;
  for (auto& scene : ood_scenes) {
    if (!scene.polylines.empty()) ood_field.push_back(std::move(scene));
  }
  for (auto& row : scorer.score(ood_field, ood_stored, "ood")) result.scenes.push_back(std::move(row));
  compare::rankDeviations(result);
  for (std::size_t j = 0; j < field.size(); ++j) {
    const auto& row = result.scenes[j];
    if (row.status != compare::SceneStatus::Scored) continue;
    const double flagged = row.flagged ? 1.0 : 0.0;
    if (injected[j] == 0) {
      counts.clean += 1.0;
      counts.cleanFlagged += flagged;
      continue;
    }
    counts.injected += 1.0;
    counts.injectedFlagged += flagged;
    if (beyondRegion(row, clean_scenes[index[j]], factor_scenes[index[j]])) {
      counts.beyond += 1.0;
      counts.beyondFlagged += flagged;
    }
  }
  for (std::size_t j = field.size(); j < result.scenes.size(); ++j) {
    counts.ood += result.scenes[j].status == compare::SceneStatus::OutOfDistribution ? 1.0 : 0.0;
    counts.oodFlagged += result.scenes[j].flagged ? 1.0 : 0.0;
  }
  return counts;
}

int runDeviationsBench(DeviationsBenchOptions options) {
  if (!(options.share > 0.0 && options.share < 1.0)) {
    throw ConfigError::field("command line", "--share", formatValue(options.share), "a share in (0, 1)");
  }
  if (!(options.level > 0.0 && options.level < 1.0)) {
    throw ConfigError::field("command line", "--level", formatValue(options.level), "a share in (0, 1)");
  }
  const auto clean = scenario::loadLogicalScenario(options.scenario);
  const auto factor = withFrictionLimit(*clean, options.maxDecel);
  const auto ood = scenario::loadLogicalScenario(options.oodScenario);
  fmt::print("bench deviations: {} field scenes per seed of {} ({:.0f} % with the Ego's deceleration limited to {:g} "
             "m/s^2), {} scenes of {} (a label the model never trained on), level {:g}\n",
             options.fieldSamples, clean->name, 100.0 * options.share, options.maxDecel, options.oodSamples, ood->name,
             options.level);
  fs::create_directories(options.work);
  if (options.model.empty()) options.model = trainModel(options, clean);
  const model::Predictor predictor(options.model, options.threads);
  for (const auto& [name, seeds] : {std::pair{"validation", options.validationSeeds}, std::pair{"test", options.testSeeds}}) {
    for (const auto seed : seeds) {
      printCounts(fmt::format("{} seed {}", name, seed), benchSeed(options, seed, predictor, clean, factor, ood),
                  options.level);
    }
  }
  return 0;
}

}  // namespace

void addDeviationsBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<DeviationsBenchOptions>();
  CLI::App* command = bench.add_subcommand(
      "deviations", "Field data with a known share of scenes carrying a factor the tests never had (a friction limit "
                    "on the Ego's deceleration): false alarms, precision, recall and throughput of `deviations`");
  command->add_option("--scenario", options->scenario, "Logical scenario of test and field data")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  command->add_option("--ood-scenario", options->oodScenario, "Logical scenario of a label the model never trained on")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  command->add_option("--work", options->work, "Folder of the training run and the model (a model there is reused)")
      ->capture_default_str();
  command->add_option("--model", options->model, "A calibrated model to score with instead of training one");
  addNumber(command, "--train-samples", options->trainSamples, "Clean test scenes to train on")->capture_default_str();
  addNumber(command, "--train-seed", options->trainSeed, "Seed of the training scenes and of the training")
      ->capture_default_str();
  addNumber(command, "--steps", options->steps, "Optimizer steps of the training")->capture_default_str();
  addNumber(command, "--field-samples", options->fieldSamples, "Field scenes per seed")->capture_default_str();
  addNumber(command, "--ood-samples", options->oodSamples, "Scenes of --ood-scenario per seed")->capture_default_str();
  addNumber(command, "--validation-seed", options->validationSeeds, "Seeds the settings were chosen on")
      ->capture_default_str();
  addNumber(command, "--test-seed", options->testSeeds, "Seeds reported")->capture_default_str();
  addNumber(command, "--share", options->share, "Share of field scenes with the factor")->capture_default_str();
  addNumber(command, "--max-decel", options->maxDecel, "The friction limit: the Ego controller's max_decel (m/s^2)")
      ->capture_default_str();
  addNumber(command, "--level", options->level, "Level of `deviations`")->capture_default_str();
  command->add_option("--metrics", options->metrics, "Metrics scored")->delimiter(',')->capture_default_str();
  addNumber(command, "--threads", options->threads, "libtorch threads")->capture_default_str();
  addNumber(command, "--jobs", options->jobs, "SUMO worker processes")->capture_default_str();
  command->callback([options, &context] { context.action = [options] { return runDeviationsBench(*options); }; });
}

}  // namespace vsd::cli
