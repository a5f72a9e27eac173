// `vsd-sumo bench train`: data-parallel training (README "Distributed training") on the
// same two cores two ways — one process with 2 libtorch threads vs 2 ranks with 1 thread
// each (c10d Gloo on loopback) — with the same data, seed and global batch: training
// samples/s, the all-reduce's share of the step time, and the validation ADE of both
// (the same up to float rounding). Each configuration is a `vsd-sumo train` process.

#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <optional>
#include <regex>

#include "commands.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/process.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

struct TrainBenchOptions {
  fs::path scenario = "scenarios/acc_lk.yaml";
  fs::path work;
  std::uint64_t samples = 2000;
  int steps = 200;
  int batch = 64;
  int ranks = 2;
  int port = 29650;
};

struct TrainMeasurement {
  double samplesPerSecond = 0.0;
  double allreduceShare = 0.0;  ///< of the training steps' wall time
  double validationAde = 0.0;
  double seconds = 0.0;         ///< wall time of the whole process(es)
};

/// A number the training report printed after `label` (see TrainSummary::report()).
double reported(const std::string& output, const std::string& pattern, const std::string& what) {
  std::smatch match;
  if (!std::regex_search(output, match, std::regex(pattern))) {
    throw Error(fmt::format("bench train: the training printed no {}: {}", what, firstErrorLine(output)));
  }
  return std::stod(match[1]);
}

TrainMeasurement measured(const ProcessResult& result) {
  if (result.exitCode != 0) {
    throw Error(fmt::format("bench train: training failed (exit {}): {}", result.exitCode, firstErrorLine(result.output)));
  }
  TrainMeasurement m;
  m.samplesPerSecond = reported(result.output, R"(([0-9.]+) training samples/s)", "throughput");
  m.validationAde = reported(result.output, R"(best validation ADE ([0-9.]+) m)", "validation ADE");
  std::smatch share;
  if (std::regex_search(result.output, share, std::regex(R"(= ([0-9.]+) % of the training steps)"))) {
    m.allreduceShare = std::stod(share[1]) / 100.0;
  }
  m.seconds = result.seconds;
  return m;
}

std::vector<std::string> trainArguments(const TrainBenchOptions& options, const fs::path& data, const fs::path& out,
                                         int threads) {
  return {siblingExecutable("vsd-sumo"), "--quiet", "train", "-d", data.string(), "-o", out.string(), "--steps",
          std::to_string(options.steps), "--minibatch", std::to_string(options.batch), "--patience", "1000000",
          "--threads", std::to_string(threads), "--seed", "1"};
}

/// `ranks` processes of one training on loopback, 1 thread each; rank 0's report.
TrainMeasurement measureRanks(const TrainBenchOptions& options, const fs::path& data, const fs::path& work) {
  std::vector<ChildProcess> children;
  for (int rank = 0; rank < options.ranks; ++rank) {
    std::vector<std::string> argv = {"env", "MASTER_ADDR=127.0.0.1", fmt::format("MASTER_PORT={}", options.port),
                                     fmt::format("WORLD_SIZE={}", options.ranks), fmt::format("RANK={}", rank)};
    const auto train = trainArguments(options, data, work / "ranks.pt", 1);
    argv.insert(argv.end(), train.begin(), train.end());
    const auto log = work / fmt::format("rank{}.log", rank);
    fs::remove(log);
    children.push_back(ChildProcess::spawn(argv, log));
  }
  std::vector<ProcessResult> results;
  for (auto& child : children) results.push_back(child.wait());
  for (const auto& result : results) {
    if (result.exitCode != 0) measured(result);  // throws with the failing rank's message
  }
  return measured(results.front());
}

int runTrainBench(const TrainBenchOptions& options) {
  std::optional<TemporaryDirectory> temporary;
  fs::path work = options.work;
  if (work.empty()) {
    temporary.emplace("vsd-bench-train");
    work = temporary->path();
  }
  ensureDirectory(work);
  const fs::path data = work / "data";
  if (!fs::exists(data / "dataset.h5")) {
    const auto run = runProcess({siblingExecutable("vsd-sumo"), "--quiet", "run", options.scenario.string(),
                                 "--samples", std::to_string(options.samples), "--seed", "1", "--out", data.string()},
                                work / "run.log");
    if (run.exitCode != 0) throw Error(fmt::format("bench train: generating data failed: {}", firstErrorLine(run.output)));
  }
  fmt::print("vsd-sumo bench train: VectorNet (default architecture, offsets decoder) on {} samples of {}, {} "
             "optimizer steps of a global batch of {}\n",
             options.samples, options.scenario.filename().string(), options.steps, options.batch);
  const auto one = measured(runProcess(trainArguments(options, data, work / "one.pt", options.ranks), work / "one.log"));
  fmt::print("  1 process x {} threads: {:>6.0f} training samples/s, validation ADE {:.3f} m, {:.1f} s\n",
             options.ranks, one.samplesPerSecond, one.validationAde, one.seconds);
  const auto parallel = measureRanks(options, data, work);
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
  auto options = std::make_shared<TrainBenchOptions>();
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
  command->callback([options, &context] { context.action = [options] { return runTrainBench(*options); }; });
}

}  // namespace vsd::cli
