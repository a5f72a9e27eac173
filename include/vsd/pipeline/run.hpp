#pragma once
// `vsd-sumo run`: sample concrete scenarios from a logical scenario, build the
// SUMO networks (many scenarios per net), co-simulate with libsumo, compute
// metrics and write the run's outputs:
//
//   <out>/concrete.csv   one row per concrete scenario (inputs, metrics, status)
//   <out>/traces.h5      full traces of every vehicle (schema vsd-traces/1)
//   <out>/dataset.h5     the vectorized scene of every completed run
//   <out>/manifest.json  tool and SUMO versions, scenario hash, seed, command line, output hashes
//   <out>/nets/, <out>/fcd/   with --keep-nets / --fcd
//
// The folder changes as a whole (vsd/core/files.hpp: OutputFolder). Netconvert,
// libsumo and the Ego controllers run in worker processes (--jobs of them, at
// least one) under a watchdog; a crash, exit() or hang there fails the scenario
// it happened in and the run goes on (see worker_pool.hpp).
//
// Results are identical for the same seed whatever --jobs and --batch are.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/run_folder/shards.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/road/network.hpp"
#include "vsd/pipeline/worker_pool.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::pipeline {

/// A concrete scenario with the road it is simulated on.
struct ScenarioWithRoad {
  scenario::ConcreteScenario concrete;
  road::RoadGeometry road;
};
/// Supplies concrete scenario `index` (its `index` field must equal the argument).
using ScenarioSource = std::function<ScenarioWithRoad(std::uint64_t index)>;

struct RunOptions {
  static constexpr std::size_t kDefaultBatch = 250;
  /// Largest sample index (first sample + samples); 2^50 keeps indices exact in double.
  static constexpr std::uint64_t kMaxSampleIndex = std::uint64_t{1} << 50;

  std::filesystem::path scenarioFile;
  std::filesystem::path outputDir;  ///< empty: out/<functional scenario>
  std::uint64_t samples = 1000;     ///< 1 .. 100000000
  std::uint64_t seed = 1;           ///< any value
  std::uint64_t firstSample = 0;    ///< index of the first concrete scenario (runs can be split), .. kMaxSampleIndex
  int jobs = 1;                     ///< worker processes (libsumo: one simulation per process), 1 .. 256
  std::size_t batch = kDefaultBatch;  ///< concrete scenarios per SUMO network and simulation, 1 .. 4096
  bool keepNets = false;            ///< keep <out>/nets/batch_*.{nod,edg,net}.xml + .sumocfg
  bool fcd = false;                 ///< write <out>/fcd/batch_*.fcd.xml (implies keepNets)
  bool writeFiles = true;           ///< false: only call the outcome callback (used by compare)
  int compression = 1;              ///< deflate level of dataset.h5's vectors (0 = none .. 9)
  /// How batch networks are built; unset: written directly, unless the scenario gives
  /// netconvert options (sumo.netconvert_options), which need netconvert.
  std::optional<road::NetWriter> netWriter;
  /// Run only shard K of N of the sweep [firstSample, firstSample + samples) into
  /// <out>/shards/shard-K-of-N/ (see vsd/run_folder/shards.hpp). A shard that is finished
  /// already (same sweep) is not run again: re-running a sweep resumes it.
  std::optional<ShardId> shard;
  WatchdogOptions watchdog;         ///< per-step time limit of controllers and libsumo (--step-timeout)
  /// Fail fast: when each of the first `maxFailures` concrete scenarios of the run fails for
  /// the same reason (numbers aside), the run stops with that reason (SumoError) instead of
  /// meeting it in every scenario (e.g. an Ego plugin that hangs costs --step-timeout each).
  /// 0: never stop early. 0 .. 100000.
  std::uint64_t maxFailures = 8;
  /// Replace a run folder of another functional scenario (docs/output-policy.md).
  bool force = false;
  /// s of extra wall time per Ego step (--ego-step-cost-ms; 0: none): a slow Ego stack's
  /// cost, for benchmarks. It counts against the watchdog's per-step limit.
  double egoStepCost = 0.0;
  /// Where the Ego controllers and libsumo run. Process (the default, and the only
  /// choice `vsd-sumo run` offers): forked worker processes under the watchdog (see
  /// worker_pool.hpp). None: the calling process itself, the same batches in the same
  /// order through the same code, without fork, pipe or watchdog — a plugin's crash,
  /// exit() or hang takes the caller with it. Only with jobs = 1. It exists so that
  /// `vsd-sumo bench isolation` can measure what the worker processes cost.
  enum class Isolation { Process, None };
  Isolation isolation = Isolation::Process;
  /// `--reference NAME`: every concrete scenario runs a second time with this built-in
  /// controller (its default parameters) as the Ego, e.g. UN R157's reference driver; both
  /// outcomes go side by side into concrete.csv (README "--reference"). Empty: none.
  std::string reference;
  std::string commandLine;          ///< recorded in the manifest
  /// Empty: scenarios are sampled from the logical scenario (seed, index) and their roads
  /// generated. Set for scenarios read from elsewhere (`vsd-sumo run FILE.xosc`).
  ScenarioSource source;

  /// Throws ConfigError naming the flag and the accepted range.
  void validate() const;
};

/// Everything the run knows about one concrete scenario.
struct ScenarioOutcome {
  std::uint64_t index = 0;
  std::vector<double> inputs;    ///< in the logical scenario's input order
  std::vector<double> metrics;   ///< in RunSummary::metricNames order; NaN when failed
  std::string failure;           ///< empty when the run completed
  Trace trace;
  std::vector<LaneGeometry> lanes;  ///< the road's lanes as SUMO built them (scenario frame)
  int egoLane = 0;
  /// With --reference: the same scenario with the reference driver as the Ego.
  std::vector<double> referenceMetrics;  ///< RunSummary::metricNames order; NaN when it failed
  std::string referenceFailure;          ///< empty when the reference run completed
  bool ok() const { return failure.empty(); }
};

/// Passes `outcomes` through the encoding a worker process sends its results to the parent
/// with, and decodes them as the parent does; returns the message's size in bytes. Throws
/// Error if outcomes are lost. What the pipe costs beyond the simulation (`bench isolation`).
std::size_t passThroughWorkerPipe(const std::vector<ScenarioOutcome>& outcomes);

/// The regulation's pass criterion as a value of a scenario run with --reference
/// (UN R157 5.2.5.2: the system avoids a collision wherever the reference driver does):
/// 1 if the reference driver avoided a collision the system under test had, 0 if not,
/// NaN if either run failed. `collision` tells a run's metrics collide (MetricSet::collision).
inline constexpr const char* kReferenceCriterion = "reference_avoids_sut_collides";
double referenceAvoidsSutCollides(const ScenarioOutcome& outcome,
                                  const std::function<bool(const std::vector<double>&)>& collision);

struct MetricSummary {
  std::string name;
  std::string unit;
  std::size_t finite = 0;     ///< scenarios with a finite value
  std::size_t infinite = 0;   ///< e.g. ttc_min when the Ego never closes in
  double min = 0.0;
  double mean = 0.0;
  double max = 0.0;
};

struct RunSummary {
  std::string functionalScenario;
  std::filesystem::path outputDir;
  std::uint64_t samples = 0;
  std::uint64_t seed = 0;
  std::uint64_t ok = 0;
  std::uint64_t failed = 0;
  std::uint64_t collisions = 0;  ///< completed runs that meet the metrics' collision rule
  std::string reference;         ///< --reference controller; empty: none
  std::uint64_t referenceCollisions = 0;      ///< completed reference runs that collide
  std::uint64_t referenceAvoidsSutCollides = 0;  ///< scenarios where kReferenceCriterion is 1
  std::string collisionRule;     ///< e.g. "d_min <= 0"; empty when no metric of the run defines one
  std::map<std::string, std::uint64_t> failureReasons;  ///< reason (numbers replaced by #) -> count
  std::map<std::string, std::string> failureExamples;   ///< reason (numbers replaced by #) -> first message
  std::vector<std::string> inputNames;
  std::vector<std::string> metricNames;
  std::vector<MetricSummary> metrics;
  double seconds = 0.0;
  double scenariosPerSecond = 0.0;
  int jobs = 1;
  std::size_t batch = 0;
  int workerRestarts = 0;  ///< worker processes started again after a crash, exit or hang
  std::vector<std::filesystem::path> outputs;
  std::optional<ShardId> shard;  ///< set for a shard of a sweep
  std::uint64_t firstSample = 0;
  bool resumed = false;          ///< the shard was finished already: nothing was run

  /// Multi-line human-readable report (what the CLI prints).
  std::string report() const;
};

/// Called for every scenario, in sample order, in the calling process.
using OutcomeCallback = std::function<void(const ScenarioOutcome&)>;

/// Runs the logical scenario. Throws ConfigError / SumoError / IoError for
/// faults of the whole run — including "every concrete scenario failed" —
/// and InterruptedError on SIGINT/SIGTERM; then the output folder keeps its
/// earlier contents. Per-scenario faults (also crashes, exit() and hangs of the
/// controller or libsumo) are recorded in the outcomes and concrete.csv.
RunSummary runScenarios(const RunOptions& options, const OutcomeCallback& on_outcome = {});

/// Builds the controllers the Ego of `concrete` uses: its own, those its controller actions
/// hand it to, and `reference` (a controller name; empty: none). Throws ConfigError for an
/// unknown name, bad parameters or a plugin that cannot be loaded. It runs their code in this
/// process: `run` does so in a worker, `scenario check` for built-in controllers only.
void buildEgoControllers(const scenario::LogicalScenario& logical, const scenario::ConcreteScenario& concrete,
                         const std::string& reference = {});

/// Where a run of `logical` writes without --out: out/<functional scenario>.
std::filesystem::path defaultRunFolder(const scenario::LogicalScenario& logical);

/// Reads what a finished run's manifest.json says (counts, sample range, seed, shard);
/// metric statistics are not in it. Throws DatasetError naming the file.
RunSummary readRunManifest(const std::filesystem::path& run_folder);

/// Same, with an already loaded logical scenario.
RunSummary runScenarios(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                        const OutcomeCallback& on_outcome = {});

}  // namespace vsd::pipeline
