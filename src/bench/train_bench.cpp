// `bench train` (process_bench.hpp): data-parallel training (README "Distributed training")
// on the same cores two ways, each configuration a `vsd-sumo train` process.

#include <fmt/format.h>

#include <optional>
#include <regex>

#include "vsd/bench/process_bench.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

/// A number the training report printed (see TrainSummary::report()).
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
  return options.tool.command({"train", "-d", data.string(), "-o", out.string(), "--steps",
                               std::to_string(options.steps), "--minibatch", std::to_string(options.batch),
                               "--patience", "1000000", "--threads", std::to_string(threads), "--seed", "1"});
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

/// The training data: one `run` of the scenario, reused when the work folder has it.
fs::path trainingData(const TrainBenchOptions& options, const fs::path& work) {
  const fs::path data = work / "data";
  if (fs::exists(data / "dataset.h5")) return data;
  const auto run = runProcess(options.tool.command({"run", options.scenario.string(), "--samples",
                                                    std::to_string(options.samples), "--seed", "1", "--out",
                                                    data.string()}),
                              work / "run.log");
  if (run.exitCode != 0) throw Error(fmt::format("bench train: generating data failed: {}", firstErrorLine(run.output)));
  return data;
}

}  // namespace

TrainBenchResult runTrainBench(const TrainBenchOptions& options) {
  std::optional<TemporaryDirectory> temporary;
  fs::path work = options.work;
  if (work.empty()) {
    temporary.emplace("vsd-bench-train");
    work = temporary->path();
  }
  ensureDirectory(work);
  const fs::path data = trainingData(options, work);
  TrainBenchResult result;
  result.oneProcess =
      measured(runProcess(trainArguments(options, data, work / "one.pt", options.ranks), work / "one.log"));
  result.ranks = measureRanks(options, data, work);
  return result;
}

}  // namespace vsd::bench
