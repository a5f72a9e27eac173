#pragma once
// `vsd-sumo run`: sample concrete scenarios from a logical scenario, build the
// SUMO networks (many scenarios per net), co-simulate with libsumo, compute
// metrics and write the run's outputs:
//
//   <out>/concrete.csv   one row per concrete scenario (inputs, metrics, status)
//   <out>/traces.h5      full traces of every vehicle (schema vsd-traces/1)
//   <out>/manifest.json  tool and SUMO versions, scenario hash, seed, command line, output hashes
//   <out>/nets/, <out>/fcd/   with --keep-nets / --fcd
//
// Results are identical for the same seed whatever --jobs and --batch are.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/scenario/logical_scenario.hpp"
#include "vsd/sim/sumo_session.hpp"

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
  bool ok() const { return failure.empty(); }
};

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
  std::vector<std::filesystem::path> outputs;

  /// Multi-line human-readable report (what the CLI prints).
  std::string report() const;
};

/// Called for every scenario, in sample order, in the calling process.
using OutcomeCallback = std::function<void(const ScenarioOutcome&)>;

/// Runs the logical scenario. Throws ConfigError / SumoError / IoError for
/// faults of the whole run (nothing is left behind that looks complete);
/// per-scenario faults are recorded in the outcomes and concrete.csv.
RunSummary runScenarios(const RunOptions& options, const OutcomeCallback& on_outcome = {});

/// Same, with an already loaded logical scenario.
RunSummary runScenarios(const std::shared_ptr<const scenario::LogicalScenario>& logical, const RunOptions& options,
                        const OutcomeCallback& on_outcome = {});

}  // namespace vsd::pipeline
