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
#include <iterator>
#include <optional>
#include <regex>
#include <set>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/outcome_files.hpp"
#include "vsd/pipeline/provenance.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/pipeline/worker_pool.hpp"
#include "vsd/road/network.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/activity.hpp"
#include "vsd/sim/batch_simulation.hpp"
#include "vsd/sim/trace_file.hpp"
#include "vsd/vector/dataset.hpp"
#include "outcome_codec.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

void RunOptions::validate() const {
  if (samples < 1 || samples > 100'000'000) {
    throw ConfigError::field("command line", "--samples", std::to_string(samples), "1 .. 100000000");
  }
  if (jobs < 1 || jobs > 256) throw ConfigError::field("command line", "--jobs", std::to_string(jobs), "1 .. 256");
  watchdog.validate();
  if (!(egoStepCost >= 0.0 && egoStepCost <= 10.0)) {
    throw ConfigError::field("command line", "--ego-step-cost-ms", fmt::format("{}", egoStepCost * 1000.0),
                             "0 .. 10000");
  }
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
  if (maxFailures > 100'000) {
    throw ConfigError::field("command line", "--max-failures", std::to_string(maxFailures), "0 (never stop early) .. 100000");
  }
  if (isolation == Isolation::None && jobs != 1) {
    throw ConfigError::field("command line", "--jobs", std::to_string(jobs),
                             "1 when the simulation runs in the calling process (isolation none)");
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
  road::NetWriter netWriter = road::NetWriter::Direct;
  std::optional<ShardInfo> shard;

  std::uint64_t firstIndexOf(std::size_t batch) const { return options.firstSample + batch * options.batch; }
  std::uint64_t endIndexOf(std::size_t batch) const {
    return std::min(options.firstSample + options.samples, firstIndexOf(batch) + options.batch);
  }
};

/// What the parent has learnt from workers that died or hung. Only the parent
/// changes it; a worker started afterwards is a fork and reads its copy to
/// resume where its predecessor stopped, without the scenario that brought it down.
struct RecoveryPlan {
  /// Scenarios failed by a fault of their controller or of libsumo: index -> reason.
  std::map<std::uint64_t, std::string> failed;
  /// Scenarios whose outcome the parent already holds (sent before a later fault).
  std::set<std::uint64_t> done;
  /// batch -> groups of scenarios simulated in separate libsumo sessions (absent: one group).
  /// A fault inside a shared simulation step splits its group, until it is isolated.
  std::map<std::size_t, std::vector<std::vector<std::uint64_t>>> groups;
  /// Batches whose network netconvert finished: a restarted worker reuses it.
  std::set<std::size_t> netReady;
  /// batch -> faults that could not be attributed (a retry, then the run stops).
  std::map<std::size_t, int> unattributed;
  /// Per worker: the batch the worker (re)starts with.
  std::vector<std::size_t> resumeAt;

  std::vector<std::vector<std::uint64_t>> groupsOf(const Context& context, std::size_t batch) const {
    const auto it = groups.find(batch);
    if (it != groups.end()) return it->second;
    std::vector<std::uint64_t> all;
    for (auto index = context.firstIndexOf(batch); index < context.endIndexOf(batch); ++index) all.push_back(index);
    return {all};
  }
};

struct PreparedBatch {
  std::size_t number = 0;
  fs::path stem;
  std::vector<scenario::ConcreteScenario> scenarios;
  std::vector<road::RoadGeometry> roads;
  std::vector<std::string> preFailure;  ///< per scenario: why it cannot be simulated (empty: fine)
  std::optional<road::PendingNetwork> pending;
  fs::path readyNet;  ///< a network a previous worker finished for this batch
  /// Per scenario: its lanes as SUMO loads them from the full-detail network, when the
  /// network is written directly (empty: the simulation asks SUMO).
  std::vector<std::vector<LaneGeometry>> lanes;
};

std::vector<std::string> netconvertOptions(const Context& context) { return context.logical->sumo.netconvertOptions; }

/// Outcomes of one group of a batch ('G'), or the batch's remaining outcomes
/// that needed no simulation ('B', the batch's last message).
enum class Part : char { Group = 'G', BatchEnd = 'B' };

ScenarioWithRoad concreteScenario(const std::shared_ptr<const scenario::LogicalScenario>& logical,
                                  const RunOptions& options, std::uint64_t index) {
  if (options.source) return options.source(index);
  auto concrete = scenario::sampleConcreteScenario(logical, options.seed, index);
  auto road = road::buildRoadGeometry(concrete);
  return {std::move(concrete), std::move(road)};
}

/// m, SUMO's sublane resolution for a scenario. vsd-sumo moves every road user itself and
/// takes the metrics from its own states, so SUMO's picture of lateral positions reaches an
/// output only through what SUMO reports itself: its FCD, or devices and outputs a user adds
/// with sumo_options. Only then, and only where road users move across lanes, SUMO runs its
/// sublane model, which costs it CPU (docs/benchmarks.md); a scenario that sets the
/// resolution itself keeps its own. (SUMO's collision checks do not fire between road users
/// placed with moveToXY, sublane model or not, so they do not need it either.)
double lateralResolutionFor(const scenario::LogicalScenario& logical, bool fcd) {
  constexpr double kSublane = 1.75;  // m: half a lane; finer costs SUMO more CPU
  const auto& options = logical.sumo.sumoOptions;
  const bool given = std::find(options.begin(), options.end(), "--lateral-resolution") != options.end();
  const bool sumo_reports_positions = fcd || !options.empty();
  return logical.hasLateralMotion() && sumo_reports_positions && !given ? kSublane : 0.0;
}

/// Prepares, converts and simulates batches; one per worker process.
class BatchProcessor {
 public:
  using Send = std::function<void(Part, std::vector<ScenarioOutcome>)>;

  BatchProcessor(const Context& context, const RecoveryPlan& plan)
      : context_(context), plan_(plan), registry_(sim::ControllerRegistry::withBuiltins()) {}

  PreparedBatch prepare(std::size_t number) {
    const auto t_start = std::chrono::steady_clock::now();
    PreparedBatch batch;
    batch.number = number;
    batch.stem = context_.workDir / fmt::format("batch_{:05}", number);
    road::NetworkBuilder builder;
    for (std::uint64_t index = context_.firstIndexOf(number); index < context_.endIndexOf(number); ++index) {
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
    const bool direct = !builder.empty() && context_.netWriter == road::NetWriter::Direct && builder.directlyWritable();
    batch.lanes.resize(batch.scenarios.size());
    if (direct) {
      for (std::size_t i = 0; i < batch.scenarios.size(); ++i) {
        batch.lanes[i] = builder.lanesAsLoaded(batch.scenarios[i].index);
      }
    }
    const fs::path ready = batch.stem.string() + ".net.xml";
    if (plan_.netReady.count(number) && fs::exists(ready)) {
      batch.readyNet = ready;
    } else if (!builder.empty()) {
      batch.pending = buildNetwork(builder, batch.stem, direct);
    }
    spdlog::debug("batch {}: sampled and wrote {} roads in {:.3f} s", number, batch.scenarios.size(),
                  secondsSince(t_start));
    return batch;
  }

  road::PendingNetwork buildNetwork(const road::NetworkBuilder& builder, const fs::path& stem, bool direct) const {
    if (direct) {
      if (context_.keepBatchFiles) builder.writePlainXml(stem);  // for netedit users
      return road::PendingNetwork::ready(builder.writeSumoNet(stem));
    }
    builder.writePlainXml(stem);
    return road::PendingNetwork::start(stem, netconvertOptions(context_));
  }

  /// Simulates the batch, sending each group's outcomes as it completes, then the rest.
  void finish(PreparedBatch& batch, const Send& send) {
    const auto t_start = std::chrono::steady_clock::now();
    std::vector<ScenarioOutcome> outcomes(batch.scenarios.size());
    for (std::size_t i = 0; i < batch.scenarios.size(); ++i) {
      outcomes[i].index = batch.scenarios[i].index;
      outcomes[i].inputs = batch.scenarios[i].inputs;
      outcomes[i].failure = batch.preFailure[i];
      outcomes[i].egoLane = batch.scenarios[i].ego.lane;
      const auto failed = plan_.failed.find(outcomes[i].index);
      if (failed != plan_.failed.end()) outcomes[i].failure = failed->second;
    }
    double wait_seconds = 0.0;
    std::vector<bool> sent(outcomes.size(), false);
    if (batch.pending || !batch.readyNet.empty()) {
      fs::path net = batch.readyNet;
      if (net.empty()) net = convertIsolatingFailures(batch, outcomes);
      else reportMarker(static_cast<std::int64_t>(batch.number));
      wait_seconds = secondsSince(t_start);
      simulateGroups(batch, net, outcomes, sent, send);
    }
    std::vector<ScenarioOutcome> rest;
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
      if (!sent[i] && !plan_.done.count(outcomes[i].index)) rest.push_back(withMetrics(std::move(outcomes[i])));
    }
    send(Part::BatchEnd, std::move(rest));
    if (!context_.keepBatchFiles) removeBatchFiles(batch.stem);
    spdlog::debug("batch {}: waited {:.3f} s for netconvert, simulated and computed metrics in {:.3f} s", batch.number,
                  wait_seconds, secondsSince(t_start) - wait_seconds);
  }

 private:
  ScenarioOutcome withMetrics(ScenarioOutcome outcome) const {
    if (!outcome.ok()) {
      outcome.metrics.assign(context_.metricSet->names().size(), std::numeric_limits<double>::quiet_NaN());
      return outcome;
    }
    outcome.metrics = metricsOf(outcome.trace, outcome.lanes, outcome.egoLane);
    return outcome;
  }

  std::vector<double> metricsOf(const Trace& trace, const std::vector<LaneGeometry>& lanes, int ego_lane) const {
    const auto lane = static_cast<std::size_t>(ego_lane);
    const Polyline lane_centre = lane < lanes.size() ? lanes[lane].centre : Polyline{};
    return context_.metricSet->evaluate({trace, lane_centre});
  }

  /// Converts the batch's network. If netconvert fails, each scenario is
  /// converted alone to find the culprits, which fail; if every scenario fails
  /// alone too, the fault is systemic and the run stops.
  fs::path convertIsolatingFailures(PreparedBatch& batch, std::vector<ScenarioOutcome>& outcomes) {
    const ActivityScope converting(Activity::Netconvert);
    faultPoint("netconvert.wait");
    try {
      fs::path net = batch.pending->wait();
      reportMarker(static_cast<std::int64_t>(batch.number));  // reusable by a restarted worker
      return net;
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

  /// Each group is one libsumo session; scenarios done or failed before are skipped.
  void simulateGroups(const PreparedBatch& batch, const fs::path& net, std::vector<ScenarioOutcome>& outcomes,
                      std::vector<bool>& sent, const Send& send) {
    std::map<std::uint64_t, std::size_t> position;
    for (std::size_t i = 0; i < batch.scenarios.size(); ++i) position[batch.scenarios[i].index] = i;
    const auto groups = plan_.groupsOf(context_, batch.number);
    for (std::size_t g = 0; g < groups.size(); ++g) {
      std::vector<std::size_t> members;
      for (const auto index : groups[g]) {
        const std::size_t i = position.at(index);
        if (outcomes[i].failure.empty() && !plan_.done.count(index)) members.push_back(i);
      }
      if (members.empty()) continue;
      reportUnit(static_cast<std::int64_t>(g));
      const fs::path fcd = groups.size() == 1 ? batch.stem.string() + ".fcd.xml"
                                              : batch.stem.string() + fmt::format(".group{}.fcd.xml", g);
      simulate(batch, net, members, fcd, outcomes);
      std::vector<ScenarioOutcome> part;
      for (const auto i : members) {
        part.push_back(withMetrics(std::move(outcomes[i])));
        sent[i] = true;
      }
      send(Part::Group, std::move(part));
    }
    reportUnit(-1);
  }

  void simulate(const PreparedBatch& batch, const fs::path& net, const std::vector<std::size_t>& members,
                const fs::path& fcd, std::vector<ScenarioOutcome>& outcomes) {
    std::vector<sim::ScenarioRun> runs;
    for (const auto i : members) {
      const auto index = batch.scenarios[i].index;
      runs.push_back({&batch.scenarios[i], &batch.roads[i], context_.layout.offsetFor(index), &batch.lanes[i]});
    }
    sim::BatchOptions options;
    options.step = context_.logical->step;
    options.steps = context_.logical->steps();
    options.collisionAction = context_.logical->sumo.collisionAction;
    options.sumoOptions = context_.logical->sumo.sumoOptions;
    options.scenarioDir = context_.logical->sourceFile.parent_path();
    options.egoStepCost = context_.options.egoStepCost;
    options.lateralResolution = lateralResolutionFor(*context_.logical, context_.options.fcd);
    if (context_.options.fcd) options.fcdOutput = fcd;
    auto results = sim::simulateBatch(net, runs, registry_, options);
    for (std::size_t r = 0; r < results.size(); ++r) {
      auto& outcome = outcomes[members[r]];
      outcome.failure = std::move(results[r].failure);
      outcome.trace = std::move(results[r].trace);
      outcome.lanes = std::move(results[r].lanes);
    }
    if (context_.options.reference.empty()) return;
    // The same scenarios with the reference driver as the Ego: only its metrics are kept.
    options.egoControllerOverride = context_.options.reference;
    options.fcdOutput.clear();
    const auto reference = sim::simulateBatch(net, runs, registry_, options);
    for (std::size_t r = 0; r < reference.size(); ++r) {
      auto& outcome = outcomes[members[r]];
      outcome.referenceFailure = reference[r].failure;
      outcome.referenceMetrics = reference[r].ok()
                                     ? metricsOf(reference[r].trace, reference[r].lanes, outcome.egoLane)
                                     : std::vector<double>(context_.metricSet->names().size(),
                                                           std::numeric_limits<double>::quiet_NaN());
    }
  }

  static void removeBatchFiles(const fs::path& stem) {
    std::error_code ignored;
    for (const char* suffix : {".nod.xml", ".edg.xml", ".net.xml", ".netconvert.log"}) {
      fs::remove(stem.string() + suffix, ignored);
    }
  }

  const Context& context_;
  const RecoveryPlan& plan_;
  sim::ControllerRegistry registry_;
};

/// Processes batches first, first + stride, ... with netconvert for the next
/// batch running while the current one is simulated.
void processBatches(const Context& context, const RecoveryPlan& plan, std::size_t first, std::size_t stride,
                    const BatchProcessor::Send& send) {
  BatchProcessor processor(context, plan);
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
    prepare_next();  // starts netconvert for the following batch before simulating this one
    PreparedBatch batch = std::move(ahead.front());
    ahead.pop_front();
    processor.finish(batch, send);
  }
}

/// Why a scenario failed, from the fault of the worker that simulated it.
std::string faultReason(const WorkerFault& fault) {
  const auto& activity = fault.activity;
  switch (activity.activity) {
    case Activity::Controller:
      return fmt::format("Ego controller {} at t = {:.1f} s", fault.what(), activity.time);
    case Activity::SumoVehicles:
      return fmt::format("libsumo {} handling the scenario's vehicles at t = {:.1f} s", fault.what(), activity.time);
    case Activity::SumoStep:
      return fmt::format("libsumo {} in a simulation step at t = {:.1f} s (isolated to this scenario)", fault.what(),
                         activity.time);
    case Activity::SumoLoad: return fmt::format("libsumo {} loading the network", fault.what());
    case Activity::Netconvert: return fmt::format("netconvert {}", fault.what());
    case Activity::Idle: break;
  }
  return fmt::format("worker process {}", fault.what());
}

/// Groups failure messages that differ only in numbers ("at t = 3.4 s").
std::string failureKind(const std::string& failure) {
  static const std::regex numbers("[-+]?[0-9]+(\\.[0-9]+)?");
  return std::regex_replace(failure, numbers, "#");
}

/// Fail fast (RunOptions::maxFailures): learns the fates of the run's first scenarios as
/// they become known (a worker lost in a scenario, or its outcome) and stops the run when
/// all of them failed the same way - a fault every scenario will meet.
class FailFast {
 public:
  explicit FailFast(const RunOptions& options)
      : first_(options.firstSample), count_(options.samples > options.maxFailures ? options.maxFailures : 0) {}

  /// Scenario `index` completed (`failure` empty) or failed; throws SumoError when the first
  /// scenarios all failed for one reason.
  void note(std::uint64_t index, const std::string& failure) {
    if (decided_ || index < first_ || index - first_ >= count_) return;
    if (failure.empty()) {
      decided_ = true;
      return;
    }
    failures_.emplace(index, failure);
    if (failures_.size() < count_) return;
    decided_ = true;
    const std::string kind = failureKind(failures_.begin()->second);
    for (const auto& [other, reason] : failures_) {
      if (failureKind(reason) != kind) return;
    }
    throw SumoError(fmt::format("the first {} concrete scenarios all failed the same way: {}; stopped early, nothing "
                                "written (--max-failures 0 runs every scenario)",
                                count_, failures_.begin()->second));
  }

 private:
  std::uint64_t first_;
  std::uint64_t count_;
  bool decided_ = false;
  std::map<std::uint64_t, std::string> failures_;
};

/// Receives the outcomes of each batch from its worker, in sample order, and
/// turns worker faults into failed scenarios: the worker is restarted where it
/// stopped, without the scenario (or group) that brought it down.
class BatchCollector {
 public:
  BatchCollector(const Context& context, RecoveryPlan& plan, WorkerPool& pool)
      : context_(context), plan_(plan), pool_(pool), failFast_(context.options) {}

  std::vector<ScenarioOutcome> collect(std::size_t batch) {
    const int worker = static_cast<int>(batch % static_cast<std::size_t>(pool_.size()));
    std::map<std::uint64_t, ScenarioOutcome> received;
    for (;;) {
      std::vector<char> message;
      try {
        message = pool_.receive(worker);
      } catch (const WorkerLost& lost) {
        recordLoss(batch, lost);
        for (const auto& [index, reason] : plan_.failed) failFast_.note(index, reason);
        plan_.resumeAt[static_cast<std::size_t>(worker)] = batch;
        pool_.restart(worker);
        continue;
      }
      const auto part = static_cast<Part>(message.back());
      message.pop_back();
      for (auto& outcome : decodeOutcomes(message)) {
        failFast_.note(outcome.index, outcome.failure);
        plan_.done.insert(outcome.index);
        received[outcome.index] = std::move(outcome);
      }
      if (part == Part::BatchEnd) break;
    }
    forget(batch);
    std::vector<ScenarioOutcome> outcomes;
    for (auto& [index, outcome] : received) outcomes.push_back(std::move(outcome));
    if (outcomes.size() != context_.endIndexOf(batch) - context_.firstIndexOf(batch)) {
      throw Error(fmt::format("internal: batch {} came back with {} of {} scenarios", batch, outcomes.size(),
                              context_.endIndexOf(batch) - context_.firstIndexOf(batch)));
    }
    return outcomes;
  }

 private:
  void recordLoss(std::size_t batch, const WorkerLost& lost) {
    const auto& fault = lost.fault();
    const auto& activity = fault.activity;
    spdlog::debug("batch {}: {}", batch, lost.what());
    if (activity.marker == static_cast<std::int64_t>(batch)) plan_.netReady.insert(batch);
    const bool per_scenario = activity.activity == Activity::Controller || activity.activity == Activity::SumoVehicles;
    if (per_scenario && activity.subject >= 0) {
      plan_.failed[static_cast<std::uint64_t>(activity.subject)] = faultReason(fault);
      return;
    }
    if (activity.activity == Activity::Netconvert) {
      failAll(batch, plan_.groupsOf(context_, batch), faultReason(fault));
      return;
    }
    if ((activity.activity == Activity::SumoStep || activity.activity == Activity::SumoLoad) && activity.unit >= 0) {
      isolate(batch, static_cast<std::size_t>(activity.unit), fault);
      return;
    }
    if (++plan_.unattributed[batch] > 1) {
      throw SumoError(fmt::format("{} twice while simulating batch {} (outside any controller or libsumo call)",
                                  lost.what(), batch));
    }
  }

  /// A fault of a whole libsumo session: a network that cannot load fails its
  /// group; a step splits the group in halves until one scenario is left.
  void isolate(std::size_t batch, std::size_t unit, const WorkerFault& fault) {
    auto groups = plan_.groupsOf(context_, batch);
    if (unit >= groups.size()) throw Error(fmt::format("internal: batch {} has no group {}", batch, unit));
    std::vector<std::uint64_t> pending;
    for (const auto index : groups[unit]) {
      if (!plan_.failed.count(index) && !plan_.done.count(index)) pending.push_back(index);
    }
    if (fault.activity.activity == Activity::SumoLoad || pending.size() <= 1) {
      failAll(batch, {pending}, faultReason(fault));
      return;
    }
    const auto half = pending.begin() + static_cast<std::ptrdiff_t>(pending.size() / 2);
    groups[unit] = std::vector<std::uint64_t>(pending.begin(), half);
    groups.insert(groups.begin() + static_cast<std::ptrdiff_t>(unit) + 1, std::vector<std::uint64_t>(half, pending.end()));
    plan_.groups[batch] = groups;
  }

  /// A completed batch needs no recovery state any more (it would grow with the run).
  void forget(std::size_t batch) {
    plan_.done.clear();  // only the batch being collected has entries
    plan_.failed.erase(plan_.failed.lower_bound(context_.firstIndexOf(batch)),
                       plan_.failed.lower_bound(context_.endIndexOf(batch)));
    plan_.groups.erase(batch);
    plan_.netReady.erase(batch);
    plan_.unattributed.erase(batch);
  }

  void failAll(std::size_t, const std::vector<std::vector<std::uint64_t>>& groups, const std::string& reason) {
    for (const auto& group : groups) {
      for (const auto index : group) {
        if (!plan_.done.count(index)) plan_.failed[index] = reason;
      }
    }
  }

  const Context& context_;
  RecoveryPlan& plan_;
  WorkerPool& pool_;
  FailFast failFast_;
};

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
    if (summary_.reference.empty()) return;
    if (outcome.referenceFailure.empty() && metricSet_.collision(outcome.referenceMetrics)) {
      ++summary_.referenceCollisions;
    }
    const auto collision = [&](const std::vector<double>& values) { return metricSet_.collision(values); };
    if (referenceAvoidsSutCollides(outcome, collision) == 1.0) ++summary_.referenceAvoidsSutCollides;
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

/// concrete.csv + traces.h5 + dataset.h5, staged in the output folder.
class RunFiles {
 public:
  RunFiles(const Context& context, const OutputFolder& folder, const std::vector<std::string>& metric_names)
      : folder_(folder), logical_(*context.logical), seed_(context.options.seed),
        reference_(!context.options.reference.empty()), metricSet_(*context.metricSet) {
    csvStream_.open(folder_.stage(kCsv), std::ios::binary | std::ios::trunc);
    if (!csvStream_) throw IoError((folder_.path() / kCsv).string() + ": cannot open for writing");
    csv_.emplace(csvStream_);
    std::vector<std::string> header = {"functional_scenario", "sample", "seed", "status", "failure"};
    for (const auto& input : logical_.inputs) header.push_back(input.name);
    header.insert(header.end(), metric_names.begin(), metric_names.end());
    // With --reference only: the reference driver's outcome beside the system's.
    if (reference_) {
      header.insert(header.end(), {"reference_status", "reference_failure"});
      for (const auto& name : metric_names) header.push_back("reference_" + name);
      header.emplace_back(kReferenceCriterion);
    }
    csv_->writeRow(header);
    outcomeFiles_.emplace(logical_, metric_names, context.options.compression, folder_.stage(kTraces),
                          folder_.stage(kDataset), folder_.path() / kTraces, folder_.path() / kDataset);
  }

  void write(const ScenarioOutcome& outcome) {
    std::vector<std::string> row = {logical_.name, std::to_string(outcome.index), std::to_string(seed_),
                                    outcome.ok() ? "ok" : "failed", outcome.failure};
    for (double value : outcome.inputs) row.push_back(formatNumber(value));
    for (double value : outcome.metrics) row.push_back(formatNumber(value));
    if (reference_) appendReference(outcome, row);
    csv_->writeRow(row);
    outcomeFiles_->write(outcome);
  }

  void appendReference(const ScenarioOutcome& outcome, std::vector<std::string>& row) const {
    const bool simulated = !outcome.referenceMetrics.empty();
    row.push_back(!simulated ? "" : outcome.referenceFailure.empty() ? "ok" : "failed");
    row.push_back(outcome.referenceFailure);
    for (std::size_t m = 0; m < metricSet_.names().size(); ++m) {
      row.push_back(simulated ? formatNumber(outcome.referenceMetrics[m]) : "");
    }
    const auto collision = [&](const std::vector<double>& values) { return metricSet_.collision(values); };
    row.push_back(formatNumber(referenceAvoidsSutCollides(outcome, collision)));
  }

  /// Completes and closes the three files (still staged).
  void close() {
    csvStream_.close();
    if (!csvStream_) throw IoError((folder_.path() / kCsv).string() + ": write failed (disk full?)");
    folder_.staged(kCsv);
    outcomeFiles_->close();
    outcomeFiles_.reset();
    folder_.staged(kTraces);
    folder_.staged(kDataset);
  }

 private:
  static constexpr const char* kCsv = "concrete.csv";
  static constexpr const char* kTraces = "traces.h5";
  static constexpr const char* kDataset = "dataset.h5";

  const OutputFolder& folder_;
  const scenario::LogicalScenario& logical_;
  std::uint64_t seed_;
  bool reference_;
  const metrics::MetricSet& metricSet_;
  std::ofstream csvStream_;
  std::optional<CsvWriter> csv_;
  std::optional<OutcomeFiles> outcomeFiles_;
};

/// The run's description; the output folder adds every file's hash and size and
/// writes it last. `first_sample` and `samples` say which concrete scenarios the
/// folder holds (a shard of a larger sweep, to be merged).
nlohmann::json runManifest(const Context& context, const RunSummary& summary, const std::string& started) {
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  provenance().addTo(manifest);
  manifest["command_line"] = context.options.commandLine;
  manifest["scenario_file"] = context.logical->sourceFile.string();
  manifest["scenario_sha256"] = sha256OfFile(context.logical->sourceFile);
  manifest["functional_scenario"] = context.logical->name;
  manifest["seed"] = context.options.seed;
  if (!context.options.reference.empty()) manifest["reference"] = context.options.reference;
  manifest["first_sample"] = context.options.firstSample;
  manifest["samples"] = context.options.samples;
  manifest["batch"] = context.options.batch;
  manifest["jobs"] = context.options.jobs;
  manifest["step_timeout"] = context.options.watchdog.stepTimeout;
  manifest["started"] = started;
  manifest["finished"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["ok"] = summary.ok;
  manifest["failed"] = summary.failed;
  manifest["collisions"] = summary.collisions;
  if (context.shard) manifest["shard"] = nlohmann::json::parse(context.shard->toJson());
  manifest["worker_restarts"] = summary.workerRestarts;
  if (context.options.isolation == RunOptions::Isolation::None) manifest["isolation"] = "none";
  manifest["inputs"] = summary.inputNames;
  manifest["metrics"] = summary.metricNames;
  return manifest;
}

/// Moves kept nets / FCD files from the work directory into the staged nets/ and fcd/.
void stageBatchFiles(const Context& context, const OutputFolder& folder) {
  for (std::size_t b = 0; b < context.batches; ++b) {
    const std::string stem = fmt::format("batch_{:05}", b);
    for (const char* suffix : {".nod.xml", ".edg.xml", ".net.xml"}) {
      const fs::path source = context.workDir / (stem + suffix);
      if (fs::exists(source)) fs::rename(source, folder.stage(fs::path("nets") / (stem + suffix)));
    }
    if (fs::exists(folder.stagingPath() / "nets" / (stem + ".net.xml"))) {
      folder.stageText(fs::path("nets") / (stem + ".sumocfg"),
                       fmt::format("<configuration>\n  <input>\n    <net-file value=\"{}.net.xml\"/>\n  </input>\n"
                                   "  <time>\n    <step-length value=\"{}\"/>\n  </time>\n</configuration>\n",
                                   stem, context.logical->step));
    }
  }
  if (!context.options.fcd) return;
  for (const auto& entry : fs::directory_iterator(context.workDir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("batch_", 0) == 0 && name.size() > 8 && name.compare(name.size() - 8, 8, ".fcd.xml") == 0) {
      fs::rename(entry.path(), folder.stage(fs::path("fcd") / name));
    }
  }
}

}  // namespace

void buildEgoControllers(const scenario::LogicalScenario& logical, const scenario::ConcreteScenario& concrete,
                         const std::string& reference) {
  auto registry = sim::ControllerRegistry::withBuiltins();
  const sim::ControllerNeeds needs = sim::controllerNeeds(logical);
  sim::makeController(registry, logical.ego.controller.name, logical.ego.controller.library,
                      logical.sourceFile.parent_path(),
                      sim::ControllerParams(concrete.controllerParams, logical.ego.controller.where), needs);
  if (!reference.empty()) {
    sim::makeController(registry, reference, {}, logical.sourceFile.parent_path(),
                        sim::ControllerParams({}, "--reference " + reference), needs);
  }
  // The controllers the Ego's controller actions hand it to (the Ego's actions come last).
  const std::size_t first = concrete.actions.size() - logical.ego.actions.size();
  for (std::size_t j = 0; j < logical.ego.actions.size(); ++j) {
    const auto& spec = logical.ego.actions[j];
    if (spec.kind != scenario::ActionSpec::Kind::Controller) continue;
    sim::makeController(registry, spec.controller.name, spec.controller.library, logical.sourceFile.parent_path(),
                        sim::ControllerParams(concrete.actions[first + j].controllerParams, spec.controller.where),
                        sim::controllerNeeds(logical, spec));
  }
}

namespace {

/// Fails fast on problems every scenario would hit (unknown controller, bad
/// parameters, a plugin that cannot be loaded) before any output is created.
/// The probe runs the controller's code, so it runs in a worker: a probe that
/// crashes or hangs proves nothing about the run (its scenario will record it).
void probeController(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options) {
  auto make_controller = [&] {
    buildEgoControllers(*logical, concreteScenario(logical, options, options.firstSample).concrete, options.reference);
  };
  if (options.isolation == RunOptions::Isolation::None) {
    make_controller();
    return;
  }
  WorkerPool probe(1, [&](int, WorkerChannel&) { make_controller(); }, options.watchdog);
  try {
    probe.finish();
  } catch (const WorkerLost& lost) {
    spdlog::debug("controller probe: {}", lost.what());
  }
}

road::NetWriter chooseNetWriter(const scenario::LogicalScenario& logical, const RunOptions& options) {
  const bool needs_netconvert = !logical.sumo.netconvertOptions.empty();
  if (!options.netWriter) return needs_netconvert ? road::NetWriter::Netconvert : road::NetWriter::Direct;
  if (*options.netWriter == road::NetWriter::Direct && needs_netconvert) {
    throw ConfigError(fmt::format("{}: sumo.netconvert_options need netconvert: use --net-writer netconvert "
                                  "(or leave --net-writer unset)",
                                  logical.sourceFile.string()));
  }
  return *options.netWriter;
}

}  // namespace

fs::path defaultRunFolder(const scenario::LogicalScenario& logical) { return fs::path("out") / logical.name; }

RunSummary runScenarios(const RunOptions& options, const OutcomeCallback& on_outcome) {
  return runScenarios(scenario::loadLogicalScenario(options.scenarioFile), options, on_outcome);
}

namespace {

RunSummary runRange(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                    const std::optional<ShardInfo>& shard, const OutcomeCallback& on_outcome);

fs::path outputFolder(const scenario::LogicalScenario& logical, const RunOptions& options) {
  return options.outputDir.empty() ? defaultRunFolder(logical) : options.outputDir;
}

/// True if `folder` holds a finished shard of the same sweep whose files are all there.
bool finishedShard(const ShardInfo& wanted) {
  if (!fs::exists(wanted.folder / "manifest.json")) return false;
  const ShardInfo found = readShardManifest(wanted.folder);
  if (!found.sameSweep(wanted) || found.id.index != wanted.id.index || found.firstSample != wanted.firstSample ||
      found.samples != wanted.samples) {
    throw ConfigError(fmt::format("{}: holds {} of another sweep (scenario {}, seed {}, samples {}+{}): remove it or "
                                  "choose another --out",
                                  wanted.folder.string(), found.id.label(), found.functionalScenario, found.seed,
                                  found.sweepFirstSample, found.sweepSamples));
  }
  const auto manifest = nlohmann::json::parse(readTextFile(wanted.folder / "manifest.json"));
  for (const auto& [file, entry] : manifest.at("outputs").items()) {
    std::error_code ec;
    const auto bytes = fs::file_size(wanted.folder / file, ec);
    if (ec || bytes != entry.at("bytes").get<std::uintmax_t>()) return false;
  }
  return true;
}

RunSummary runShard(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                    const OutcomeCallback& on_outcome) {
  const ShardId id = *options.shard;
  const auto range = shardRange(options.firstSample, options.samples, options.batch, id);
  ShardInfo info;
  info.id = id;
  info.folder = shardsFolder(outputFolder(*logical, options)) / id.folderName();
  info.firstSample = range.first;
  info.samples = range.samples;
  info.sweepFirstSample = options.firstSample;
  info.sweepSamples = options.samples;
  info.seed = options.seed;
  info.functionalScenario = logical->name;
  info.scenarioSha256 = sha256OfFile(logical->sourceFile);
  info.batch = options.batch;
  info.compression = options.compression;
  if (options.writeFiles && finishedShard(info)) {
    spdlog::info("{} ({}) is finished already: skipped", id.label(), info.folder.string());
    RunSummary summary = readRunManifest(info.folder);
    summary.resumed = true;
    return summary;
  }
  RunOptions part = options;
  part.firstSample = range.first;
  part.samples = range.samples;
  part.outputDir = info.folder;
  part.shard.reset();
  RunSummary summary = runRange(logical, part, info, on_outcome);
  summary.shard = id;
  return summary;
}

using ConsumeBatch = std::function<void(const std::vector<ScenarioOutcome>&)>;

/// RunOptions::Isolation::None: what simulateAll's only worker does with --jobs 1,
/// here in the calling process; each batch's outcomes go to `consume` in sample
/// order when its last part is ready. Nothing to recover: a fault ends the caller.
void simulateInProcess(const Context& context, const ConsumeBatch& consume) {
  const RecoveryPlan nothing_failed;
  FailFast fail_fast(context.options);
  std::vector<ScenarioOutcome> batch;
  processBatches(context, nothing_failed, 0, 1, [&](Part part, std::vector<ScenarioOutcome> outcomes) {
    for (const auto& outcome : outcomes) fail_fast.note(outcome.index, outcome.failure);
    std::move(outcomes.begin(), outcomes.end(), std::back_inserter(batch));
    if (part != Part::BatchEnd) return;
    std::sort(batch.begin(), batch.end(), [](const auto& a, const auto& b) { return a.index < b.index; });
    consume(batch);
    batch.clear();
  });
}

/// Runs every batch in worker processes and hands the outcomes, in sample order, to
/// `consume`. Returns the number of workers restarted after a fault.
int simulateAll(const Context& context, const ConsumeBatch& consume) {
  if (context.options.isolation == RunOptions::Isolation::None) {
    simulateInProcess(context, consume);
    return 0;
  }
  const int jobs = context.options.jobs;
  RecoveryPlan plan;
  for (int w = 0; w < jobs; ++w) plan.resumeAt.push_back(static_cast<std::size_t>(w));
  WorkerPool pool(
      jobs,
      [&context, &plan, jobs](int worker, WorkerChannel& channel) {
        processBatches(context, plan, plan.resumeAt[static_cast<std::size_t>(worker)], static_cast<std::size_t>(jobs),
                       [&](Part part, const std::vector<ScenarioOutcome>& outcomes) {
                         auto message = encodeOutcomes(outcomes);
                         message.push_back(static_cast<char>(part));
                         channel.send(message);
                       });
      },
      context.options.watchdog);
  BatchCollector collector(context, plan, pool);
  for (std::size_t b = 0; b < context.batches; ++b) consume(collector.collect(b));
  pool.finish();
  return pool.restarts();
}

}  // namespace

RunSummary runScenarios(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                        const OutcomeCallback& on_outcome) {
  options.validate();
  if (options.shard) return runShard(logical, options, on_outcome);
  return runRange(logical, options, std::nullopt, on_outcome);
}

RunSummary readRunManifest(const fs::path& run_folder) {
  const fs::path path = run_folder / "manifest.json";
  RunSummary summary;
  try {
    const auto manifest = nlohmann::json::parse(readTextFile(path));
    const std::string command = manifest.value("command", std::string("run"));
    if (command != "run" && command != "merge") {  // e.g. a search folder: say what it is, not a missing key
      throw DatasetError(fmt::format("{}: a folder of `vsd-sumo {}`, not a run folder (expected the --out of "
                                     "`vsd-sumo run`)",
                                     run_folder.string(), command));
    }
    summary.functionalScenario = manifest.at("functional_scenario").get<std::string>();
    summary.outputDir = run_folder;
    summary.samples = manifest.at("samples").get<std::uint64_t>();
    summary.firstSample = manifest.at("first_sample").get<std::uint64_t>();
    summary.seed = manifest.at("seed").get<std::uint64_t>();
    summary.ok = manifest.at("ok").get<std::uint64_t>();
    summary.failed = manifest.at("failed").get<std::uint64_t>();
    summary.collisions = manifest.at("collisions").get<std::uint64_t>();
    summary.seconds = manifest.at("seconds").get<double>();
    summary.jobs = manifest.at("jobs").get<int>();
    summary.batch = manifest.at("batch").get<std::size_t>();
    summary.inputNames = manifest.at("inputs").get<std::vector<std::string>>();
    summary.metricNames = manifest.at("metrics").get<std::vector<std::string>>();
    if (manifest.contains("shard")) summary.shard = readShardManifest(run_folder).id;
    for (const auto& [file, entry] : manifest.at("outputs").items()) summary.outputs.push_back(run_folder / file);
  } catch (const nlohmann::json::exception& error) {
    throw DatasetError(fmt::format("{}: not a run manifest ({})", path.string(), error.what()));
  }
  summary.scenariosPerSecond = static_cast<double>(summary.samples) / std::max(summary.seconds, 1e-9);
  return summary;
}

namespace {

/// The run as its workers see it: --fcd implies --keep-nets, jobs capped by the batches, the
/// metric set (--reference needs a collision rule), the batch layout and the network writer.
Context makeContext(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                    const std::optional<ShardInfo>& shard) {
  Context context;
  context.logical = logical;
  context.options = options;
  context.shard = shard;
  if (context.options.fcd) context.options.keepNets = true;
  context.options.jobs = static_cast<int>(std::min<std::uint64_t>(
      static_cast<std::uint64_t>(options.jobs), (options.samples + options.batch - 1) / options.batch));
  context.metricSet = std::make_unique<metrics::MetricSet>(
      logical->metrics, scenarioAvailability(*logical),
      logical->sourceFile.string() + ": metrics");
  if (!options.reference.empty() && context.metricSet->collisionRule().empty()) {
    throw ConfigError::field("command line", "--reference", options.reference,
                             fmt::format("a scenario whose metrics tell a collision ({}: metrics lists none with a "
                                         "collision rule, such as d_min)",
                                         logical->sourceFile.string()));
  }
  context.batches = static_cast<std::size_t>((options.samples + options.batch - 1) / options.batch);
  context.keepBatchFiles = context.options.keepNets;
  context.layout = road::BatchLayout(road::BatchLayout::cellSizeFor(logical->road));
  context.netWriter = chooseNetWriter(*logical, options);
  return context;
}

/// The summary before any scenario ran: what the run was asked for.
RunSummary plannedSummary(const Context& context, const fs::path& out) {
  const RunOptions& options = context.options;
  RunSummary summary;
  summary.functionalScenario = context.logical->name;
  summary.outputDir = out;
  summary.samples = options.samples;
  summary.seed = options.seed;
  summary.reference = options.reference;
  summary.firstSample = options.firstSample;
  summary.jobs = options.jobs;
  summary.batch = options.batch;
  summary.inputNames = context.logical->inputNames();
  return summary;
}

RunSummary runRange(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                    const std::optional<ShardInfo>& shard, const OutcomeCallback& on_outcome) {
  const auto start = std::chrono::steady_clock::now();
  const std::string started = utcTimestamp();
  Context context = makeContext(logical, options, shard);
  probeController(logical, options);

  const fs::path out = outputFolder(*logical, options);
  std::optional<OutputFolder> folder;
  std::optional<TemporaryDirectory> temporary_work;
  if (options.writeFiles) {
    checkOutput({out, &output_kinds::runFolder(), logical->name, options.force, "--out", "--force",
                 {{"scenario", logical->sourceFile}}});
    folder.emplace(out);
  }
  if (context.options.keepNets && folder) {
    context.workDir = folder->stagingPath() / ".work";  // scratch inside the staging folder, not an output
    ensureDirectory(context.workDir);
  } else {
    temporary_work.emplace("vsd-run");
    context.workDir = temporary_work->path();
  }

  RunSummary summary = plannedSummary(context, out);
  SummaryBuilder summary_builder(summary, *context.metricSet);

  std::optional<RunFiles> files;
  if (folder) files.emplace(context, *folder, context.metricSet->names());

  Progress progress(fmt::format("run {}", logical->name), options.samples, "scenarios");
  summary.workerRestarts = simulateAll(context, [&](const std::vector<ScenarioOutcome>& outcomes) {
    for (const auto& outcome : outcomes) {
      summary_builder.add(outcome);
      if (files) files->write(outcome);
      if (on_outcome) on_outcome(outcome);
    }
    progress.advance(outcomes.size());
    faultPoint("run.write");
    throwIfInterrupted();
  });
  progress.finish();
  summary_builder.finish();
  summary.seconds = secondsSince(start);
  summary.scenariosPerSecond = static_cast<double>(summary.samples) / std::max(summary.seconds, 1e-9);

  if (summary.ok == 0) {
    const std::string reason =
        summary.failureExamples.empty() ? "unknown" : summary.failureExamples.begin()->second;
    throw SumoError(fmt::format("every concrete scenario failed (e.g. {}); nothing was written to {}", reason,
                                options.writeFiles ? out.string() : std::string("the outcomes")));
  }
  if (folder) {
    files->close();
    files.reset();
    if (context.options.keepNets) stageBatchFiles(context, *folder);
    if (temporary_work) temporary_work.reset();
    std::error_code ignored;
    fs::remove_all(folder->stagingPath() / ".work", ignored);
    summary.outputs = folder->commit(runManifest(context, summary, started));
  }
  return summary;
}

}  // namespace

double referenceAvoidsSutCollides(const ScenarioOutcome& outcome,
                                  const std::function<bool(const std::vector<double>&)>& collision) {
  if (!outcome.ok() || outcome.referenceMetrics.empty() || !outcome.referenceFailure.empty()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return collision(outcome.metrics) && !collision(outcome.referenceMetrics) ? 1.0 : 0.0;
}

std::string RunSummary::report() const {
  std::string text;
  if (shard) {
    text += fmt::format("{} of the sweep: samples {} .. {}{}\n", shard->label(), firstSample, firstSample + samples - 1,
                        resumed ? fmt::format(" — finished already in {}, not run again", outputDir.string()) : "");
  }
  text += fmt::format("{}: {} concrete scenarios (seed {}) in {:.2f} s = {:.0f} scenarios/s ({} job{}, batch {})\n",
                                 functionalScenario, samples, seed, seconds, scenariosPerSecond, jobs,
                                 jobs == 1 ? "" : "s", batch);
  text += fmt::format("  completed {}, failed {}", ok, failed);
  if (!collisionRule.empty()) text += fmt::format(", collisions ({}) {}", collisionRule, collisions);
  text += "\n";
  if (!reference.empty()) {
    text += fmt::format("  reference driver {}: collisions {}; {} (the system collides where it does not) {}\n",
                        reference, referenceCollisions, kReferenceCriterion, referenceAvoidsSutCollides);
  }
  for (const auto& [kind, count] : failureReasons) {
    text += fmt::format("    {} x {}\n", count, count == 1 ? failureExamples.at(kind) : kind);
  }
  if (workerRestarts > 0) {
    text += fmt::format("  worker processes restarted after a crash, exit or hang: {}\n", workerRestarts);
  }
  if (!metrics.empty()) {
    text += fmt::format("  {:<16} {:>10} {:>10} {:>10}  {}\n", "metric", "min", "mean", "max", "unit");
    // A metric with no finite value (e.g. a clearance to a road user that never came alongside)
    // has no min, mean or max: '-', not NaN.
    const auto cell = [](double value) {
      return std::isnan(value) ? fmt::format("{:>10}", "-") : fmt::format("{:>10.3f}", value);
    };
    for (const auto& metric : metrics) {
      text += fmt::format("  {:<16} {} {} {}  {}{}\n", metric.name, cell(metric.min), cell(metric.mean),
                          cell(metric.max), metric.unit,
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
