#pragma once
// `vsd-sumo export`: vectorized scenes from an arbitrary SUMO map with its own
// demand. SUMO drives the traffic; chosen vehicles are Egos. For every Ego and
// every window start t0 (every `stride` s while it drives), a scene holds
//   - every lane within `radius` of the Ego at t0 (left and right boundary,
//     split into vectors of at most `max_vector_length`, junction-internal
//     lanes included),
//   - every other vehicle that is within the radius at some instant of
//     [t0 - history, t0 + horizon], one vector per step; instants where it is
//     absent or outside the radius are masked (vector_valid = 0),
//   - the Ego's history and initial vector; its future is the target.
// Windows in which the Ego leaves the network are not complete and are counted
// as skipped. With --closed-loop every Ego is driven by an Ego controller (the
// plugin API of `run`) from its first step on.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/core/defaults.hpp"
#include "vsd/pipeline/worker_pool.hpp"
#include "vsd/sim/map_simulation.hpp"

namespace vsd::pipeline {

/// Which vehicles are Egos: all | random:K | vtype:NAME | id,id,...
struct EgoSelection {
  enum class Kind { All, Random, VehicleType, Ids };
  Kind kind = Kind::All;
  std::size_t count = 0;         ///< Random
  std::string vehicleType;       ///< VehicleType
  std::vector<std::string> ids;  ///< Ids
  /// Throws ConfigError naming --egos, the value and the accepted forms.
  static EgoSelection parse(const std::string& text);
};

struct ExportOptions {
  // Bounds of the numeric options (validate() names the violated one).
  // --step, --horizon and --history: kMinStep, kMaxStep, kMaxWindowSteps (core/trace.hpp).
  static constexpr double kMaxStride = 3600.0;           ///< s
  static constexpr double kMaxLaneChangeDuration = 60.0; ///< s
  static constexpr double kMaxRadius = 1000.0;           ///< m
  static constexpr double kMinVectorLength = 0.1;        ///< m
  static constexpr double kMaxVectorLength = 1000.0;     ///< m
  static constexpr double kMaxSimulationTime = 1e7;      ///< s (--begin, --end; about 116 days)

  sim::MapSource source;                 ///< a .sumocfg, or --net + --routes
  std::filesystem::path openDrive;       ///< alternatively an OpenDRIVE map (+ source.routes), imported by netconvert
  std::filesystem::path output;          ///< dataset file (.h5)
  std::string egos = "all";
  std::uint64_t seed = 1;                ///< Ego selection and SUMO's --seed
  double step = kDefaultStep;            ///< s, kMinStep .. kMaxStep
  double horizon = kDefaultHorizon;      ///< s of Ego future (target), a multiple of step, <= kMaxWindowSteps steps
  double history = 0.0;                  ///< s of past before t0 in the polylines, as horizon (0 allowed)
  double stride = 1.0;                   ///< s between window starts of one Ego, step .. kMaxStride
  double radius = 60.0;                  ///< m around the Ego at t0, (0, kMaxRadius]
  double maxVectorLength = 5.0;          ///< m, lane boundary vectors, kMinVectorLength .. kMaxVectorLength
  std::optional<double> begin;           ///< s of simulation time (default: the map's)
  std::optional<double> end;
  std::string label;                     ///< default: the map file's stem
  std::uint64_t maxSamples = 0;          ///< stop after this many (0: no limit)
  double laneChangeDuration = 2.0;       ///< s, SUMO lane changes (0: the map's own, e.g. sublane)
  int compression = 1;                   ///< deflate level of the dataset's vectors (0 = none)
  bool closedLoop = false;
  std::string controller = "paper_ego";
  std::filesystem::path controllerLibrary;
  std::vector<std::pair<std::string, double>> controllerParams;
  WatchdogOptions watchdog;              ///< per-step time limit of controllers and libsumo (--step-timeout)
  /// Road users placed at the start besides the map's demand (an imported network scenario's;
  /// sim::MapSimulationOptions::placed), network frame.
  std::vector<sim::PlacedRoadUser> placed;
  /// The file the dataset's provenance and messages name (an imported scenario); empty: the map's.
  std::filesystem::path sourceFile;

  /// Throws ConfigError naming the flag, the value and the constraint.
  void validate() const;
};

struct ExportSummary {
  std::filesystem::path output;
  std::string label;
  std::uint64_t samples = 0;
  std::uint64_t egos = 0;            ///< Egos with at least one sample
  std::uint64_t windowsSkipped = 0;  ///< windows the Ego left (or parked in) before their end
  std::uint64_t parkedSteps = 0;     ///< vehicle steps spent parked (masked: off the lane)
  std::uint64_t maskedJumps = 0;     ///< vehicle states masked: farther from the last one than the speed allows
  std::uint64_t maskedAccelerations = 0;  ///< vehicle states masked: velocity changed by more than 15 m/s^2
  std::uint64_t windowsImplausible = 0;   ///< windows skipped: the Ego's state at t0 was masked
  std::uint64_t egosAsked = 0;       ///< Egos named or drawn (--egos ids / random:K); 0 for all / vtype:
  std::uint64_t maxSamples = 0;      ///< --max-samples the export stopped at (0: no limit)
  std::uint64_t vehiclesSeen = 0;
  std::uint64_t laneVectors = 0;     ///< lane-boundary vectors of the whole network
  double simulatedSeconds = 0.0;
  double seconds = 0.0;
  double samplesPerSecond = 0.0;
  double bytesPerSample = 0.0;
  bool closedLoop = false;
  std::vector<sim::EgoFailure> failedEgos;  ///< closed-loop Egos taken out: controller error, crash, exit or hang
  std::string report() const;
};

/// Runs the export. libsumo and the controllers run in a worker process under
/// the watchdog: a closed-loop Ego whose controller throws, crashes, exits or
/// hangs is taken out at that moment and listed in failedEgos (the export is
/// repeated without it — deterministically — if the fault took the worker
/// down); a crash or hang of libsumo itself ends the export with SumoError.
/// Throws ConfigError / SumoError for a map SUMO or netconvert rejects, an Ego
/// id that never appears, an empty selection, a window longer than the
/// simulation, InterruptedError on SIGINT/SIGTERM; the output file is then not
/// created (or an older one is kept).
ExportSummary exportMap(const ExportOptions& options);

/// Which windows a process builds: window w (in the order a one-process export emits
/// them) belongs to rank w mod ranks.
struct WindowShare {
  std::uint64_t rank = 0;
  std::uint64_t ranks = 1;
  bool mine(std::uint64_t window) const { return window % ranks == rank; }
};

class Communicator;

/// What `mpirun -n N vsd-sumo export` ends with on this rank.
struct ClusterExportResult {
  int exitCode = 0;
  std::string report;  ///< rank 0: the export's summary; other ranks: empty
};

/// `export` on an MPI job: every rank simulates the whole map (SUMO is deterministic,
/// and closed-loop Egos interact with the traffic, so no rank can skip any of it) but
/// builds and writes only its share of the windows (WindowShare) to a part file next
/// to the output; rank 0 then joins the parts in window order, bit for bit, into the
/// one dataset a one-process export writes. Faults of the map or options are reported
/// once by rank 0 (exit code 1 on every rank).
ClusterExportResult exportOnCluster(const ExportOptions& options, Communicator& communicator);

}  // namespace vsd::pipeline
