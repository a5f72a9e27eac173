// `vsd-sumo bench run`: end-to-end throughput of `vsd-sumo run` (default batch
// vs. one network + one simulation per scenario, side by side) and peak memory
// as --samples grows. Each measurement is a separate `vsd-sumo run` process, so
// start-up, scenario loading and file writing are included and peak RSS is the
// run's own.

#include <fmt/format.h>

#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/process.hpp"
#include "vsd/pipeline/run.hpp"

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
};

struct Measurement {
  std::uint64_t samples = 0;
  std::size_t batch = 0;
  double seconds = 0.0;
  long maxRssKiB = 0;
  double rate() const { return static_cast<double>(samples) / seconds; }
};

Measurement measureRun(const BenchOptions& options, std::uint64_t samples, std::size_t batch, const fs::path& work) {
  const fs::path out = work / fmt::format("run_{}_{}", samples, batch);
  const std::vector<std::string> argv = {fs::read_symlink("/proc/self/exe").string(), "--quiet", "run",
                                         options.scenario.string(), "--samples", std::to_string(samples),
                                         "--batch", std::to_string(batch), "--jobs", std::to_string(options.jobs),
                                         "--seed", "1", "--out", out.string()};
  const auto result = runProcess(argv, work / "bench.log");
  if (result.exitCode != 0) {
    throw Error(fmt::format("benchmark run failed (exit {}): {}", result.exitCode, firstErrorLine(result.output)));
  }
  std::error_code ignored;
  fs::remove_all(out, ignored);
  return {samples, batch, result.seconds, result.maxRssKiB};
}

int runBench(const BenchOptions& options) {
  TemporaryDirectory work("vsd-bench");
  fmt::print("vsd-sumo bench run: {} (jobs {}), end to end: sample -> net -> simulate -> metrics -> files\n",
             options.scenario.string(), options.jobs);
  const Measurement batched = measureRun(options, options.samples, options.batch, work.path());
  const Measurement single = measureRun(options, options.batchOneSamples, 1, work.path());
  fmt::print("  {:<28} {:>8} {:>10} {:>14}\n", "mode", "samples", "seconds", "scenarios/s");
  fmt::print("  {:<28} {:>8} {:>10.2f} {:>14.1f}\n", fmt::format("batch {}", batched.batch), batched.samples,
             batched.seconds, batched.rate());
  fmt::print("  {:<28} {:>8} {:>10.2f} {:>14.1f}\n", "batch 1 (net + sim each)", single.samples, single.seconds,
             single.rate());
  fmt::print("  speed-up of batching: {:.0f}x\n", batched.rate() / single.rate());
  fmt::print("  peak memory (RSS) as --samples grows:\n");
  for (const auto samples : options.memorySamples) {
    const Measurement memory = measureRun(options, samples, options.batch, work.path());
    fmt::print("    --samples {:>7}: {:>7.1f} MiB ({:.0f} scenarios/s)\n", samples,
               static_cast<double>(memory.maxRssKiB) / 1024.0, memory.rate());
  }
  return 0;
}

}  // namespace

void addBenchCommand(CLI::App& app, CommandContext& context) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks whose output is recorded in the README");
  bench->require_subcommand(1);
  auto options = std::make_shared<BenchOptions>();
  CLI::App* run = bench->add_subcommand("run", "Throughput and peak memory of `vsd-sumo run`");
  run->add_option("scenario", options->scenario, "Logical scenario")->check(CLI::ExistingFile)->capture_default_str();
  run->add_option("--samples", options->samples, "Samples for the batched run")->capture_default_str();
  run->add_option("--batch-one-samples", options->batchOneSamples, "Samples for the --batch 1 run")
      ->capture_default_str();
  run->add_option("--memory-samples", options->memorySamples, "Sample counts for the memory runs")
      ->capture_default_str();
  run->add_option("--batch", options->batch, "Batch size of the batched runs")->capture_default_str();
  run->add_option("--jobs", options->jobs, "Worker processes")->capture_default_str();
  run->callback([options, &context] { context.action = [options] { return runBench(*options); }; });
}

}  // namespace vsd::cli
