// `vsd-sumo bench deviations`: flags and printing of the deviations finder's benchmark on
// field data with known answers (vsd/bench/deviations_bench.hpp, docs/deviations.md).

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/bench/deviations_bench.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

std::string share(double k, double n) {
  const auto [low, high] = bench::wilsonInterval(k, n);
  return fmt::format("{:.0f}/{:.0f} = {:.1f} % [{:.1f}, {:.1f}]", k, n, 100.0 * k / n, 100.0 * low, 100.0 * high);
}

void printCounts(const std::string& name, const bench::DeviationCounts& c, double level) {
  fmt::print("    {}:\n", name);
  fmt::print("      false alarms on clean scenes:  {} (nominal {:.1f} %)\n", share(c.cleanFlagged, c.clean), 100.0 * level);
  fmt::print("      precision of flagged scenes:   {}\n", share(c.injectedFlagged, c.injectedFlagged + c.cleanFlagged));
  fmt::print("      recall, all injected scenes:   {}\n", share(c.injectedFlagged, c.injected));
  fmt::print("      recall, injected scenes moved beyond the 90 % region: {} ({:.0f} of {:.0f} injected moved)\n",
             share(c.beyondFlagged, c.beyond), c.beyond, c.injected);
  fmt::print("      out of distribution (unseen label): {:.0f} reported apart, {:.0f} of them flagged\n", c.ood, c.oodFlagged);
  fmt::print("      scoring throughput: {:.0f} scenes/s ({:.0f} scenes in {:.2f} s, 32 futures each)\n",
             c.scenes / c.seconds, c.scenes, c.seconds);
}

void printModel(const bench::DeviationsBench& bench, const bench::DeviationsModel& model) {
  const auto& options = bench.options();
  if (model.training) {
    fmt::print("  model: {} trained on {} clean scenes (seed {}), {} steps, validation ADE {:.3f} m, {:.0f} s\n",
               model.path.string(), options.trainSamples, options.trainSeed, options.steps,
               model.training->bestValidationAde, model.training->seconds);
  } else {
    fmt::print("  model: {} (exists: reused; remove it to train afresh)\n", model.path.string());
  }
}

int printDeviationsBench(const bench::DeviationsBenchOptions& given) {
  bench::DeviationsBench bench(given);
  const auto& options = bench.options();
  fmt::print("bench deviations: {} field scenes per seed of {} ({:.0f} % with the Ego's deceleration limited to {:g} "
             "m/s^2), {} scenes of {} (a label the model never trained on), level {:g}\n",
             options.fieldSamples, bench.scenarioName(), 100.0 * options.share, options.maxDecel, options.oodSamples,
             bench.oodScenarioName(), options.level);
  const auto model = bench.prepareModel();
  if (given.model.empty()) printModel(bench, model);
  bench.prepareCalibration();
  const std::string runs = fmt::format("ranked among {} clean calibration runs (seed {})", bench.calibrationRuns(),
                                       options.calibrationSeed);
  if (options.calibrationSamples > 0) {
    fmt::print("  calibration: {} of {} clean runs of seed {} rank (the others failed or left the map at once), scored "
               "once in {:.2f} s\n",
               bench.calibrationRuns(), options.calibrationSamples, options.calibrationSeed, bench.calibrationSeconds());
  }
  for (const auto& [name, seeds] : {std::pair{"validation", options.validationSeeds}, std::pair{"test", options.testSeeds}}) {
    for (const auto seed : seeds) {
      const auto counts = bench.scoreSeed(seed);
      fmt::print("  {} seed {}:\n", name, seed);
      printCounts("the model's own calibration", counts.model, options.level);
      if (counts.runs) printCounts(runs, *counts.runs, options.level);
    }
  }
  return 0;
}

void addFieldFlags(CLI::App& command, bench::DeviationsBenchOptions& options) {
  addNumber(&command, "--field-samples", options.fieldSamples, "Field scenes per seed")->capture_default_str();
  addNumber(&command, "--ood-samples", options.oodSamples, "Scenes of --ood-scenario per seed")->capture_default_str();
  addNumber(&command, "--validation-seed", options.validationSeeds, "Seeds the settings were chosen on")
      ->capture_default_str();
  addNumber(&command, "--test-seed", options.testSeeds, "Seeds reported")->capture_default_str();
  addNumber(&command, "--calibration-samples", options.calibrationSamples,
            "Clean runs the field is also ranked among (deviations --calibration); 0: none")
      ->capture_default_str();
  addNumber(&command, "--calibration-seed", options.calibrationSeed, "Seed of the calibration runs")
      ->capture_default_str();
  addNumber(&command, "--share", options.share, "Share of field scenes with the factor")->capture_default_str();
  addNumber(&command, "--max-decel", options.maxDecel, "The friction limit: the Ego controller's max_decel (m/s^2)")
      ->capture_default_str();
  addNumber(&command, "--level", options.level, "Level of `deviations`")->capture_default_str();
  command.add_option("--metrics", options.metrics, "Metrics scored")->delimiter(',')->capture_default_str();
}

}  // namespace

void addDeviationsBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::DeviationsBenchOptions>();
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
  addFieldFlags(*command, *options);
  addNumber(command, "--threads", options->threads, "libtorch threads")->capture_default_str();
  addNumber(command, "--jobs", options->jobs, "SUMO worker processes")->capture_default_str();
  command->callback([options, &context] { context.action = [options] { return printDeviationsBench(*options); }; });
}

}  // namespace vsd::cli
