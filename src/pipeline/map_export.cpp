#include "vsd/pipeline/map_export.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "vsd/sim/activity.hpp"
#include "vsd/core/bytes.hpp"
#include "vsd/core/error.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/core/random.hpp"
#include "vsd/road/map_importers.hpp"
#include "vsd/road/network.hpp"
#include "vsd/sim/controller.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/pipeline/worker_pool.hpp"
#include "vsd/vector/vectorize.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

EgoSelection EgoSelection::parse(const std::string& text) {
  const std::string expected = "all, random:K (K > 0), vtype:NAME, or a comma-separated list of vehicle ids";
  EgoSelection selection;
  if (text == "all") return selection;
  if (text.rfind("random:", 0) == 0) {
    selection.kind = Kind::Random;
    const std::string count = text.substr(7);
    char* end = nullptr;
    const long long value = std::strtoll(count.c_str(), &end, 10);
    if (count.empty() || *end != '\0' || value <= 0) throw ConfigError::field("command line", "--egos", text, expected);
    selection.count = static_cast<std::size_t>(value);
    return selection;
  }
  if (text.rfind("vtype:", 0) == 0) {
    selection.kind = Kind::VehicleType;
    selection.vehicleType = text.substr(6);
    if (selection.vehicleType.empty()) throw ConfigError::field("command line", "--egos", text, expected);
    return selection;
  }
  selection.kind = Kind::Ids;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string id = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (id.empty()) throw ConfigError::field("command line", "--egos", text, expected);
    selection.ids.push_back(id);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return selection;
}

namespace {

bool isMultipleOf(double value, double step) {
  const double ratio = value / step;
  return std::abs(ratio - std::round(ratio)) < 1e-6;
}

int stepsOf(double seconds, double step) { return static_cast<int>(std::lround(seconds / step)); }

}  // namespace

void ExportOptions::validate() const {
  const std::string where = "command line";
  if (source.config.empty() && source.net.empty() && openDrive.empty()) {
    throw ConfigError("no map given: pass a .sumocfg, or --net with --routes, or --opendrive with --routes");
  }
  const int given = (!source.config.empty() ? 1 : 0) + (!source.net.empty() ? 1 : 0) + (!openDrive.empty() ? 1 : 0);
  if (given > 1) throw ConfigError("give exactly one map: a .sumocfg, --net or --opendrive");
  if (!source.config.empty() && !source.routes.empty()) {
    throw ConfigError("--routes is only used with --net or --opendrive (a .sumocfg names its own route files)");
  }
  if (output.empty()) throw ConfigError("--out is required (the dataset file to write)");
  requireFileOutputPath(output, "--out");
  // Bounds keep the work finite: a window is at most kMaxWindowSteps steps, the
  // lane query looks at most kMaxRadius around the Ego, a lane of 1 km is split into
  // at most 10^4 vectors.
  if (!(step >= kMinStep && step <= kMaxStep) || !isMultipleOf(step, kMinStep)) {
    throw ConfigError::field(where, "--step", formatValue(step),
                             fmt::format("a multiple of {0} s in {0} .. {1} s", kMinStep, kMaxStep));
  }
  if (!(horizon > 0.0) || !isMultipleOf(horizon, step) || horizon / step > kMaxWindowSteps + 0.5) {
    throw ConfigError::field(where, "--horizon", formatValue(horizon),
                             fmt::format("a multiple of --step > 0 s, at most {} steps", kMaxWindowSteps));
  }
  if (!(history >= 0.0) || !isMultipleOf(history, step) || history / step > kMaxWindowSteps + 0.5) {
    throw ConfigError::field(where, "--history", formatValue(history),
                             fmt::format("a multiple of --step >= 0 s, at most {} steps", kMaxWindowSteps));
  }
  if (!(stride >= step) || !isMultipleOf(stride, step) || stride > kMaxStride) {
    throw ConfigError::field(where, "--stride", formatValue(stride),
                             fmt::format("a multiple of --step in --step .. {} s", kMaxStride));
  }
  if (!(laneChangeDuration >= 0.0 && laneChangeDuration <= kMaxLaneChangeDuration)) {
    throw ConfigError::field(where, "--lane-change-duration", formatValue(laneChangeDuration),
                             fmt::format("a duration in 0 .. {} s", kMaxLaneChangeDuration));
  }
  if (!(radius > 0.0 && radius <= kMaxRadius)) {
    throw ConfigError::field(where, "--radius", formatValue(radius), fmt::format("a radius in (0, {}] m", kMaxRadius));
  }
  if (!(maxVectorLength >= kMinVectorLength && maxVectorLength <= kMaxVectorLength)) {
    throw ConfigError::field(where, "--max-vector-length", formatValue(maxVectorLength),
                             fmt::format("a length in {} .. {} m", kMinVectorLength, kMaxVectorLength));
  }
  for (const auto& [flag, time] : {std::pair{"--begin", begin}, std::pair{"--end", end}}) {
    if (time && !(*time >= 0.0 && *time <= kMaxSimulationTime)) {
      throw ConfigError::field(where, flag, formatValue(*time), fmt::format("a time in 0 .. {} s", kMaxSimulationTime));
    }
  }
  if (compression < 0 || compression > 9) {
    throw ConfigError::field(where, "--compression", std::to_string(compression), "a deflate level 0 .. 9");
  }
  if (begin && end && *end <= *begin) {
    throw ConfigError::field(where, "--end", formatValue(*end), "an end time after --begin");
  }
  EgoSelection::parse(egos);
  watchdog.validate();
}

namespace {

/// Bounds of physically possible motion (README "export"): a state that moves a vehicle
/// farther than its speed allows (plus the tolerance), or that changes its velocity
/// faster than any road vehicle can, is masked — never written as a valid instant.
/// SUMO produces such states: continuous lane changes (--lanechange.duration) shift a
/// vehicle sideways and back, and some maps' lane geometry makes positions jump.
constexpr double kJumpTolerance = 0.5;               ///< m beyond speed x elapsed time
constexpr double kMaxPlausibleAcceleration = 15.0;   ///< m/s^2, from positions (second difference)
/// After this many masked states in a row the vehicle's motion starts afresh from where
/// it is (it was moved by SUMO, e.g. teleported): the masking never spreads without end.
constexpr int kMaxMaskedInARow = 3;

/// One recorded state: its step, and whether it continues the vehicle's motion possibly.
struct Recorded {
  std::int64_t step = 0;
  VehicleState state;
  bool plausible = true;
};

/// The last plausible motion of a vehicle: where it was, how fast, and its velocity.
struct Motion {
  std::int64_t step = 0;
  Vec2 position = Vec2::Zero();
  double speed = 0.0;
  std::optional<Vec2> velocity;  ///< from the two last plausible positions
  int maskedInARow = 0;
};

/// The last window-length of states of one vehicle.
struct History {
  std::deque<Recorded> states;  ///< increasing steps
  double length = kCarLength;  // overwritten from the snapshot before use
  double width = kCarWidth;
  std::int64_t lastStep = 0;
  bool ego = false;
  std::int64_t nextT0 = 0;  ///< Egos: step of the next window start
  std::uint64_t samples = 0;
  Vec2 windowLo = Vec2::Zero();  ///< bounding box of the states in the current window
  Vec2 windowHi = Vec2::Zero();
  std::optional<Motion> motion;  ///< the last plausible state

  const Recorded* at(std::int64_t step) const {
    if (states.empty() || step < states.front().step || step > states.back().step) return nullptr;
    // Steps are consecutive unless the vehicle was away (teleport): try the direct index first.
    const auto offset = static_cast<std::size_t>(step - states.front().step);
    if (offset < states.size() && states[offset].step == step) return &states[offset];
    const auto it = std::lower_bound(states.begin(), states.end(), step,
                                     [](const Recorded& entry, std::int64_t value) { return entry.step < value; });
    return it != states.end() && it->step == step ? &*it : nullptr;
  }

  /// Whether `state` at `step` continues the motion possibly (see kJumpTolerance);
  /// `jumps` / `accelerations` count the refusals by cause.
  bool plausible(std::int64_t step, const VehicleState& state, double dt, std::uint64_t& jumps,
                 std::uint64_t& accelerations) {
    const Vec2 position = state.position();
    if (!motion || step - motion->step > 1 + kMaxMaskedInARow || motion->maskedInARow >= kMaxMaskedInARow) {
      motion = Motion{step, position, state.speed, std::nullopt, 0};  // a new start (first state, or moved by SUMO)
      return true;
    }
    const double elapsed = static_cast<double>(step - motion->step) * dt;
    const Vec2 displacement = position - motion->position;
    const Vec2 velocity = displacement / elapsed;
    if (displacement.norm() > std::max(motion->speed, state.speed) * elapsed + kJumpTolerance) {
      ++jumps;
      ++motion->maskedInARow;
      return false;
    }
    if (motion->velocity && (velocity - *motion->velocity).norm() / elapsed > kMaxPlausibleAcceleration) {
      ++accelerations;
      ++motion->maskedInARow;
      return false;
    }
    motion = Motion{step, position, state.speed, velocity, 0};
    return true;
  }
};

class Exporter {
 public:
  Exporter(const ExportOptions& options, const WindowShare& share, const vector::LaneIndex& lanes,
           vector::DatasetWriter& writer, vector::Provenance provenance, std::string label)
      : options_(options),
        share_(share),
        lanes_(lanes),
        writer_(writer),
        provenance_(std::move(provenance)),
        label_(std::move(label)),
        historySteps_(stepsOf(options.history, options.step)),
        horizonSteps_(stepsOf(options.horizon, options.step)),
        strideSteps_(stepsOf(options.stride, options.step)) {}

  /// Records the vehicles of step `step`; returns the Egos seen for the first time.
  std::vector<std::string> record(std::int64_t step, const std::vector<sim::VehicleSnapshot>& vehicles,
                                  const std::function<bool(const sim::VehicleSnapshot&)>& is_ego) {
    std::vector<std::string> fresh;
    const std::int64_t window = historySteps_ + horizonSteps_;
    for (const auto& vehicle : vehicles) {
      if (vehicle.parked) {
        // Absent while parked: masked in other vehicles' polylines, and an Ego's
        // window that overlaps parking is incomplete (skipped).
        ++parkedSteps_;
        continue;
      }
      auto [it, inserted] = histories_.try_emplace(vehicle.id);
      History& history = it->second;
      if (inserted) {
        history.length = vehicle.length;
        history.width = vehicle.width;
        history.ego = is_ego(vehicle);
        history.nextT0 = step + historySteps_;
        if (history.ego) fresh.push_back(vehicle.id);
        ++vehiclesSeen_;
      }
      const bool plausible = history.plausible(step, vehicle.state, options_.step, maskedJumps_, maskedAccelerations_);
      history.states.push_back({step, vehicle.state, plausible});
      while (history.states.front().step < step - window) history.states.pop_front();
      history.lastStep = step;
    }
    return fresh;
  }

  /// Emits the windows that end at `step`; forgets vehicles gone for a whole window.
  void emit(std::int64_t step, double time) {
    const std::int64_t window = historySteps_ + horizonSteps_;
    // Each vehicle's bounding box over the window, once per step (dozens of
    // windows may end in one step, each asking which vehicles came near).
    for (auto& [id, history] : histories_) {
      history.windowLo = history.windowHi = history.states.back().state.position();
      for (const auto& recorded : history.states) {
        history.windowLo = history.windowLo.cwiseMin(recorded.state.position());
        history.windowHi = history.windowHi.cwiseMax(recorded.state.position());
      }
    }
    for (auto it = histories_.begin(); it != histories_.end();) {
      History& history = it->second;
      if (history.ego && history.lastStep == step && step == history.nextT0 + horizonSteps_) {
        if (!completeWindow(history, step)) {
          ++skipped_;
        } else if (!history.at(step - horizonSteps_)->plausible) {
          ++skippedImplausible_;  // the Ego's initial state is not a possible one: no sample starts there
        } else {
          emitWindow(it->first, history, step, time);
        }
        history.nextT0 += strideSteps_;
      }
      if (history.lastStep < step - window) {
        // Gone for good: a window it had started but not finished is skipped.
        if (history.ego && history.nextT0 <= history.lastStep) ++skipped_;
        if (history.ego && history.samples > 0) ++egosWithSamples_;
        it = histories_.erase(it);
      } else {
        ++it;
      }
    }
  }

  void finish() {
    for (auto& [id, history] : histories_) {
      if (history.ego && history.samples > 0) ++egosWithSamples_;
    }
    histories_.clear();
  }

  std::uint64_t samples() const { return samples_; }
  std::uint64_t skipped() const { return skipped_; }
  std::uint64_t egos() const { return egosWithSamples_; }
  std::uint64_t vehiclesSeen() const { return vehiclesSeen_; }
  std::uint64_t parkedSteps() const { return parkedSteps_; }
  std::uint64_t maskedJumps() const { return maskedJumps_; }
  std::uint64_t maskedAccelerations() const { return maskedAccelerations_; }
  std::uint64_t skippedImplausible() const { return skippedImplausible_; }

 private:
  bool completeWindow(const History& history, std::int64_t step) const {
    const std::int64_t first = step - historySteps_ - horizonSteps_;
    std::int64_t present = 0;
    for (const auto& recorded : history.states) {
      if (recorded.step >= first && recorded.step <= step) ++present;
    }
    return present == historySteps_ + horizonSteps_ + 1;
  }

  void emitWindow(const std::string& ego_id, History& ego, std::int64_t step, double time) {
    if (!share_.mine(samples_)) {  // another rank's window: counted, not built
      ++samples_;
      ++ego.samples;
      return;
    }
    const std::int64_t first = step - historySteps_ - horizonSteps_;
    const std::int64_t t0 = step - horizonSteps_;
    const std::size_t instants = static_cast<std::size_t>(historySteps_ + horizonSteps_ + 1);
    const VehicleState& ego_start = ego.at(t0)->state;
    const Vec2 centre = ego_start.position();
    const double radius_sq = options_.radius * options_.radius;

    Trace trace;
    trace.step = options_.step;
    trace.vehicles.push_back(trackOf(ego, first, instants, nullptr, 0.0));
    trace.vehicles.front().role = VehicleRole::Ego;
    for (const auto& [id, other] : histories_) {
      if (&other == &ego) continue;
      const Vec2 nearest = centre.cwiseMax(other.windowLo).cwiseMin(other.windowHi);
      if ((nearest - centre).squaredNorm() > radius_sq) continue;  // the whole window stays away
      bool near = false;
      for (const auto& recorded : other.states) {
        if (recorded.step >= first && recorded.step <= step &&
            (recorded.state.position() - centre).squaredNorm() <= radius_sq) {
          near = true;
          break;
        }
      }
      if (near) trace.vehicles.push_back(trackOf(other, first, instants, &centre, radius_sq));
    }

    auto scene = vector::buildScene(label_, trace, static_cast<std::size_t>(historySteps_),
                                    lanes_.query(centre, options_.radius));
    scene.sample = samples_;
    scene.provenance = provenance_;
    scene.provenance.egoId = ego_id;
    // SUMO counts time in milliseconds: round away the float noise of the subtraction.
    scene.provenance.t0 = std::round((time - static_cast<double>(horizonSteps_) * options_.step) * 1000.0) / 1000.0;
    writer_.append(scene);
    ++samples_;
    ++ego.samples;
  }

  /// The states of `history` at steps first .. first + instants - 1; masked where absent,
  /// where the motion is impossible, or (if `centre` is given) outside the radius.
  static VehicleTrack trackOf(const History& history, std::int64_t first, std::size_t instants, const Vec2* centre,
                              double radius_sq) {
    VehicleTrack track;
    track.length = history.length;
    track.width = history.width;
    track.states.resize(instants);
    track.valid.assign(instants, 0);
    for (std::size_t k = 0; k < instants; ++k) {
      const Recorded* recorded = history.at(first + static_cast<std::int64_t>(k));
      if (recorded == nullptr) continue;
      track.states[k] = recorded->state;
      track.valid[k] = recorded->plausible &&
                               (centre == nullptr || (recorded->state.position() - *centre).squaredNorm() <= radius_sq)
                           ? 1
                           : 0;
    }
    return track;
  }

  const ExportOptions& options_;
  WindowShare share_;
  const vector::LaneIndex& lanes_;
  vector::DatasetWriter& writer_;
  vector::Provenance provenance_;
  std::string label_;
  std::int64_t historySteps_;
  std::int64_t horizonSteps_;
  std::int64_t strideSteps_;
  std::unordered_map<std::string, History> histories_;
  std::uint64_t samples_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t egosWithSamples_ = 0;
  std::uint64_t vehiclesSeen_ = 0;
  std::uint64_t parkedSteps_ = 0;
  std::uint64_t maskedJumps_ = 0;
  std::uint64_t maskedAccelerations_ = 0;
  std::uint64_t skippedImplausible_ = 0;
};

}  // namespace

namespace {

/// Which vehicles random:K and id lists make Egos (empty for all / vtype:).
std::unordered_set<std::string> chooseEgos(const EgoSelection& selection, const ExportOptions& options,
                                           const sim::MapSimulationOptions& simulation_options,
                                           const fs::path& map_file) {
  std::unordered_set<std::string> chosen;
  if (selection.kind == EgoSelection::Kind::Random) {
    // random:K needs every vehicle that will depart: a SUMO-only first run lists them.
    spdlog::info("listing the vehicles of {} (a first, SUMO-only run) to draw {} Egos", map_file.string(),
                 selection.count);
    const auto departed = sim::MapSimulation::listDepartures(simulation_options);
    if (departed.size() < selection.count) {
      throw ConfigError(fmt::format("--egos random:{}: only {} vehicles depart in {}", selection.count, departed.size(),
                                    map_file.string()));
    }
    Rng rng = Rng::derive(options.seed, 0, RandomStream::EgoSelection);
    const auto order = rng.permutation(departed.size());
    for (std::size_t i = 0; i < selection.count; ++i) chosen.insert(departed[order[i]]);
  } else if (selection.kind == EgoSelection::Kind::Ids) {
    chosen.insert(selection.ids.begin(), selection.ids.end());
  }
  return chosen;
}

/// What a map export needs besides its options (decided in the parent).
struct ExportJob {
  const ExportOptions& options;
  sim::MapSimulationOptions simulation;
  fs::path mapFile;
  std::string label;
  fs::path datasetPath;                        ///< the temporary file to write
  std::vector<sim::EgoFailure> plannedFailures;  ///< controller faults found by earlier attempts
  WindowShare share;                           ///< the windows this process writes (MPI: its rank's)
};

/// Fails with one line if the Egos asked for never showed up.
void checkSelectionWasSeen(const EgoSelection& selection, const ExportJob& job, const Exporter& exporter,
                           const std::unordered_set<std::string>& seen_egos,
                           const std::unordered_set<std::string>& seen_types, double begin, double end) {
  if (selection.kind == EgoSelection::Kind::Ids) {
    for (const auto& id : selection.ids) {
      if (!seen_egos.count(id)) {
        throw ConfigError(fmt::format("--egos: vehicle '{}' never appears in {} (between t = {} and {} s)", id,
                                      job.mapFile.string(), begin, end));
      }
    }
  }
  if (selection.kind == EgoSelection::Kind::VehicleType && exporter.vehiclesSeen() > 0 &&
      !seen_types.count(selection.vehicleType)) {
    std::vector<std::string> types(seen_types.begin(), seen_types.end());
    std::sort(types.begin(), types.end());
    throw ConfigError(fmt::format("--egos vtype:{}: no vehicle of that type in {} (types: {})", selection.vehicleType,
                                  job.mapFile.string(), fmt::join(types, ", ")));
  }
  if (exporter.samples() == 0) {
    throw ConfigError(fmt::format("no complete window in {}: no Ego stayed {} s (history + horizon) in the network "
                                  "between t = {} and {} s",
                                  job.mapFile.string(), job.options.history + job.options.horizon, begin, end));
  }
}

/// What an export wrote and skipped, once its simulation (started at `begin`) has ended.
ExportSummary exportSummary(const Exporter& exporter, const vector::LaneIndex& lanes,
                            const sim::MapSimulation& simulation, std::uint64_t egos_asked, double begin) {
  ExportSummary summary;
  summary.samples = exporter.samples();
  summary.egos = exporter.egos();
  summary.windowsSkipped = exporter.skipped();
  summary.vehiclesSeen = exporter.vehiclesSeen();
  summary.parkedSteps = exporter.parkedSteps();
  summary.maskedJumps = exporter.maskedJumps();
  summary.maskedAccelerations = exporter.maskedAccelerations();
  summary.windowsImplausible = exporter.skippedImplausible();
  summary.egosAsked = egos_asked;
  summary.laneVectors = lanes.vectors();
  summary.simulatedSeconds = simulation.time() - begin;
  summary.failedEgos = simulation.failures();
  return summary;
}

/// Simulates the map and writes the dataset to job.datasetPath (in a worker
/// process: libsumo and the controllers run here). `progress` gets the
/// simulated seconds so far and the seconds to simulate (0 if unknown).
/// `lane_pool`, if given, receives the map's shared lane vectors (to join MPI parts).
ExportSummary simulateAndWrite(const ExportJob& job, const std::function<void(double, double)>& progress,
                               std::vector<vector::Feature>* lane_pool = nullptr) {
  const ExportOptions& options = job.options;
  const EgoSelection selection = EgoSelection::parse(options.egos);
  auto registry = sim::ControllerRegistry::withBuiltins();
  const sim::ControllerParams params(options.controllerParams, "command line: --controller-param");
  if (options.closedLoop) {  // fail fast on an unknown controller or bad parameters
    sim::makeController(registry, options.controller, options.controllerLibrary, fs::current_path(), params);
  }
  const auto chosen = chooseEgos(selection, options, job.simulation, job.mapFile);

  sim::MapSimulation simulation(job.simulation);
  for (const auto& failure : job.plannedFailures) simulation.scheduleFailure(failure.id, failure.time, failure.reason);
  const double begin = simulation.time();
  const double window_seconds = options.history + options.horizon;
  if (const auto end = simulation.endTime(); end && *end - begin < window_seconds) {
    throw ConfigError(fmt::format("a window of {} s (--history {} + --horizon {}) is longer than the simulation "
                                  "({} s from {} to {})",
                                  window_seconds, options.history, options.horizon, *end - begin, begin, *end));
  }
  const vector::LaneIndex lanes(simulation.lanes(), options.maxVectorLength);

  vector::DatasetHeader header;
  header.kind = "map";
  header.step = options.step;
  header.horizon = stepsOf(options.horizon, options.step);
  header.history = stepsOf(options.history, options.step);
  header.compression = options.compression;
  vector::DatasetWriter writer(job.datasetPath, header, job.options.output);
  writer.setSharedVectors(lanes.pool());
  if (lane_pool) *lane_pool = lanes.pool();
  const vector::Provenance provenance{job.mapFile.string(), sha256OfFile(job.mapFile), "", 0.0};
  Exporter exporter(options, job.share, lanes, writer, provenance, job.label);

  std::unordered_set<std::string> seen_egos;
  std::unordered_set<std::string> seen_types;
  const auto is_ego = [&](const sim::VehicleSnapshot& vehicle) {
    if (selection.kind == EgoSelection::Kind::VehicleType) seen_types.insert(vehicle.type);
    switch (selection.kind) {
      case EgoSelection::Kind::All: return true;
      case EgoSelection::Kind::VehicleType: return vehicle.type == selection.vehicleType;
      default: return chosen.count(vehicle.id) > 0;
    }
  };

  const double total = simulation.endTime() ? *simulation.endTime() - begin : 0.0;
  progress(0.0, total);
  std::int64_t step = 0;
  double reported = begin;
  std::uint64_t written = 0;
  while (simulation.step()) {
    ++step;
    for (const auto& id : exporter.record(step, simulation.vehicles(), is_ego)) {
      seen_egos.insert(id);
      if (!options.closedLoop) continue;
      reportSimulationTime(simulation.time());
      reportSubject(-1, id);
      if (const auto reason = simulation.scheduledFailure(id)) {
        simulation.failEgo(id, *reason);
      } else {
        simulation.takeOver(id, sim::makeController(registry, options.controller, options.controllerLibrary,
                                                     fs::current_path(), params));
      }
    }
    exporter.emit(step, simulation.time());
    if (simulation.time() - reported >= 1.0) {
      reported = simulation.time();
      progress(reported - begin, total);
    }
    if (exporter.samples() / 1000 > written / 1000) faultPoint("export.write");
    written = exporter.samples();
    if (options.maxSamples > 0 && exporter.samples() >= options.maxSamples) break;
  }
  exporter.finish();
  checkSelectionWasSeen(selection, job, exporter, seen_egos, seen_types, begin, simulation.time());
  writer.close();

  return exportSummary(exporter, lanes, simulation, chosen.size(), begin);
}

enum class ExportMessage : char { Progress = 'P', Summary = 'S' };

std::vector<char> encodeSummary(const ExportSummary& summary) {
  ByteWriter writer;
  writer.put<char>(static_cast<char>(ExportMessage::Summary));
  writer.put(summary.samples);
  writer.put(summary.egos);
  writer.put(summary.windowsSkipped);
  writer.put(summary.vehiclesSeen);
  writer.put(summary.parkedSteps);
  writer.put(summary.maskedJumps);
  writer.put(summary.maskedAccelerations);
  writer.put(summary.windowsImplausible);
  writer.put(summary.egosAsked);
  writer.put(summary.laneVectors);
  writer.put(summary.simulatedSeconds);
  writer.put<std::uint64_t>(summary.failedEgos.size());
  for (const auto& failure : summary.failedEgos) {
    writer.putString(failure.id);
    writer.put(failure.time);
    writer.putString(failure.reason);
  }
  return writer.bytes();
}

ExportSummary decodeSummary(ByteReader& reader) {
  ExportSummary summary;
  summary.samples = reader.get<std::uint64_t>();
  summary.egos = reader.get<std::uint64_t>();
  summary.windowsSkipped = reader.get<std::uint64_t>();
  summary.vehiclesSeen = reader.get<std::uint64_t>();
  summary.parkedSteps = reader.get<std::uint64_t>();
  summary.maskedJumps = reader.get<std::uint64_t>();
  summary.maskedAccelerations = reader.get<std::uint64_t>();
  summary.windowsImplausible = reader.get<std::uint64_t>();
  summary.egosAsked = reader.get<std::uint64_t>();
  summary.laneVectors = reader.get<std::uint64_t>();
  summary.simulatedSeconds = reader.get<double>();
  const auto failures = reader.get<std::uint64_t>();
  for (std::uint64_t i = 0; i < failures; ++i) {
    sim::EgoFailure failure;
    failure.id = reader.getString();
    failure.time = reader.get<double>();
    failure.reason = reader.getString();
    summary.failedEgos.push_back(std::move(failure));
  }
  return summary;
}

/// Runs simulateAndWrite in a worker process. A crash, exit() or hang of an
/// Ego's controller fails that Ego: the export starts again (deterministically)
/// with the Ego taken out when the fault happened. A fault of libsumo itself
/// ends the export with one line.
ExportSummary exportInWorker(ExportJob& job) {
  std::optional<Progress> progress;
  double shown = 0.0;
  for (;;) {
    WorkerPool pool(1, [&job](int, WorkerChannel& channel) {
      const auto summary = simulateAndWrite(job, [&](double seconds, double total) {
        ByteWriter message;
        message.put<char>(static_cast<char>(ExportMessage::Progress));
        message.put(seconds);
        message.put(total);
        channel.send(message.bytes());
      });
      channel.send(encodeSummary(summary));
    }, job.options.watchdog);
    try {
      for (;;) {
        const auto message = pool.receive(0);
        ByteReader reader(message);
        if (static_cast<ExportMessage>(reader.get<char>()) == ExportMessage::Summary) {
          auto summary = decodeSummary(reader);
          pool.finish();
          if (progress) progress->finish();
          return summary;
        }
        const double seconds = reader.get<double>();
        const double total = reader.get<double>();
        if (!progress) progress.emplace(fmt::format("export {}", job.label), static_cast<std::size_t>(total), "s simulated");
        if (seconds > shown) {  // an attempt after a fault repeats what was shown
          progress->advance(static_cast<std::size_t>(seconds) - static_cast<std::size_t>(shown));
          shown = seconds;
        }
      }
    } catch (const WorkerLost& lost) {
      const auto& fault = lost.fault();
      const auto& activity = fault.activity;
      const bool ego_fault = activity.activity == Activity::Controller || activity.activity == Activity::SumoVehicles;
      if (!ego_fault || activity.label.empty()) {
        // Times are SUMO's own clock (a map may start at 50,300 s); while loading there is none yet.
        const std::string when = activity.activity == Activity::SumoLoad
                                     ? std::string("while loading the simulation")
                                     : fmt::format("during {} at simulation time t = {:.1f} s",
                                                   activityName(activity.activity), activity.time);
        throw SumoError(fmt::format("{}: {} {}", job.mapFile.string(),
                                    activity.activity == Activity::Idle ? "the export's worker process " + fault.what()
                                                                        : "libsumo " + fault.what(),
                                    when));
      }
      const std::string who = activity.activity == Activity::Controller ? "Ego controller" : "libsumo";
      job.plannedFailures.push_back(
          {activity.label, activity.time, fmt::format("{} {} at t = {:.1f} s", who, fault.what(), activity.time)});
      spdlog::warn("Ego '{}': {}; exporting again without it from t = {:.1f} s", activity.label, fault.what(),
                   activity.time);
    }
  }
}

/// The job of exporting `options` (the OpenDRIVE map converted into `work`).
ExportJob makeJob(const ExportOptions& options, const TemporaryDirectory& work) {
  ExportJob job{options, {}, options.source.mainFile(), "", "", {}, WindowShare{}};
  job.simulation.source = options.source;
  job.simulation.step = options.step;
  job.simulation.begin = options.begin;
  job.simulation.end = options.end;
  job.simulation.seed = options.seed;
  job.simulation.laneChangeDuration = options.laneChangeDuration;
  job.simulation.placed = options.placed;
  job.simulation.workDir = work.path();
  if (!options.openDrive.empty()) {
    job.simulation.source.net =
        road::MapImporterRegistry::withBuiltins().forFile(options.openDrive).toNet(options.openDrive, work.path());
    job.mapFile = options.openDrive;
  }
  if (!options.sourceFile.empty()) job.mapFile = options.sourceFile;
  job.label = options.label.empty() ? job.mapFile.stem().string() : options.label;
  return job;
}

/// Output, label, time and rates of a finished export of `options` (its output written).
void finishSummary(ExportSummary& summary, const ExportOptions& options, const std::string& label,
                   std::chrono::steady_clock::time_point start) {
  summary.output = options.output;
  summary.label = label;
  summary.closedLoop = options.closedLoop;
  summary.maxSamples = options.maxSamples;
  summary.seconds = secondsSince(start);
  summary.samplesPerSecond = static_cast<double>(summary.samples) / std::max(summary.seconds, 1e-9);
  summary.bytesPerSample = static_cast<double>(fs::file_size(options.output)) /
                           static_cast<double>(std::max<std::uint64_t>(summary.samples, 1));
}

/// <output's folder>/.<output name>.parts/part-K-of-N.h5: where rank K writes its windows.
fs::path partPath(const fs::path& output, int rank, int ranks) {
  return output.parent_path() / ("." + output.filename().string() + ".parts") /
         fmt::format("part-{}-of-{}.h5", rank, ranks);
}

/// Rank 0: the ranks' parts joined in window order (window w is sample w / N of part
/// w % N), copied bit for bit: the file a one-process export writes.
void joinParts(const ExportOptions& options, const std::vector<vector::Feature>& lane_pool, std::uint64_t samples,
               int ranks, const fs::path& target) {
  std::vector<std::unique_ptr<vector::DatasetReader>> parts;
  for (int r = 0; r < ranks; ++r) {
    parts.push_back(std::make_unique<vector::DatasetReader>(partPath(options.output, r, ranks)));
  }
  vector::DatasetHeader header = parts.front()->header();
  header.compression = options.compression;
  vector::DatasetWriter writer(target, header);
  writer.setSharedVectors(lane_pool);
  const auto n = static_cast<std::uint64_t>(ranks);
  for (std::uint64_t w = 0; w < samples; ++w) writer.appendCopy(*parts[w % n], w / n);
  writer.close();
}

}  // namespace

ExportSummary exportMap(const ExportOptions& options) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  TemporaryDirectory work("vsd-export");
  ExportJob job = makeJob(options, work);
  if (!options.output.parent_path().empty()) ensureDirectory(options.output.parent_path());
  AtomicOutput output(options.output);
  job.datasetPath = output.tempPath();
  ExportSummary summary = exportInWorker(job);
  output.commitUnlessInterrupted();
  finishSummary(summary, options, job.label, start);
  return summary;
}

ClusterExportResult exportOnCluster(const ExportOptions& options, Communicator& communicator) {
  const auto start = std::chrono::steady_clock::now();
  const int rank = communicator.rank();
  const int ranks = communicator.size();
  const fs::path mine = partPath(options.output, rank, ranks);
  // Parts are read once, by rank 0: not compressed (the joined file is).
  ExportOptions part_options = options;
  part_options.compression = 0;
  std::optional<TemporaryDirectory> work;
  std::optional<ExportJob> job;
  ExportSummary summary;
  std::vector<vector::Feature> lane_pool;
  std::string failure;
  try {
    options.validate();
    ensureDirectory(mine.parent_path());
    work.emplace("vsd-export");
    job.emplace(makeJob(part_options, *work));
    job->share = WindowShare{static_cast<std::uint64_t>(rank), static_cast<std::uint64_t>(ranks)};
    job->datasetPath = mine;
    // In this process (a rank is its own process already): the lane pool is needed to join.
    summary = simulateAndWrite(*job, [](double, double) {}, &lane_pool);
  } catch (const Error& error) {
    failure = error.what();
  }
  // Every rank simulates the whole map, so faults of the map or the options occur on
  // every rank alike: rank 0 reports the first one, once.
  if (!checkOnEveryRank(communicator, [&] {
        if (!failure.empty()) throw ConfigError(failure);
      })) {
    std::error_code ignored;
    fs::remove(mine, ignored);
    return {1, {}};
  }
  ClusterExportResult result;
  if (rank != 0) return result;
  AtomicOutput output(options.output);
  workOrEndJob(communicator, "joining the parts",
               [&] { joinParts(options, lane_pool, summary.samples, ranks, output.tempPath()); });
  output.commit();
  std::error_code ignored;
  fs::remove_all(mine.parent_path(), ignored);
  finishSummary(summary, options, job->label, start);
  result.report = fmt::format("{} MPI ranks, windows spread over them (window w on rank w mod {}); parts joined by "
                              "rank 0\n",
                              ranks, ranks) +
                  summary.report();
  return result;
}

std::string ExportSummary::report() const {
  std::string text = fmt::format(
      "{}: {} samples from {} Egos{} ({} vehicles seen, {:.0f} s simulated) in {:.2f} s = {:.0f} samples/s\n"
      "  windows skipped (Ego left the network or parked before the window ended): {}\n"
      "  vehicle steps parked (off the lane, masked): {}\n"
      "  vehicle states masked as impossible motion: {} jumps beyond speed x step + {} m, {} accelerations beyond "
      "{} m/s^2; windows skipped for a masked Ego start: {}\n"
      "  lane-boundary vectors in the network: {}\n",
      label, samples, egos, closedLoop ? " driven by the controller (closed loop)" : "", vehiclesSeen,
      simulatedSeconds, seconds, samplesPerSecond, windowsSkipped, parkedSteps, maskedJumps, kJumpTolerance,
      maskedAccelerations, kMaxPlausibleAcceleration, windowsImplausible, laneVectors);
  if (egosAsked > 0 && egos < egosAsked) {
    const bool limited = maxSamples > 0 && samples >= maxSamples;
    text += fmt::format("  only {} of the {} Egos asked for gave a sample ({})\n", egos, egosAsked,
                        limited ? fmt::format("--max-samples {} ended the export before the others", maxSamples)
                                : "the others never stayed a whole window in the network");
  }
  if (!failedEgos.empty()) {
    text += fmt::format("  Egos taken out because their controller failed: {}\n", failedEgos.size());
    for (const auto& failure : failedEgos) text += fmt::format("    {}: {}\n", failure.id, failure.reason);
  }
  text += fmt::format("  {} ({:.0f} bytes per sample)\n", output.string(), bytesPerSample);
  return text;
}

}  // namespace vsd::pipeline
