#include "vsd/bench/run_bench.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include "vsd/core/files.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

std::vector<std::string> runArguments(const RunBenchOptions& options, std::uint64_t samples, std::size_t batch,
                                      const fs::path& out) {
  return {"run", options.scenario.string(), "--samples", std::to_string(samples), "--net-batch", std::to_string(batch),
          "--jobs", std::to_string(options.jobs), "--seed", "1", "--out", out.string()};
}

RunMeasurement measureRun(const RunBenchOptions& options, std::uint64_t samples, std::size_t batch,
                          const fs::path& work, const std::vector<std::string>& extra = {}) {
  const fs::path out = work / fmt::format("run_{}_{}", samples, batch);
  auto args = runArguments(options, samples, batch, out);
  args.insert(args.end(), extra.begin(), extra.end());
  const auto [result, cpu_seconds] = options.tool.run(args, work);
  std::error_code ignored;
  fs::remove_all(out, ignored);
  return {samples, batch, result.seconds, cpu_seconds, result.maxRssKiB};
}

/// `mpirun -n <ranks> vsd-sumo run ...` (one core per rank, nothing oversubscribed).
RunMeasurement measureMpiRun(const RunBenchOptions& options, int ranks, const fs::path& out, const fs::path& work) {
  std::vector<std::string> argv = {"mpirun", "-n", std::to_string(ranks)};
  if (::geteuid() == 0) argv.emplace_back("--allow-run-as-root");
  const auto command = options.tool.command(runArguments(options, options.mpiSamples, options.batch, out));
  argv.insert(argv.end(), command.begin(), command.end());
  const auto [result, cpu_seconds] = runChecked(argv, work / "bench.log");
  return {options.mpiSamples, options.batch, result.seconds, cpu_seconds, result.maxRssKiB};
}

/// 2 MPI ranks vs 1 (each rank one process on its own core), and whether the merged
/// outputs of both equal a one-process run's bytes.
MpiComparison compareMpiRanks(const RunBenchOptions& options, const fs::path& work) {
  const fs::path plain = work / "mpi_plain";
  options.tool.run(runArguments(options, options.mpiSamples, options.batch, plain), work);
  MpiComparison mpi;
  mpi.samples = options.mpiSamples;
  mpi.one = measureMpiRun(options, 1, work / "mpi_1", work);
  mpi.two = measureMpiRun(options, 2, work / "mpi_2", work);
  options.tool.run({"merge", (work / "mpi_1").string()}, work);
  mpi.mergeSeconds = options.tool.run({"merge", (work / "mpi_2").string()}, work).result.seconds;
  mpi.identical = sameRunOutputs(plain, work / "mpi_1") && sameRunOutputs(plain, work / "mpi_2");
  return mpi;
}

}  // namespace

double RunBenchResult::cpuMicrosecondsPerVehicleStep() const {
  const auto vehicle_steps = static_cast<double>(roadUsers * static_cast<std::size_t>(steps));
  return 1000.0 * batched.cpuMillisecondsPerSample() / vehicle_steps;
}

RunBenchResult runBench(const RunBenchOptions& options) {
  TemporaryDirectory work("vsd-bench");
  RunBenchResult result;
  result.batched = measureRun(options, options.samples, options.batch, work.path());
  result.netconvert = measureRun(options, options.samples, options.batch, work.path(), {"--net-writer", "netconvert"});
  result.single = measureRun(options, options.batchOneSamples, 1, work.path());
  const auto logical = scenario::loadLogicalScenario(options.scenario);
  result.roadUsers = 1 + logical->others.size();
  result.steps = logical->steps();
  for (const auto samples : options.memorySamples) {
    result.memory.push_back(measureRun(options, samples, options.batch, work.path()));
  }
  if (!pipeline::mpiLibraryVersion().empty()) result.mpi = compareMpiRanks(options, work.path());
  return result;
}

}  // namespace vsd::bench
