#pragma once
// `vsd-sumo bench run`: end-to-end throughput and CPU time per scenario of `vsd-sumo run`
// (default batch with the direct network writer and with netconvert, vs one network + one
// simulation per scenario), peak memory as --samples grows, and 2 MPI ranks vs 1. Each
// measurement is a separate `vsd-sumo run` process, so peak RSS is the run's own and CPU
// time counts every process of the run (workers, netconvert).
//
// `vsd-sumo bench isolation`: `run` with its controllers and libsumo in a worker process
// (what users get) vs in the calling process, alternating, both in this process.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "vsd/bench/measure.hpp"
#include "vsd/pipeline/run.hpp"

namespace vsd::bench {

struct RunBenchOptions {
  std::filesystem::path scenario = kDefaultScenario;
  std::uint64_t samples = 10000;         ///< of the batched runs
  std::uint64_t batchOneSamples = 100;   ///< of the --net-batch 1 run
  std::vector<std::uint64_t> memorySamples = {2000, 20000};
  std::size_t batch = pipeline::RunOptions::kDefaultBatch;
  int jobs = 1;
  std::uint64_t mpiSamples = 4000;       ///< of the MPI runs (1 rank vs 2)
  Tool tool;
};

/// One `vsd-sumo run` process.
struct RunMeasurement {
  std::uint64_t samples = 0;
  std::size_t batch = 0;
  double seconds = 0.0;     ///< wall time
  double cpuSeconds = 0.0;  ///< of every process of the run
  long maxRssKiB = 0;
  double rate() const { return static_cast<double>(samples) / seconds; }  ///< scenarios/s
  double cpuMillisecondsPerSample() const { return 1000.0 * cpuSeconds / static_cast<double>(samples); }
};

/// `mpirun -n 1` vs `-n 2` (one core per rank) and whether the merged outputs equal a one-process run's bytes.
struct MpiComparison {
  std::uint64_t samples = 0;
  RunMeasurement one;
  RunMeasurement two;
  double mergeSeconds = 0.0;  ///< merging the 2 shards
  bool identical = false;
};

struct RunBenchResult {
  RunMeasurement batched;     ///< --net-batch options.batch, direct network writer
  RunMeasurement netconvert;  ///< the same with --net-writer netconvert
  RunMeasurement single;      ///< --net-batch 1: one network and one simulation per scenario
  std::size_t roadUsers = 0;  ///< of the scenario, the Ego included
  int steps = 0;              ///< simulation steps per scenario
  std::vector<RunMeasurement> memory;  ///< one per options.memorySamples
  std::optional<MpiComparison> mpi;    ///< none: this build has no MPI

  /// CPU time per simulated road user and step of the batched run (us; every process counted).
  double cpuMicrosecondsPerVehicleStep() const;
};

RunBenchResult runBench(const RunBenchOptions& options);

struct IsolationBenchOptions {
  std::filesystem::path scenario = kDefaultScenario;
  std::uint64_t samples = 2000;
  std::size_t batch = pipeline::RunOptions::kDefaultBatch;
  int rounds = 3;
};

/// One `run` in this process: wall time and the resources of this process (the parent)
/// and of the worker processes it forked and reaped.
struct IsolationMeasurement {
  int round = 0;
  pipeline::RunOptions::Isolation isolation = pipeline::RunOptions::Isolation::Process;
  double seconds = 0.0;
  Usage parent;
  Usage workers;
  double cpu() const { return parent.cpu() + workers.cpu(); }
};

/// Medians over the rounds of one isolation (s).
struct IsolationMedians {
  double cpu = 0.0;
  double system = 0.0;
  double wall = 0.0;
};

struct IsolationBenchResult {
  std::vector<IsolationMeasurement> runs;  ///< in the order run (alternating per round)
  bool identical = false;                  ///< outputs of both isolations byte-identical
  double codecMilliseconds = 0.0;          ///< CPU per scenario of encoding + decoding outcomes for the pipe
  double codecBytes = 0.0;                 ///< per scenario
  double forkMilliseconds = 0.0;           ///< CPU of starting a worker that does nothing

  IsolationMedians medians(pipeline::RunOptions::Isolation isolation) const;
};

IsolationBenchResult runIsolationBench(const IsolationBenchOptions& options);

/// "none", "process".
std::string isolationName(pipeline::RunOptions::Isolation isolation);

}  // namespace vsd::bench
