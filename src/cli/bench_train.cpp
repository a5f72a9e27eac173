// `vsd-sumo bench train`: flags and printing of the data-parallel training benchmark
// (vsd/bench/process_bench.hpp).

#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "commands.hpp"
#include "vsd/bench/process_bench.hpp"

namespace vsd::cli {

namespace {

int printTrainBench(const bench::TrainBenchOptions& options) {
  const auto result = bench::runTrainBench(options);
  const auto& one = result.oneProcess;
  const auto& parallel = result.ranks;
  fmt::print("vsd-sumo bench train: VectorNet (default architecture, offsets decoder) on {} samples of {}, {} "
             "optimizer steps of a global batch of {}\n",
             options.samples, options.scenario.filename().string(), options.steps, options.batch);
  fmt::print("  1 process x {} threads: {:>6.0f} training samples/s, validation ADE {:.3f} m, {:.1f} s\n",
             options.ranks, one.samplesPerSecond, one.validationAde, one.seconds);
  fmt::print("  {} ranks x 1 thread:    {:>6.0f} training samples/s, validation ADE {:.3f} m, {:.1f} s; all-reduce "
             "{:.1f} % of the step time\n",
             options.ranks, parallel.samplesPerSecond, parallel.validationAde, parallel.seconds,
             parallel.allreduceShare * 100.0);
  fmt::print("  speed-up of {} ranks over 1 process with {} threads: {:.2f}x (the same training; float rounding "
             "differs with the thread layout: validation ADE differs by {:.3f} m)\n",
             options.ranks, options.ranks, parallel.samplesPerSecond / one.samplesPerSecond,
             std::abs(parallel.validationAde - one.validationAde));
  return 0;
}

}  // namespace

void addTrainBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::TrainBenchOptions>();
  CLI::App* command = bench.add_subcommand(
      "train", "Data-parallel training: N ranks x 1 thread vs 1 process x N threads (samples/s, all-reduce share)");
  command->add_option("scenario", options->scenario, "Logical scenario the data comes from")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  command->add_option("--work", options->work, "Keep data and models in this folder (data reused when present)");
  command->add_option("--samples", options->samples, "Scenarios simulated for the training data")->capture_default_str();
  command->add_option("--steps", options->steps, "Optimizer steps")->capture_default_str();
  command->add_option("--minibatch", options->batch, "Global training minibatch")->capture_default_str();
  command->add_option("--ranks", options->ranks, "Ranks (and the threads of the one process)")
      ->check(CLI::Range(2, 64))
      ->capture_default_str();
  command->add_option("--port", options->port, "MASTER_PORT of the ranks' rendezvous on 127.0.0.1")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  command->callback([options, &context] {
    options->tool = benchTool();
    context.action = [options] { return printTrainBench(*options); };
  });
}

}  // namespace vsd::cli
