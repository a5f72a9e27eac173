#include "vsd/pipeline/run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <fstream>
#include <optional>
#include <regex>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/outcome_codec.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/pipeline/worker_pool.hpp"
#include "vsd/road/network.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/batch_simulation.hpp"
#include "vsd/sim/trace_file.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

void RunOptions::validate() const {
  if (samples < 1 || samples > 100'000'000) {
    throw ConfigError::field("command line", "--samples", std::to_string(samples), "1 .. 100000000");
  }
  if (jobs < 1 || jobs > 256) throw ConfigError::field("command line", "--jobs", std::to_string(jobs), "1 .. 256");
  if (batch < 1 || batch > road::BatchLayout::kMaxBatch) {
    throw ConfigError::field("command line", "--batch", std::to_string(batch),
                             fmt::format("1 .. {}", road::BatchLayout::kMaxBatch));
  }
  // Sample indices are stored as int64 (datasets) and printed exactly (CSV): the
  // last one must stay far below 2^63 and must not wrap around.
  if (firstSample > kMaxSampleIndex - samples) {
    throw ConfigError::field("command line", "--first-sample", std::to_string(firstSample),
                             fmt::format("0 .. {} (minus --samples)", kMaxSampleIndex));
  }
  if (compression < 0 || compression > 9) {
    throw ConfigError::field("command line", "--compression", std::to_string(compression), "a deflate level 0 .. 9");
  }
}

namespace {

/// Everything a batch needs, shared (read-only) by all workers.
struct Context {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  RunOptions options;
  std::unique_ptr<metrics::MetricSet> metricSet;
  road::BatchLayout layout;
  fs::path workDir;
  std::size_t batches = 0;
  bool keepBatchFiles = false;
};

struct PreparedBatch {
  std::size_t number = 0;
  fs::path stem;
  std::vector<scenario::ConcreteScenario> scenarios;
  std::vector<road::RoadGeometry> roads;
  std::vector<std::string> preFailure;  ///< per scenario: why it cannot be simulated (empty: fine)
  std::optional<road::PendingNetwork> pending;
};

std::vector<std::string> netconvertOptions(const Context& context) { return context.logical->sumo.netconvertOptions; }

ScenarioWithRoad concreteScenario(const std::shared_ptr<const scenario::LogicalScenario>& logical,
                                  const RunOptions& options, std::uint64_t index) {
  if (options.source) return options.source(index);
  auto concrete = scenario::sampleConcreteScenario(logical, options.seed, index);
  auto road = road::buildRoadGeometry(concrete);
  return {std::move(concrete), std::move(road)};
}

/// Prepares, converts and simulates batches; one per process.
class BatchProcessor {
 public:
  explicit BatchProcessor(const Context& context) : context_(context), registry_(sim::ControllerRegistry::withBuiltins()) {}

  PreparedBatch prepare(std::size_t number) {
    const auto t_start = std::chrono::steady_clock::now();
    PreparedBatch batch;
    batch.number = number;
    batch.stem = context_.workDir / fmt::format("batch_{:05}", number);
    const std::uint64_t first = context_.options.firstSample + number * context_.options.batch;
    const std::uint64_t last =
        std::min(context_.options.firstSample + context_.options.samples, first + context_.options.batch);
    road::NetworkBuilder builder;
    for (std::uint64_t index = first; index < last; ++index) {
      auto [concrete, road] = concreteScenario(context_.logical, context_.options, index);
      batch.scenarios.push_back(std::move(concrete));
      batch.roads.push_back(std::move(road));
      std::string failure;
      if (!context_.layout.fits(batch.roads.back())) {
        const auto [lo, hi] = batch.roads.back().bounds();
        failure = fmt::format("road extends beyond its {:.0f} m layout cell (x {:.4g}..{:.4g} m, y {:.4g}..{:.4g} m)",
                              context_.layout.cellSize(), lo.x(), hi.x(), lo.y(), hi.y());
      } else {
        builder.add(index, batch.roads.back(), context_.layout.offsetFor(index));
      }
      batch.preFailure.push_back(failure);
    }
    if (!builder.empty()) {
      builder.writePlainXml(batch.stem);
      batch.pending = road::PendingNetwork::start(batch.stem, netconvertOptions(context_));
    }
    spdlog::debug("batch {}: sampled and wrote {} roads in {:.3f} s", number, batch.scenarios.size(),
                  secondsSince(t_start));
    return batch;
  }

  std::vector<ScenarioOutcome> finish(PreparedBatch& batch) {
    const auto t_start = std::chrono::steady_clock::now();
    std::vector<ScenarioOutcome> outcomes(batch.scenarios.size());
    for (std::size_t i = 0; i < batch.scenarios.size(); ++i) {
      outcomes[i].index = batch.scenarios[i].index;
      outcomes[i].inputs = batch.scenarios[i].inputs;
      outcomes[i].failure = batch.preFailure[i];
      outcomes[i].egoLane = batch.scenarios[i].ego.lane;
    }
    double wait_seconds = 0.0;
    if (batch.pending) {
      const fs::path net = convertIsolatingFailures(batch, outcomes);
      wait_seconds = secondsSince(t_start);
      simulate(batch, net, outcomes);
    }
    const double simulate_seconds = secondsSince(t_start) - wait_seconds;
    const std::size_t metric_count = context_.metricSet->names().size();
    for (auto& outcome : outcomes) {
      if (!outcome.ok()) {
        outcome.metrics.assign(metric_count, std::numeric_limits<double>::quiet_NaN());
        continue;
      }
      const auto lane = static_cast<std::size_t>(outcome.egoLane);
      const Polyline lane_centre = lane < outcome.lanes.size() ? outcome.lanes[lane].centre : Polyline{};
      outcome.metrics = context_.metricSet->evaluate({outcome.trace, lane_centre});
    }
    if (!context_.keepBatchFiles) removeBatchFiles(batch.stem);
    spdlog::debug("batch {}: waited {:.3f} s for netconvert, simulated {:.3f} s, metrics {:.3f} s", batch.number,
                  wait_seconds, simulate_seconds, secondsSince(t_start) - wait_seconds - simulate_seconds);
    return outcomes;
  }

 private:
  /// Converts the batch's network. If netconvert fails, each scenario is
  /// converted alone to find the culprits, which fail; if every scenario fails
  /// alone too, the fault is systemic and the run stops.
  fs::path convertIsolatingFailures(PreparedBatch& batch, std::vector<ScenarioOutcome>& outcomes) {
    try {
      return batch.pending->wait();
    } catch (const SumoError& batch_error) {
      std::size_t succeeded = 0;
      road::NetworkBuilder good;
      for (std::size_t i = 0; i < batch.scenarios.size(); ++i) {
        if (!outcomes[i].failure.empty()) continue;
        road::NetworkBuilder single;
        const auto index = batch.scenarios[i].index;
        single.add(index, batch.roads[i], context_.layout.offsetFor(index));
        const fs::path stem = batch.stem.string() + fmt::format(".single{}", index);
        single.writePlainXml(stem);
        try {
          road::PendingNetwork::start(stem, netconvertOptions(context_)).wait();
          good.add(index, batch.roads[i], context_.layout.offsetFor(index));
          ++succeeded;
        } catch (const SumoError& error) {
          outcomes[i].failure = error.what();
        }
        removeBatchFiles(stem);
      }
      if (succeeded == 0) throw batch_error;
      good.writePlainXml(batch.stem);
      return road::PendingNetwork::start(batch.stem, netconvertOptions(context_)).wait();
    }
  }

  void simulate(const PreparedBatch& batch, const fs::path& net, std::vector<ScenarioOutcome>& outcomes) {
    std::vector<sim::ScenarioRun> runs;
    std::vector<std::size_t> positions;
    for (std::size_t i = 0; i < batch.scenarios.size(); ++i) {
      if (!outcomes[i].failure.empty()) continue;
      const auto index = batch.scenarios[i].index;
      runs.push_back({&batch.scenarios[i], &batch.roads[i], context_.layout.offsetFor(index)});
      positions.push_back(i);
    }
    if (runs.empty()) return;
    sim::BatchOptions options;
    options.step = context_.logical->step;
    options.steps = context_.logical->steps();
    options.collisionAction = context_.logical->sumo.collisionAction;
    options.sumoOptions = context_.logical->sumo.sumoOptions;
    options.scenarioDir = context_.logical->sourceFile.parent_path();
    if (context_.options.fcd) options.fcdOutput = batch.stem.string() + ".fcd.xml";
    auto results = sim::simulateBatch(net, runs, registry_, options);
    for (std::size_t r = 0; r < results.size(); ++r) {
      auto& outcome = outcomes[positions[r]];
      outcome.failure = std::move(results[r].failure);
      outcome.trace = std::move(results[r].trace);
      outcome.lanes = std::move(results[r].lanes);
    }
  }

  static void removeBatchFiles(const fs::path& stem) {
    std::error_code ignored;
    for (const char* suffix : {".nod.xml", ".edg.xml", ".net.xml", ".netconvert.log"}) {
      fs::remove(stem.string() + suffix, ignored);
    }
  }

  const Context& context_;
  sim::ControllerRegistry registry_;
};

/// Processes batches first, first + stride, ... with netconvert for the next
/// batch running while the current one is simulated.
template <typename Deliver>
void processBatches(const Context& context, std::size_t first, std::size_t stride, Deliver&& deliver) {
  BatchProcessor processor(context);
  std::deque<PreparedBatch> ahead;
  std::size_t next = first;
  auto prepare_next = [&] {
    if (next < context.batches) {
      ahead.push_back(processor.prepare(next));
      next += stride;
    }
  };
  prepare_next();
  while (!ahead.empty()) {
    throwIfInterrupted();
    prepare_next();  // starts netconvert for the following batch before simulating this one
    PreparedBatch batch = std::move(ahead.front());
    ahead.pop_front();
    deliver(batch.number, processor.finish(batch));
  }
}

/// Groups failure messages that differ only in numbers ("at t = 3.4 s").
std::string failureKind(const std::string& failure) {
  static const std::regex numbers("[-+]?[0-9]+(\\.[0-9]+)?");
  return std::regex_replace(failure, numbers, "#");
}

class SummaryBuilder {
 public:
  SummaryBuilder(RunSummary& summary, const metrics::MetricSet& metric_set)
      : summary_(summary), metricSet_(metric_set) {
    summary_.metricNames = metric_set.names();
    summary_.collisionRule = metric_set.collisionRule();
    const auto units = metric_set.units();
    for (std::size_t m = 0; m < units.size(); ++m) {
      MetricSummary metric;
      metric.name = summary_.metricNames[m];
      metric.unit = units[m];
      metric.min = std::numeric_limits<double>::infinity();
      metric.max = -std::numeric_limits<double>::infinity();
      summary_.metrics.push_back(metric);
    }
    sums_.assign(units.size(), 0.0);
  }

  void add(const ScenarioOutcome& outcome) {
    if (!outcome.ok()) {
      ++summary_.failed;
      const std::string kind = failureKind(outcome.failure);
      ++summary_.failureReasons[kind];
      summary_.failureExamples.emplace(kind, outcome.failure);
      return;
    }
    ++summary_.ok;
    for (std::size_t m = 0; m < outcome.metrics.size(); ++m) {
      const double value = outcome.metrics[m];
      auto& metric = summary_.metrics[m];
      if (std::isinf(value)) {
        ++metric.infinite;
      } else if (std::isfinite(value)) {
        ++metric.finite;
        metric.min = std::min(metric.min, value);
        metric.max = std::max(metric.max, value);
        sums_[m] += value;
      }
    }
    if (metricSet_.collision(outcome.metrics)) ++summary_.collisions;
  }

  void finish() {
    for (std::size_t m = 0; m < summary_.metrics.size(); ++m) {
      auto& metric = summary_.metrics[m];
      if (metric.finite == 0) {
        metric.min = metric.mean = metric.max = std::numeric_limits<double>::quiet_NaN();
      } else {
        metric.mean = sums_[m] / static_cast<double>(metric.finite);
      }
    }
  }

 private:
  RunSummary& summary_;
  const metrics::MetricSet& metricSet_;
  std::vector<double> sums_;
};

/// concrete.csv + traces.h5 + dataset.h5, written under temporary names.
class RunFiles {
 public:
  RunFiles(const Context& context, const fs::path& out, const std::vector<std::string>& metric_names)
      : csvOutput_(out / "concrete.csv"), traceOutput_(out / "traces.h5"), datasetOutput_(out / "dataset.h5"),
        logical_(*context.logical), seed_(context.options.seed),
        scenarioSha256_(sha256OfFile(context.logical->sourceFile)) {
    csvStream_.open(csvOutput_.tempPath(), std::ios::binary | std::ios::trunc);
    if (!csvStream_) throw IoError(csvOutput_.finalPath().string() + ": cannot open for writing");
    csv_.emplace(csvStream_);
    std::vector<std::string> header = {"functional_scenario", "sample", "seed", "status", "failure"};
    for (const auto& input : logical_.inputs) header.push_back(input.name);
    header.insert(header.end(), metric_names.begin(), metric_names.end());
    csv_->writeRow(header);

    std::vector<std::string> ids = {logical_.ego.id};
    std::vector<double> lengths = {logical_.ego.length};
    std::vector<double> widths = {logical_.ego.width};
    for (const auto& other : logical_.others) {
      ids.push_back(other.id);
      lengths.push_back(other.length);
      widths.push_back(other.width);
    }
    traces_.emplace(traceOutput_.tempPath(), logical_.name, logical_.step,
                    static_cast<std::size_t>(logical_.steps()) + 1, ids, lengths, widths, traceOutput_.finalPath());
    vector::DatasetHeader dataset_header;
    dataset_header.kind = "generated";
    dataset_header.step = logical_.step;
    dataset_header.horizon = logical_.steps();
    dataset_header.inputNames = logical_.inputNames();
    dataset_header.metricNames = metric_names;
    dataset_header.compression = context.options.compression;
    dataset_.emplace(datasetOutput_.tempPath(), dataset_header, datasetOutput_.finalPath());
    emptyTrace_.step = logical_.step;
    for (std::size_t v = 0; v < ids.size(); ++v) {
      VehicleTrack track;
      track.id = ids[v];
      track.length = lengths[v];
      track.width = widths[v];
      emptyTrace_.vehicles.push_back(track);
    }
  }

  void write(const ScenarioOutcome& outcome) {
    std::vector<std::string> row = {logical_.name, std::to_string(outcome.index), std::to_string(seed_),
                                    outcome.ok() ? "ok" : "failed", outcome.failure};
    for (double value : outcome.inputs) row.push_back(formatNumber(value));
    for (double value : outcome.metrics) row.push_back(formatNumber(value));
    csv_->writeRow(row);
    // A scenario that failed before simulation has no trace: store an all-invalid one.
    traces_->append(outcome.index, outcome.trace.vehicles.empty() ? emptyTrace_ : outcome.trace, outcome.ok());
    // A failed run has no complete future of the Ego: it cannot be a training sample.
    if (outcome.ok()) dataset_->append(sceneOf(outcome));
  }

  vector::VectorizedScene sceneOf(const ScenarioOutcome& outcome) const {
    auto scene = simulatedScene(logical_, outcome);
    scene.provenance = {logical_.sourceFile.string(), scenarioSha256_, logical_.ego.id, 0.0};
    return scene;
  }

  /// Finishes both files and renames them into place.
  std::vector<fs::path> commit() {
    csvStream_.flush();
    if (!csvStream_) throw IoError(csvOutput_.finalPath().string() + ": write failed (disk full?)");
    csvStream_.close();
    traces_->close();
    dataset_->close();
    csvOutput_.commit();
    traceOutput_.commit();
    datasetOutput_.commit();
    return {csvOutput_.finalPath(), traceOutput_.finalPath(), datasetOutput_.finalPath()};
  }

 private:
  AtomicOutput csvOutput_;
  AtomicOutput traceOutput_;
  AtomicOutput datasetOutput_;
  const scenario::LogicalScenario& logical_;
  std::uint64_t seed_;
  std::string scenarioSha256_;
  std::ofstream csvStream_;
  std::optional<CsvWriter> csv_;
  std::optional<sim::TraceFileWriter> traces_;
  std::optional<vector::DatasetWriter> dataset_;
  Trace emptyTrace_;
};


void writeManifest(const Context& context, const RunSummary& summary, const fs::path& out,
                   const std::vector<fs::path>& outputs, const std::string& started) {
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  manifest["tool_version"] = toolVersion();
  manifest["sumo_version"] = sim::SumoSession::version();
  manifest["command_line"] = context.options.commandLine;
  manifest["scenario_file"] = context.logical->sourceFile.string();
  manifest["scenario_sha256"] = sha256OfFile(context.logical->sourceFile);
  manifest["functional_scenario"] = context.logical->name;
  manifest["seed"] = context.options.seed;
  manifest["first_sample"] = context.options.firstSample;
  manifest["samples"] = context.options.samples;
  manifest["batch"] = context.options.batch;
  manifest["jobs"] = context.options.jobs;
  manifest["started"] = started;
  manifest["finished"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["ok"] = summary.ok;
  manifest["failed"] = summary.failed;
  manifest["collisions"] = summary.collisions;
  manifest["inputs"] = summary.inputNames;
  manifest["metrics"] = summary.metricNames;
  nlohmann::json files = nlohmann::json::object();
  for (const auto& path : outputs) {
    if (fs::is_regular_file(path)) files[fs::relative(path, out).string()] = {{"sha256", sha256OfFile(path)},
                                                                             {"bytes", fs::file_size(path)}};
  }
  manifest["outputs"] = files;
  writeTextFileAtomically(out / "manifest.json", manifest.dump(2) + "\n");
}

/// Moves kept nets / FCD files from the work directory into <out>/nets and <out>/fcd.
std::vector<fs::path> publishBatchFiles(const Context& context, const fs::path& out) {
  std::vector<fs::path> published;
  const fs::path nets = out / "nets";
  const fs::path fcd = out / "fcd";
  std::error_code ignored;
  fs::remove_all(nets, ignored);
  fs::remove_all(fcd, ignored);
  ensureDirectory(nets);
  if (context.options.fcd) ensureDirectory(fcd);
  for (std::size_t b = 0; b < context.batches; ++b) {
    const std::string stem = fmt::format("batch_{:05}", b);
    for (const char* suffix : {".nod.xml", ".edg.xml", ".net.xml"}) {
      const fs::path source = context.workDir / (stem + suffix);
      if (fs::exists(source)) fs::rename(source, nets / (stem + suffix));
    }
    if (fs::exists(nets / (stem + ".net.xml"))) {
      writeTextFileAtomically(nets / (stem + ".sumocfg"),
                              fmt::format("<configuration>\n  <input>\n    <net-file value=\"{}.net.xml\"/>\n  </input>\n"
                                          "  <time>\n    <step-length value=\"{}\"/>\n  </time>\n</configuration>\n",
                                          stem, context.logical->step));
      published.push_back(nets / (stem + ".net.xml"));
    }
    const fs::path fcd_source = context.workDir / (stem + ".fcd.xml");
    if (context.options.fcd && fs::exists(fcd_source)) {
      fs::rename(fcd_source, fcd / (stem + ".fcd.xml"));
      published.push_back(fcd / (stem + ".fcd.xml"));
    }
  }
  return published;
}

}  // namespace

RunSummary runScenarios(const RunOptions& options, const OutcomeCallback& on_outcome) {
  return runScenarios(scenario::loadLogicalScenario(options.scenarioFile), options, on_outcome);
}

RunSummary runScenarios(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                        const OutcomeCallback& on_outcome) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  const std::string started = utcTimestamp();

  Context context;
  context.logical = logical;
  context.options = options;
  if (context.options.fcd) context.options.keepNets = true;
  context.options.jobs = static_cast<int>(std::min<std::uint64_t>(
      static_cast<std::uint64_t>(options.jobs), (options.samples + options.batch - 1) / options.batch));
  context.metricSet = std::make_unique<metrics::MetricSet>(
      logical->metrics, scenarioAvailability(*logical),
      logical->sourceFile.string() + ": metrics");
  context.batches = static_cast<std::size_t>((options.samples + options.batch - 1) / options.batch);
  context.keepBatchFiles = context.options.keepNets;
  context.layout = road::BatchLayout(road::BatchLayout::cellSizeFor(logical->road));

  // Fail fast on problems every scenario would hit (unknown controller, bad
  // parameters, bad expressions) before any process or file is created.
  {
    auto probe = concreteScenario(logical, options, options.firstSample).concrete;
    auto registry = sim::ControllerRegistry::withBuiltins();
    sim::makeController(registry, logical->ego.controller.name, logical->ego.controller.library,
                        logical->sourceFile.parent_path(),
                        sim::ControllerParams(probe.controllerParams, logical->ego.controller.where));
  }

  const fs::path out = options.outputDir.empty() ? fs::path("out") / logical->name : options.outputDir;
  std::optional<TemporaryDirectory> temporary_work;
  struct WorkDirGuard {
    fs::path path;
    ~WorkDirGuard() {
      std::error_code ignored;
      if (!path.empty()) fs::remove_all(path, ignored);
    }
  } work_guard;
  if (options.writeFiles) ensureDirectory(out);
  if (context.options.keepNets && options.writeFiles) {
    context.workDir = out / fmt::format(".work-{}", ::getpid());
    ensureDirectory(context.workDir);
    work_guard.path = context.workDir;
  } else {
    temporary_work.emplace("vsd-run");
    context.workDir = temporary_work->path();
  }

  RunSummary summary;
  summary.functionalScenario = logical->name;
  summary.outputDir = out;
  summary.samples = options.samples;
  summary.seed = options.seed;
  summary.jobs = context.options.jobs;
  summary.batch = options.batch;
  summary.inputNames = logical->inputNames();
  SummaryBuilder summary_builder(summary, *context.metricSet);

  std::optional<RunFiles> files;
  if (options.writeFiles) files.emplace(context, out, context.metricSet->names());

  Progress progress(fmt::format("run {}", logical->name), options.samples, "scenarios");
  auto consume = [&](const std::vector<ScenarioOutcome>& outcomes) {
    for (const auto& outcome : outcomes) {
      summary_builder.add(outcome);
      if (files) files->write(outcome);
      if (on_outcome) on_outcome(outcome);
    }
    progress.advance(outcomes.size());
  };

  if (context.options.jobs == 1) {
    processBatches(context, 0, 1, [&](std::size_t, std::vector<ScenarioOutcome> outcomes) { consume(outcomes); });
  } else {
    const int jobs = context.options.jobs;
    WorkerPool pool(jobs, [&context, jobs](int worker, WorkerChannel& channel) {
      processBatches(context, static_cast<std::size_t>(worker), static_cast<std::size_t>(jobs),
                     [&](std::size_t, const std::vector<ScenarioOutcome>& outcomes) {
                       channel.send(encodeOutcomes(outcomes));
                     });
    });
    for (std::size_t b = 0; b < context.batches; ++b) {
      consume(decodeOutcomes(pool.receive(static_cast<int>(b % static_cast<std::size_t>(jobs)))));
    }
    pool.finish();
  }
  progress.finish();
  summary_builder.finish();

  if (summary.ok == 0) {
    // A fault of the whole run: nothing is committed, an earlier run in the folder stays.
    const std::string reason =
        summary.failureExamples.empty() ? "unknown" : summary.failureExamples.begin()->second;
    throw SumoError(fmt::format("every concrete scenario failed ({} reasons; e.g. {})", summary.failureReasons.size(),
                                reason));
  }
  if (options.writeFiles) {
    summary.outputs = files->commit();
    files.reset();
    if (context.options.keepNets) {
      const auto published = publishBatchFiles(context, out);
      summary.outputs.insert(summary.outputs.end(), published.begin(), published.end());
    }
  }
  summary.seconds = secondsSince(start);
  summary.scenariosPerSecond = static_cast<double>(summary.samples) / std::max(summary.seconds, 1e-9);
  if (options.writeFiles) {
    writeManifest(context, summary, out, summary.outputs, started);
    summary.outputs.push_back(out / "manifest.json");
  }
  return summary;
}

std::string RunSummary::report() const {
  std::string text = fmt::format("{}: {} concrete scenarios (seed {}) in {:.2f} s = {:.0f} scenarios/s ({} job{}, batch {})\n",
                                 functionalScenario, samples, seed, seconds, scenariosPerSecond, jobs,
                                 jobs == 1 ? "" : "s", batch);
  text += fmt::format("  completed {}, failed {}", ok, failed);
  if (!collisionRule.empty()) text += fmt::format(", collisions ({}) {}", collisionRule, collisions);
  text += "\n";
  for (const auto& [kind, count] : failureReasons) {
    text += fmt::format("    {} x {}\n", count, count == 1 ? failureExamples.at(kind) : kind);
  }
  if (!metrics.empty()) {
    text += fmt::format("  {:<16} {:>10} {:>10} {:>10}  {}\n", "metric", "min", "mean", "max", "unit");
    for (const auto& metric : metrics) {
      text += fmt::format("  {:<16} {:>10.3f} {:>10.3f} {:>10.3f}  {}{}\n", metric.name, metric.min, metric.mean,
                          metric.max, metric.unit,
                          metric.infinite > 0 ? fmt::format("  (+{} x inf)", metric.infinite) : std::string());
    }
  }
  if (!outputs.empty()) {
    text += "  outputs:\n";
    for (const auto& path : outputs) text += fmt::format("    {}\n", path.string());
  }
  return text;
}

}  // namespace vsd::pipeline
