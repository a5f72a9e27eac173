// `vsd-sumo bench run`: end-to-end throughput and CPU time per scenario of
// `vsd-sumo run` (default batch with the direct network writer and with
// netconvert, vs. one network + one simulation per scenario, side by side), peak
// memory as --samples grows, and 2 MPI ranks vs 1. Each measurement is a separate
// `vsd-sumo run` process (the executable users start, without libtorch), so
// start-up, scenario loading and file writing are included, peak RSS is the run's
// own and CPU time counts every process of the run (workers, netconvert).

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <tuple>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/process.hpp"
#include "vsd/compare/compare.hpp"
#include "vsd/experiment/experiment.hpp"
#include "vsd/model/model.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/pipeline/outcome_codec.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/report/comparison.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

struct BenchOptions {
  fs::path scenario = "scenarios/acc_lk.yaml";
  std::uint64_t samples = 10000;
  std::uint64_t batchOneSamples = 100;
  std::vector<std::uint64_t> memorySamples = {2000, 20000};
  std::size_t batch = pipeline::RunOptions::kDefaultBatch;
  int jobs = 1;
  std::uint64_t mpiSamples = 4000;
};

struct Measurement {
  std::uint64_t samples = 0;
  std::size_t batch = 0;
  double seconds = 0.0;
  double cpuSeconds = 0.0;
  long maxRssKiB = 0;
  double rate() const { return static_cast<double>(samples) / seconds; }
  double cpuMillisecondsPerSample() const { return 1000.0 * cpuSeconds / static_cast<double>(samples); }
};

/// Resource use of this process and of the children it has reaped so far.
struct Usage {
  double user = 0.0;       ///< CPU time in user mode (s)
  double system = 0.0;     ///< CPU time in the kernel (s): page faults, fork, pipes, files
  double pageFaults = 0.0;  ///< minor page faults (first touch of a page, copy on write)

  static Usage of(int who) {
    struct rusage usage {};
    ::getrusage(who, &usage);
    const auto seconds = [](const timeval& time) {
      return static_cast<double>(time.tv_sec) + 1e-6 * static_cast<double>(time.tv_usec);
    };
    return {seconds(usage.ru_utime), seconds(usage.ru_stime), static_cast<double>(usage.ru_minflt)};
  }
  Usage operator-(const Usage& before) const {
    return {user - before.user, system - before.system, pageFaults - before.pageFaults};
  }
  double cpu() const { return user + system; }
};

/// User + system CPU time of every child process this process has waited for, and
/// of their descendants they waited for (s).
double childrenCpuSeconds() { return Usage::of(RUSAGE_CHILDREN).cpu(); }

struct CheckedRun {
  ProcessResult result;
  double cpuSeconds = 0.0;  ///< of the process and every process it started
};

/// Runs `argv` to completion; throws Error if it fails.
CheckedRun runChecked(const std::vector<std::string>& argv, const fs::path& work) {
  const double cpu_before = childrenCpuSeconds();
  const auto result = runProcess(argv, work / "bench.log");
  const double cpu_seconds = childrenCpuSeconds() - cpu_before;
  if (result.exitCode != 0) {
    throw Error(fmt::format("benchmark process failed (exit {}): {}", result.exitCode, firstErrorLine(result.output)));
  }
  return {result, cpu_seconds};
}

/// Runs vsd-sumo (the executable users start) with `args` as a separate process.
CheckedRun runVsdSumo(const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {siblingExecutable("vsd-sumo"), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return runChecked(argv, work);
}

ProcessResult runSelf(const std::vector<std::string>& args, const fs::path& work) {
  return runVsdSumo(args, work).result;
}

std::vector<std::string> runArguments(const BenchOptions& options, std::uint64_t samples, std::size_t batch,
                                      const fs::path& out) {
  return {"run", options.scenario.string(), "--samples", std::to_string(samples), "--net-batch", std::to_string(batch),
          "--jobs", std::to_string(options.jobs), "--seed", "1", "--out", out.string()};
}

Measurement measureRun(const BenchOptions& options, std::uint64_t samples, std::size_t batch, const fs::path& work,
                       const std::vector<std::string>& extra = {}) {
  const fs::path out = work / fmt::format("run_{}_{}", samples, batch);
  auto args = runArguments(options, samples, batch, out);
  args.insert(args.end(), extra.begin(), extra.end());
  const auto [result, cpu_seconds] = runVsdSumo(args, work);
  std::error_code ignored;
  fs::remove_all(out, ignored);
  return {samples, batch, result.seconds, cpu_seconds, result.maxRssKiB};
}

/// `mpirun -n <ranks> vsd-sumo run ...` (one core per rank, nothing oversubscribed).
Measurement measureMpiRun(const BenchOptions& options, int ranks, const fs::path& out, const fs::path& work) {
  std::vector<std::string> argv = {"mpirun", "-n", std::to_string(ranks)};
  if (::geteuid() == 0) argv.emplace_back("--allow-run-as-root");
  argv.insert(argv.end(), {siblingExecutable("vsd-sumo"), "--quiet"});
  const auto args = runArguments(options, options.mpiSamples, options.batch, out);
  argv.insert(argv.end(), args.begin(), args.end());
  const auto [result, cpu_seconds] = runChecked(argv, work);
  return {options.mpiSamples, options.batch, result.seconds, cpu_seconds, result.maxRssKiB};
}

/// True if the run folders `a` and `b` hold the same bytes in every output file.
bool sameOutputs(const fs::path& a, const fs::path& b) {
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    if (sha256OfFile(a / file) != sha256OfFile(b / file)) return false;
  }
  return true;
}

/// 2 MPI ranks vs 1 (each rank one process on its own core), and whether the merged
/// outputs of both equal a one-process run's bytes.
void printMpiBench(const BenchOptions& options, const fs::path& work) {
  if (pipeline::mpiLibraryVersion().empty()) {
    fmt::print("  MPI: not in this build (no rank comparison)\n");
    return;
  }
  const fs::path plain = work / "mpi_plain";
  runSelf(runArguments(options, options.mpiSamples, options.batch, plain), work);
  const Measurement one = measureMpiRun(options, 1, work / "mpi_1", work);
  const Measurement two = measureMpiRun(options, 2, work / "mpi_2", work);
  runSelf({"merge", (work / "mpi_1").string()}, work);
  const auto merge = runSelf({"merge", (work / "mpi_2").string()}, work);
  fmt::print("  mpirun -n 1 vs -n 2 (--samples {}): {:.1f} vs {:.1f} scenarios/s = {:.2f}x; merging the 2 shards "
             "{:.2f} s; merged outputs byte-identical to one process: {}\n",
             options.mpiSamples, one.rate(), two.rate(), two.rate() / one.rate(), merge.seconds,
             sameOutputs(plain, work / "mpi_1") && sameOutputs(plain, work / "mpi_2") ? "yes" : "NO");
}

std::string loadAverageNow() {
  double load[3] = {0.0, 0.0, 0.0};
  if (::getloadavg(load, 3) != 3) return "unknown";
  return fmt::format("{:.2f} {:.2f} {:.2f}", load[0], load[1], load[2]);
}

int runBench(const BenchOptions& options) {
  TemporaryDirectory work("vsd-bench");
  fmt::print("vsd-sumo bench run: {} (jobs {}), end to end: sample -> net -> simulate -> metrics -> files; load "
             "average before: {}\n",
             options.scenario.string(), options.jobs, loadAverageNow());
  const Measurement batched = measureRun(options, options.samples, options.batch, work.path());
  const Measurement netconvert =
      measureRun(options, options.samples, options.batch, work.path(), {"--net-writer", "netconvert"});
  const Measurement single = measureRun(options, options.batchOneSamples, 1, work.path());
  fmt::print("  {:<36} {:>8} {:>10} {:>14} {:>16}\n", "mode", "samples", "seconds", "scenarios/s", "CPU ms/scenario");
  auto print_row = [](const std::string& mode, const Measurement& measurement) {
    fmt::print("  {:<36} {:>8} {:>10.2f} {:>14.1f} {:>16.3f}\n", mode, measurement.samples, measurement.seconds,
               measurement.rate(), measurement.cpuMillisecondsPerSample());
  };
  print_row(fmt::format("batch {}", batched.batch), batched);
  // Per road user and step, the unit of the issue-23 target (every process of the run counted).
  const auto logical = scenario::loadLogicalScenario(options.scenario);
  const auto vehicle_steps = static_cast<double>((1 + logical->others.size()) * static_cast<std::size_t>(logical->steps()));
  fmt::print("  {:<36} {:>8} {:>10} {:>14} {:>16.2f}  ({} road users x {} steps)\n", "  CPU us per simulated vehicle-step",
             "", "", "", 1000.0 * batched.cpuMillisecondsPerSample() / vehicle_steps, 1 + logical->others.size(),
             logical->steps());
  print_row(fmt::format("batch {}, --net-writer netconvert", netconvert.batch), netconvert);
  print_row("batch 1 (net + sim each)", single);
  fmt::print("  speed-up of batching: {:.0f}x; CPU time per scenario counts every process of the run\n",
             batched.rate() / single.rate());
  fmt::print("  peak memory (RSS) as --samples grows:\n");
  for (const auto samples : options.memorySamples) {
    const Measurement memory = measureRun(options, samples, options.batch, work.path());
    fmt::print("    --samples {:>7}: {:>7.1f} MiB ({:.0f} scenarios/s)\n", samples,
               static_cast<double>(memory.maxRssKiB) / 1024.0, memory.rate());
  }
  printMpiBench(options, work.path());
  return 0;
}

struct IsolationBenchOptions {
  fs::path scenario = "scenarios/acc_lk.yaml";
  std::uint64_t samples = 2000;
  std::size_t batch = pipeline::RunOptions::kDefaultBatch;
  int rounds = 3;
};

/// One `run` in this process: wall time and the resources of this process (the
/// parent) and of the worker processes it forked and reaped.
struct IsolationMeasurement {
  double seconds = 0.0;
  Usage parent;
  Usage workers;
  double cpu() const { return parent.cpu() + workers.cpu(); }
};

pipeline::RunOptions isolationRun(const IsolationBenchOptions& options, pipeline::RunOptions::Isolation isolation,
                                  const fs::path& out) {
  pipeline::RunOptions run;
  run.scenarioFile = options.scenario;
  run.outputDir = out;
  run.samples = options.samples;
  run.batch = options.batch;
  run.seed = 1;
  run.jobs = 1;
  run.isolation = isolation;
  return run;
}

IsolationMeasurement measureIsolation(const pipeline::RunOptions& run) {
  const Usage parent = Usage::of(RUSAGE_SELF), workers = Usage::of(RUSAGE_CHILDREN);
  const auto start = std::chrono::steady_clock::now();
  pipeline::runScenarios(run);
  const double seconds = secondsSince(start);
  return {seconds, Usage::of(RUSAGE_SELF) - parent, Usage::of(RUSAGE_CHILDREN) - workers};
}

/// What moving the outcomes through the pipe costs: encoding and decoding every
/// batch's outcomes as worker and parent do (CPU ms per scenario, bytes per scenario).
std::pair<double, double> outcomeCodecCost(const IsolationBenchOptions& options) {
  auto run = isolationRun(options, pipeline::RunOptions::Isolation::None, {});
  run.writeFiles = false;
  std::vector<pipeline::ScenarioOutcome> outcomes;
  pipeline::runScenarios(run, [&](const pipeline::ScenarioOutcome& outcome) { outcomes.push_back(outcome); });
  const Usage before = Usage::of(RUSAGE_SELF);
  double bytes = 0.0;
  for (std::size_t first = 0; first < outcomes.size(); first += options.batch) {
    const std::vector<pipeline::ScenarioOutcome> batch(
        outcomes.begin() + static_cast<std::ptrdiff_t>(first),
        outcomes.begin() + static_cast<std::ptrdiff_t>(std::min(outcomes.size(), first + options.batch)));
    const auto message = pipeline::encodeOutcomes(batch);
    bytes += static_cast<double>(message.size());
    if (pipeline::decodeOutcomes(message).size() != batch.size()) throw Error("internal: outcome codec lost scenarios");
  }
  const double cpu = (Usage::of(RUSAGE_SELF) - before).cpu();
  const auto n = static_cast<double>(std::max<std::size_t>(outcomes.size(), 1));
  return {1000.0 * cpu / n, bytes / n};
}

/// CPU time (parent + child, ms) of forking this process and reaping a child that
/// exits at once: what starting a worker costs before it does any work (the page
/// tables of this process are copied and torn down again).
double forkMilliseconds(int forks) {
  const Usage parent = Usage::of(RUSAGE_SELF), children = Usage::of(RUSAGE_CHILDREN);
  for (int i = 0; i < forks; ++i) {
    const pid_t pid = ::fork();
    if (pid < 0) throw Error("bench: cannot fork");
    if (pid == 0) ::_exit(0);
    int status = 0;
    ::waitpid(pid, &status, 0);
  }
  const double cpu = (Usage::of(RUSAGE_SELF) - parent).cpu() + (Usage::of(RUSAGE_CHILDREN) - children).cpu();
  return 1000.0 * cpu / forks;
}


double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// `run` with its controllers and libsumo in a worker process (what users get) vs in
/// the calling process (RunOptions::Isolation::None), alternating, both in this process.
int runIsolationBench(const IsolationBenchOptions& options) {
  using Isolation = pipeline::RunOptions::Isolation;
  TemporaryDirectory work("vsd-bench-isolation");
  fmt::print("vsd-sumo bench isolation: {}, --samples {} --net-batch {} --jobs 1, {} rounds (order alternating); load "
             "average before: {}\n",
             options.scenario.string(), options.samples, options.batch, options.rounds, loadAverageNow());
  fmt::print("  per scenario: CPU ms = user + system of the parent and its workers; faults = minor page faults\n");
  fmt::print("  {:<5} {:<9} {:>8} {:>11} {:>8} {:>12} {:>12} {:>14} {:>14}\n", "round", "isolation", "seconds",
             "scenarios/s", "CPU ms", "parent u+s", "workers u+s", "parent faults", "workers faults");
  std::map<Isolation, std::vector<IsolationMeasurement>> measured;
  const std::map<Isolation, std::string> names = {{Isolation::None, "none"}, {Isolation::Process, "process"}};
  const auto n = static_cast<double>(options.samples);
  for (int round = 1; round <= options.rounds; ++round) {
    std::vector<Isolation> order = {Isolation::None, Isolation::Process};
    if (round % 2 == 0) std::reverse(order.begin(), order.end());
    for (const auto isolation : order) {
      const fs::path out = work.path() / names.at(isolation);
      fs::remove_all(out);
      const auto m = measureIsolation(isolationRun(options, isolation, out));
      const auto& p = m.parent;
      const auto& w = m.workers;
      fmt::print("  {:<5} {:<9} {:>8.2f} {:>11.1f} {:>8.3f} {:>5.3f}+{:.3f} {:>5.3f}+{:.3f} {:>14.0f} {:>14.0f}\n", round,
                 names.at(isolation), m.seconds, n / m.seconds, 1000.0 * m.cpu() / n, 1000.0 * p.user / n,
                 1000.0 * p.system / n, 1000.0 * w.user / n, 1000.0 * w.system / n, p.pageFaults / n,
                 w.pageFaults / n);
      measured[isolation].push_back(m);
    }
  }
  auto median_of = [&](Isolation isolation, const std::function<double(const IsolationMeasurement&)>& value) {
    std::vector<double> values;
    for (const auto& m : measured[isolation]) values.push_back(value(m));
    return median(values);
  };
  const auto cpu = [](const IsolationMeasurement& m) { return m.cpu(); };
  const auto system = [](const IsolationMeasurement& m) { return m.parent.system + m.workers.system; };
  const auto wall = [](const IsolationMeasurement& m) { return m.seconds; };
  const double cpu_none = median_of(Isolation::None, cpu), cpu_process = median_of(Isolation::Process, cpu);
  const double wall_none = median_of(Isolation::None, wall), wall_process = median_of(Isolation::Process, wall);
  fmt::print("  medians: CPU {:.3f} (none) vs {:.3f} (process) ms/scenario = {:+.1f} % (system time {:.3f} vs {:.3f}); "
             "wall {:.2f} vs {:.2f} s = {:+.1f} %\n",
             1000.0 * cpu_none / n, 1000.0 * cpu_process / n, 100.0 * (cpu_process / cpu_none - 1.0),
             1000.0 * median_of(Isolation::None, system) / n, 1000.0 * median_of(Isolation::Process, system) / n,
             wall_none, wall_process, 100.0 * (wall_process / wall_none - 1.0));
  fmt::print("  outputs (concrete.csv, traces.h5, dataset.h5) byte-identical: {}\n",
             sameOutputs(work.path() / "none", work.path() / "process") ? "yes" : "NO");
  const auto [codec_ms, codec_bytes] = outcomeCodecCost(options);
  fmt::print("  of the difference: encoding + decoding the outcomes for the pipe {:.3f} ms CPU per scenario ({:.1f} "
             "KiB per scenario)\n",
             codec_ms, codec_bytes / 1024.0);
  const double fork_ms = forkMilliseconds(20);
  fmt::print("  starting a worker (fork + exit, no work) {:.2f} ms CPU; a run starts two (controller probe, worker): "
             "{:.4f} ms per scenario\n",
             fork_ms, 2.0 * fork_ms / n);
  fmt::print("  load average after: {}\n", loadAverageNow());
  return 0;
}

struct ExportBenchOptions {
  fs::path map = "/usr/share/sumo/tools/game/A10KW.sumocfg";
  double end = 300.0;
  std::string egos = "all";
  std::vector<double> memoryEnds = {100.0, 400.0};
};

int runExportBench(const ExportBenchOptions& options) {
  TemporaryDirectory work("vsd-bench");
  fmt::print("vsd-sumo bench export: {} (--egos {}), one process, defaults otherwise\n", options.map.string(),
             options.egos);
  fmt::print("  {:<22} {:>9} {:>9} {:>12} {:>14} {:>10}\n", "mode", "sim [s]", "samples", "samples/s", "bytes/sample",
             "peak RSS");
  auto measure = [&](double end, int compression) {
    const fs::path out = work.path() / "bench.h5";
    const auto result = runSelf({"export", options.map.string(), "--out", out.string(), "--egos", options.egos, "--end",
                                 fmt::format("{}", end), "--compression", std::to_string(compression)},
                                work.path());
    const vector::DatasetReader reader(out);
    const auto samples = static_cast<double>(reader.size());
    fmt::print("  {:<22} {:>9.0f} {:>9.0f} {:>12.0f} {:>14.0f} {:>7.1f} MiB\n",
               fmt::format("compression {}", compression), end, samples, samples / result.seconds,
               static_cast<double>(fs::file_size(out)) / samples, static_cast<double>(result.maxRssKiB) / 1024.0);
    fs::remove(out);
  };
  measure(options.end, 1);
  measure(options.end, 0);
  fmt::print("  peak memory as the number of samples grows (compression 1):\n");
  for (const double end : options.memoryEnds) measure(end, 1);
  return 0;
}

/// Seeds of `bench model`'s training and test scenarios (test: fresh scenarios).
constexpr std::uint64_t kModelBenchTrainSeed = 1;
constexpr std::uint64_t kModelBenchTestSeed = 2;

struct ModelBenchOptions {
  fs::path work;               ///< keeps the generated data and models here (default: a temporary folder)
  std::uint64_t samples = 2000;
  std::uint64_t testSamples = 2000;
  bool singles = false;
  bool row4 = false;           ///< also train on acc + lk only and test on acc_lk (the paper's row 4)
  bool resume = false;         ///< continue trainings from <model>.last where it exists
  int threads = 2;
  int steps = 6000;            ///< optimizer steps of every training
  std::string decoder = "kinematic";
  std::vector<std::string> decoderOptions;  ///< name=value
  std::string frame = "ego";
  int draws = 32;              ///< sampled futures per scene for the inference and interval benchmarks
};

/// For the metrics of the issue (a_min, d_min, lane_offset_max where the scenario has
/// them), `vsd-sumo compare`'s scenario mode on the test run's scenarios (same file, seed
/// and count: fresh SUMO runs, the metric registry on the trace and on the prediction with
/// the same scene context): the MAE and bias of the most likely future's metric against
/// the simulated value, the floor (the metric of the simulated positions), and for sampled
/// futures the MAE of their median and the coverage of their 50 % / 90 % intervals.
void printMetricAccuracy(const model::Predictor& predictor, const fs::path& scenario_file, std::uint64_t samples,
                         std::uint64_t seed, int draws, int threads) {
  compare::CompareOptions options;
  options.scenarioFile = scenario_file;
  options.samples = samples;
  options.seed = seed;
  options.threads = threads;
  options.draws = draws;
  const auto comparison = compare::compareScenarioPredictions(options, predictor);
  const auto statistics = report::computeStatistics(comparison);
  fmt::print("    {:<16} {:>7} {:>9} {:>9} {:>11} {:>11} {:>9} {:>9}\n", scenario_file.stem().string(), "scenes", "MAE",
             "bias", "MAE floor", "MAE median", "cover 50%", "cover 90%");
  for (const auto& m : statistics.metrics) {
    if (m.name != "a_min" && m.name != "d_min" && m.name != "lane_offset_max") continue;
    auto drawn = [&](double value) { return m.intervalPairs ? fmt::format("{:.3f}", value) : std::string("-"); };
    fmt::print("    {:<16} {:>7} {:>9.3f} {:>+9.3f} {:>11} {:>11} {:>9} {:>9}\n", m.name, m.pairs, m.mae, m.bias,
               m.floorMae ? fmt::format("{:.3f}", *m.floorMae) : std::string("-"), drawn(m.medianDrawMae),
               drawn(m.coverage50), drawn(m.coverage90));
  }
}

/// Scenes per second of predicting the most likely future and `draws` sampled futures of
/// every test scene (read once, predicted in chunks as `evaluate` does).
double samplingRate(const model::Predictor& predictor, const std::vector<fs::path>& tests, int draws) {
  std::vector<vector::VectorizedScene> scenes;
  for (const auto& path : tests) {
    const vector::DatasetReader reader(vector::resolveDatasetPath(path));
    for (std::size_t i = 0; i < reader.size(); ++i) scenes.push_back(reader.scene(i));
  }
  model::PredictOptions options;
  options.samples = draws;
  const auto start = std::chrono::steady_clock::now();
  std::size_t predicted = 0;
  for (std::size_t first = 0; first < scenes.size(); first += 4096) {
    const std::vector<vector::VectorizedScene> chunk(scenes.begin() + static_cast<std::ptrdiff_t>(first),
                                                     scenes.begin() + static_cast<std::ptrdiff_t>(std::min(scenes.size(), first + 4096)));
    predicted += predictor.predictDistribution(chunk, options).size();
  }
  return static_cast<double>(predicted) / secondsSince(start);
}

int runModelBench(const ModelBenchOptions& options) {
  std::optional<TemporaryDirectory> temporary;
  fs::path work = options.work;
  if (work.empty()) {
    temporary.emplace("vsd-bench");
    work = temporary->path();
  }
  ensureDirectory(work);
  const fs::path scenarios = fs::path(VSD_SOURCE_DIR) / "scenarios";
  fmt::print("vsd-sumo bench model: VectorNet on {} training + {} test samples per functional scenario ({} threads)\n",
             options.samples, options.testSamples, options.threads);
  double simulation_rate = 0.0;
  for (const std::string name : {"acc", "lk", "acc_lk"}) {
    for (const auto& [kind, samples, seed] : {std::tuple{std::string("train"), options.samples, kModelBenchTrainSeed},
                                                std::tuple{std::string("test"), options.testSamples, kModelBenchTestSeed}}) {
      const fs::path out = work / fmt::format("{}_{}", kind, name);
      if (fs::exists(out / "dataset.h5")) continue;
      const auto result = runSelf({"run", (scenarios / (name + ".yaml")).string(), "--samples", std::to_string(samples),
                                   "--seed", std::to_string(seed), "--out", out.string()},
                                  work);
      if (name == "acc_lk") simulation_rate = static_cast<double>(samples) / result.seconds;
    }
  }
  std::vector<fs::path> tests;
  for (const std::string label : {"acc", "lk", "acc_lk"}) tests.push_back(work / ("test_" + label));
  auto train_and_evaluate = [&](const std::string& mix, const std::vector<std::string>& labels,
                                const std::string& model_name) {
    model::TrainOptions train_options;
    for (const auto& label : labels) train_options.data.push_back(work / ("train_" + label));
    train_options.mix = model::Mix::parse(mix);
    train_options.output = work / model_name;
    train_options.threads = options.threads;
    train_options.steps = options.steps;
    train_options.config.decoder = options.decoder;
    train_options.config.decoderOptions = model::parseDecoderOptions(options.decoderOptions);
    train_options.config.frame = options.frame;
    train_options.resume = options.resume && fs::exists(train_options.output.string() + ".last");
    experiment::bindCalibrationMetrics(train_options);
    // A finished training leaves its model and no <model>.last: with --resume it is reused as it is.
    const bool finished = options.resume && !train_options.resume && fs::exists(train_options.output);
    const auto summary = finished ? model::TrainSummary{} : model::train(train_options);
    const model::Predictor predictor(train_options.output, options.threads);
    const auto evaluation = model::evaluate(predictor, tests);
    fmt::print("  mix {:<32} trained in {:>5.1f} s ({} epochs, {:.0f} samples/s), test ADE [m]:", mix, summary.seconds,
               summary.plannedEpochs, summary.samplesPerSecond);
    for (const auto& [label, errors] : evaluation.perLabel) fmt::print(" {} {:.3f}", label, errors.ade);
    fmt::print("\n");
    if (evaluation.overall.scored > 0) fmt::print("{}", evaluation.table());
    return std::pair{summary, evaluation};
  };
  fmt::print("  decoder {}{}{}, frame {}, {} optimizer steps\n", options.decoder, options.decoderOptions.empty() ? "" : " ",
             fmt::join(options.decoderOptions, " "), options.frame, options.steps);
  std::string suffix = fmt::format("_{}_{}", options.decoder, options.frame);
  for (const auto& option : options.decoderOptions) suffix += "_" + option;
  suffix += ".pt";
  const auto [summary, evaluation] = train_and_evaluate(
      fmt::format("acc={0},lk={0},acc_lk={0}", options.samples), {"acc", "lk", "acc_lk"}, "all" + suffix);
  {
    const model::Predictor all(work / ("all" + suffix), options.threads);
    fmt::print("  metrics of the all-three model's predictions vs. fresh SUMO runs of the test scenarios (as `vsd-sumo "
               "compare`); floor: metric of the simulated positions; intervals of {} sampled futures:\n",
               options.draws);
    for (const std::string label : {"acc", "lk", "acc_lk"}) {
      printMetricAccuracy(all, scenarios / (label + ".yaml"), options.testSamples, kModelBenchTestSeed, options.draws,
                          options.threads);
    }
  }
  if (options.singles) {
    for (const std::string label : {"acc", "lk", "acc_lk"}) {
      train_and_evaluate(fmt::format("{}={}", label, options.samples), {label}, label + suffix);
    }
  }
  if (options.row4) {
    fmt::print("  row 4 (ACC + LK -> ACC&LK): the acc_lk column below\n");
    train_and_evaluate(fmt::format("acc={0},lk={0}", options.samples), {"acc", "lk"}, "row4" + suffix);
  }
  const double inference_rate = static_cast<double>(evaluation.overall.samples) / evaluation.predictionSeconds;
  fmt::print("  training throughput: {:.0f} samples/s; {} samples to convergence (end of the schedule) in {:.1f} s\n",
             summary.samplesPerSecond, 3 * options.samples, summary.seconds);
  fmt::print("  inference: {:.0f} scenes/s batched (most likely future)", inference_rate);
  if (simulation_rate > 0.0) {
    fmt::print(" = {:.1f}x the simulation throughput of `vsd-sumo run` ({:.0f} scenarios/s, acc_lk)",
               inference_rate / simulation_rate, simulation_rate);
  }
  fmt::print("\n");
  const model::Predictor predictor(work / ("all" + suffix), options.threads);
  if (predictor.probabilistic() && options.draws > 0) {
    fmt::print("  inference with {} sampled futures per scene: {:.0f} scenes/s\n", options.draws,
               samplingRate(predictor, tests, options.draws));
  }
  return 0;
}

struct CompareBenchOptions {
  fs::path model;
  fs::path scenario = "scenarios/acc_lk.yaml";
  std::vector<std::uint64_t> samples = {500, 5000};
  int jobs = 1;
};

/// `vsd-sumo compare` as separate processes: prediction + simulation + report, wall time,
/// report size and peak memory.
int runCompareBench(const CompareBenchOptions& options) {
  TemporaryDirectory work("vsd-bench-compare");
  fmt::print("vsd-sumo bench compare: {} with {} (jobs {}), end to end: vectorize -> predict -> simulate -> "
             "compare -> report\n",
             options.scenario.string(), options.model.string(), options.jobs);
  fmt::print("  {:>8} {:>10} {:>14} {:>14} {:>12}\n", "samples", "seconds", "scenarios/s", "report [MiB]", "peak RSS");
  for (const auto samples : options.samples) {
    const fs::path out = work.path() / fmt::format("compare_{}", samples);
    const auto result = runSelf({"compare", options.scenario.string(), "--model", options.model.string(), "--samples",
                                 std::to_string(samples), "--seed", "99", "--jobs", std::to_string(options.jobs),
                                 "--out", out.string()},
                                work.path());
    const double report_mib = static_cast<double>(fs::file_size(out / "report.html")) / (1024.0 * 1024.0);
    fmt::print("  {:>8} {:>10.2f} {:>14.1f} {:>14.2f} {:>8.1f} MiB\n", samples, result.seconds,
               static_cast<double>(samples) / result.seconds, report_mib, static_cast<double>(result.maxRssKiB) / 1024.0);
  }
  return 0;
}

}  // namespace

void addBenchCommand(CLI::App& app, CommandContext& context) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks whose output is recorded under results/ (docs/benchmarks.md)");
  bench->require_subcommand(1);
  auto options = std::make_shared<BenchOptions>();
  CLI::App* run = bench->add_subcommand("run", "Throughput and peak memory of `vsd-sumo run`");
  run->add_option("scenario", options->scenario, "Logical scenario")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(run, "--samples", options->samples, "Samples for the batched run")->capture_default_str();
  addNumber(run, "--batch-one-samples", options->batchOneSamples, "Samples for the --net-batch 1 run")
      ->capture_default_str();
  addNumber(run, "--memory-samples", options->memorySamples, "Sample counts for the memory runs")
      ->capture_default_str();
  addNumber(run, "--net-batch", options->batch, "Samples per SUMO network of the batched runs")->capture_default_str();
  addNumber(run, "--jobs", options->jobs, "Worker processes")->capture_default_str();
  addNumber(run, "--mpi-samples", options->mpiSamples, "Samples for the MPI runs (1 rank vs 2)")
      ->capture_default_str();
  run->callback([options, &context] { context.action = [options] { return runBench(*options); }; });

  auto isolation_options = std::make_shared<IsolationBenchOptions>();
  CLI::App* isolation = bench->add_subcommand(
      "isolation", "CPU and wall time of `run` --jobs 1 with its controllers and libsumo in a worker process vs in "
                   "this process");
  isolation->add_option("scenario", isolation_options->scenario, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  addNumber(isolation, "--samples", isolation_options->samples, "Samples per run")->capture_default_str();
  addNumber(isolation, "--net-batch", isolation_options->batch, "Samples per SUMO network")->capture_default_str();
  addNumber(isolation, "--rounds", isolation_options->rounds, "Rounds of both runs")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  isolation->callback([isolation_options, &context] {
    context.action = [isolation_options] { return runIsolationBench(*isolation_options); };
  });

  auto export_options = std::make_shared<ExportBenchOptions>();
  CLI::App* exporting = bench->add_subcommand("export", "Throughput, size and peak memory of `vsd-sumo export`");
  exporting->add_option("map", export_options->map, "SUMO configuration")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(exporting, "--end", export_options->end, "Simulated seconds")->capture_default_str();
  exporting->add_option("--egos", export_options->egos, "Ego selection")->capture_default_str();
  addNumber(exporting, "--memory-ends", export_options->memoryEnds, "Simulated seconds for the memory runs")
      ->capture_default_str();
  exporting->callback([export_options, &context] {
    context.action = [export_options] { return runExportBench(*export_options); };
  });

  auto model_options = std::make_shared<ModelBenchOptions>();
  CLI::App* modeling = bench->add_subcommand("model", "Training and inference throughput and test ADE of VectorNet");
  modeling->add_option("--work", model_options->work, "Keep data and models in this folder (reused when present)");
  addNumber(modeling, "--samples", model_options->samples, "Training samples per functional scenario")
      ->capture_default_str();
  addNumber(modeling, "--test-samples", model_options->testSamples, "Test samples per functional scenario")
      ->capture_default_str();
  modeling->add_flag("--singles", model_options->singles, "Also train one model per functional scenario");
  addNumber(modeling, "--threads", model_options->threads, "libtorch threads")->capture_default_str();
  modeling->add_option("--decoder", model_options->decoder, "Decoder of the trained models")->capture_default_str();
  modeling->add_option("--decoder-option", model_options->decoderOptions, "Decoder option name=value (repeatable)");
  modeling->add_option("--steps", model_options->steps, "Optimizer steps of every training")->capture_default_str();
  modeling->add_flag("--resume", model_options->resume,
                     "Continue trainings from <model>.last where it exists; reuse finished models");
  modeling->add_flag("--row4", model_options->row4, "Also train on acc + lk only and test on acc_lk (paper row 4)");
  modeling->add_option("--frame", model_options->frame, "Model frame (ego, lane)")->capture_default_str();
  addNumber(modeling, "--futures", model_options->draws, "Sampled futures per scene in the inference benchmark")
      ->capture_default_str();
  modeling->callback([model_options, &context] {
    context.action = [model_options] { return runModelBench(*model_options); };
  });

  auto compare_options = std::make_shared<CompareBenchOptions>();
  CLI::App* comparing = bench->add_subcommand("compare", "Wall time, report size and peak memory of `vsd-sumo compare`");
  comparing->add_option("--model", compare_options->model, "VectorNet model file")->required()->check(CLI::ExistingFile);
  comparing->add_option("scenario", compare_options->scenario, "Logical scenario")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  addNumber(comparing, "--samples", compare_options->samples, "Scenario counts to compare")->capture_default_str();
  addNumber(comparing, "--jobs", compare_options->jobs, "SUMO worker processes")->capture_default_str();
  comparing->callback([compare_options, &context] {
    context.action = [compare_options] { return runCompareBench(*compare_options); };
  });

  addInteropBench(*bench, context);
  addLibraryBench(*bench, context);
  addSearchBench(*bench, context);
  addDeviationsBench(*bench, context);
  addTrainBench(*bench, context);
  addReferenceBench(*bench, context);
}

}  // namespace vsd::cli
