// `bench isolation` (run_bench.hpp): both isolations of `run` in this process, alternating
// per round so that drifting load affects both alike.

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <functional>

#include "vsd/bench/run_bench.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/statistics.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

using Isolation = pipeline::RunOptions::Isolation;

pipeline::RunOptions isolationRun(const IsolationBenchOptions& options, Isolation isolation, const fs::path& out) {
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

IsolationMeasurement measureIsolation(const pipeline::RunOptions& run, int round) {
  const Usage parent = Usage::self(), workers = Usage::children();
  const auto start = std::chrono::steady_clock::now();
  pipeline::runScenarios(run);
  const double seconds = secondsSince(start);
  return {round, run.isolation, seconds, Usage::self() - parent, Usage::children() - workers};
}

/// What moving the outcomes through the pipe costs: every batch's outcomes encoded and
/// decoded as worker and parent do (CPU ms per scenario, bytes per scenario).
std::pair<double, double> workerPipeCost(const IsolationBenchOptions& options) {
  auto run = isolationRun(options, Isolation::None, {});
  run.writeFiles = false;
  std::vector<pipeline::ScenarioOutcome> outcomes;
  pipeline::runScenarios(run, [&](const pipeline::ScenarioOutcome& outcome) { outcomes.push_back(outcome); });
  const Usage before = Usage::self();
  double bytes = 0.0;
  for (std::size_t first = 0; first < outcomes.size(); first += options.batch) {
    const std::vector<pipeline::ScenarioOutcome> batch(
        outcomes.begin() + static_cast<std::ptrdiff_t>(first),
        outcomes.begin() + static_cast<std::ptrdiff_t>(std::min(outcomes.size(), first + options.batch)));
    bytes += static_cast<double>(pipeline::passThroughWorkerPipe(batch));
  }
  const double cpu = (Usage::self() - before).cpu();
  const auto n = static_cast<double>(std::max<std::size_t>(outcomes.size(), 1));
  return {1000.0 * cpu / n, bytes / n};
}

/// CPU time (parent + child, ms) of forking this process and reaping a child that
/// exits at once: what starting a worker costs before it does any work (the page
/// tables of this process are copied and torn down again).
double forkMilliseconds(int forks) {
  const Usage parent = Usage::self(), children = Usage::children();
  for (int i = 0; i < forks; ++i) {
    const pid_t pid = ::fork();
    if (pid < 0) throw Error("bench: cannot fork");
    if (pid == 0) ::_exit(0);
    int status = 0;
    ::waitpid(pid, &status, 0);
  }
  const double cpu = (Usage::self() - parent).cpu() + (Usage::children() - children).cpu();
  return 1000.0 * cpu / forks;
}

}  // namespace

std::string isolationName(Isolation isolation) { return isolation == Isolation::None ? "none" : "process"; }

IsolationMedians IsolationBenchResult::medians(Isolation isolation) const {
  auto median_of = [&](const std::function<double(const IsolationMeasurement&)>& value) {
    std::vector<double> values;
    for (const auto& m : runs) {
      if (m.isolation == isolation) values.push_back(value(m));
    }
    return median(values);
  };
  return {median_of([](const IsolationMeasurement& m) { return m.cpu(); }),
          median_of([](const IsolationMeasurement& m) { return m.parent.system + m.workers.system; }),
          median_of([](const IsolationMeasurement& m) { return m.seconds; })};
}

IsolationBenchResult runIsolationBench(const IsolationBenchOptions& options) {
  TemporaryDirectory work("vsd-bench-isolation");
  IsolationBenchResult result;
  for (int round = 1; round <= options.rounds; ++round) {
    std::vector<Isolation> order = {Isolation::None, Isolation::Process};
    if (round % 2 == 0) std::reverse(order.begin(), order.end());
    for (const auto isolation : order) {
      const fs::path out = work.path() / isolationName(isolation);
      fs::remove_all(out);
      result.runs.push_back(measureIsolation(isolationRun(options, isolation, out), round));
    }
  }
  result.identical = sameRunOutputs(work.path() / "none", work.path() / "process");
  std::tie(result.codecMilliseconds, result.codecBytes) = workerPipeCost(options);
  result.forkMilliseconds = forkMilliseconds(20);
  return result;
}

}  // namespace vsd::bench
