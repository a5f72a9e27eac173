#pragma once
// Simulation of an arbitrary SUMO map with its own demand: SUMO drives the
// traffic; every step yields a snapshot of all vehicles (network frame, vehicle
// centres, SI units). Chosen vehicles can be handed to an Ego controller
// (closed loop) and are then driven through the kinematic model like the Ego
// of a generated scenario.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/sim/controller.hpp"

namespace vsd {
class TemporaryDirectory;
}

namespace vsd::sim {

/// A map to simulate: a .sumocfg, or a network plus route files.
struct MapSource {
  std::filesystem::path config;               ///< .sumocfg; when set, net and routes are empty
  std::filesystem::path net;                  ///< SUMO network
  std::vector<std::filesystem::path> routes;  ///< demand (route files)
  std::vector<std::string> sumoOptions;       ///< extra SUMO arguments

  /// The file that identifies the map in provenance (the config, else the network).
  const std::filesystem::path& mainFile() const { return config.empty() ? net : config; }
};

struct VehicleSnapshot {
  std::string id;
  VehicleState state;  ///< centre of the vehicle, network frame
  double length = kCarLength;  ///< m, SUMO's length of the vehicle's type
  double width = kCarWidth;    ///< m
  std::string type;
  /// Stopped with parking="true": SUMO takes it off the lane and draws it beside the
  /// road, so its position jumps sideways by metres in one step and back when it
  /// leaves. Such instants are not driving and must not enter trajectories.
  bool parked = false;
};

/// A closed-loop Ego taken out of the simulation because its controller failed.
struct EgoFailure {
  std::string id;
  double time = 0.0;   ///< s, simulation time of the failure
  std::string reason;  ///< e.g. "Ego controller crashed (signal 11, Segmentation fault) at t = 12.4 s"
};

/// A road user the simulation places on the network itself at its start (an imported
/// scenario's entity): on the lane whose centre line is nearest its centre, on a route that
/// follows the road from there (straight on where it branches, never turning back) to a dead
/// end or an edge it already passed.
struct PlacedRoadUser {
  std::string id;
  Vec2 centre = Vec2::Zero();  ///< m, network frame; within kMaxPlacementOffset of a lane's centre line
  double heading = 0.0;        ///< rad; within 90 degrees of that lane's direction
  double speed = 0.0;          ///< m/s at the start, >= 0
  double length = kCarLength;  ///< m
  double width = kCarWidth;    ///< m
  std::string vehicleClass = "passenger";  ///< SUMO's vClass
  /// true: keeps `speed` on its lane whatever lies ahead (a scripted entity; it changes lanes only
  /// where its lane ends and the road goes on in another); false: SUMO drives it (until a
  /// controller takes it over).
  bool holdsSpeed = true;
  std::string where;  ///< where it comes from, for messages (e.g. "F.xosc:57: <Private>")

  /// m: how far from its lane's centre line a road user may be placed (it starts on it).
  static constexpr double kMaxPlacementOffset = 0.25;
};

struct MapSimulationOptions {
  MapSource source;
  double step = 0.0;             ///< s (> 0); no default: from the export options
  std::optional<double> begin;   ///< s; default: the map's own
  std::optional<double> end;     ///< s; default: the map's own, else until no vehicle is left
  std::uint64_t seed = 1;        ///< SUMO's --seed
  /// s; > 0: SUMO's lane changes take this long instead of jumping a lane width
  /// within one step (which would put lane-width jumps into recorded trajectories).
  /// 0 keeps the map's setting (e.g. for maps using the sublane model).
  double laneChangeDuration = 2.0;
  /// Road users placed at the start besides the map's own demand; each departs at once
  /// (the first step), or the constructor's first step() throws ConfigError naming it.
  std::vector<PlacedRoadUser> placed;
  /// An existing folder the caller owns for the placed road users' file (a worker process that
  /// is killed leaves nothing behind); empty: a temporary folder of the simulation's own.
  std::filesystem::path workDir;
};

class MapSimulation {
 public:
  /// Loads the map and places options.placed. Throws ConfigError for missing files and a road
  /// user that cannot be placed (naming its `where`), SumoError if SUMO rejects the map.
  explicit MapSimulation(const MapSimulationOptions& options);
  MapSimulation(const MapSimulation&) = delete;
  MapSimulation& operator=(const MapSimulation&) = delete;
  ~MapSimulation();

  /// Every lane of the network including junction-internal lanes (network frame).
  std::vector<LaneGeometry> lanes() const;
  /// Advances one step; false (without stepping) once the end time is reached or
  /// no vehicle is left to come.
  bool step();
  double time() const;
  /// The map's end time (s) if it has one.
  std::optional<double> endTime() const;
  /// Vehicles in the network after the last step.
  const std::vector<VehicleSnapshot>& vehicles() const { return vehicles_; }
  /// The vehicle `id` after the last step; null if it is not in the network.
  const VehicleSnapshot* vehicle(const std::string& id) const;
  /// From the next step on, `id` (present now) is driven by `controller`.
  void takeOver(const std::string& id, std::unique_ptr<EgoController> controller);
  /// Takes a closed-loop (or about to be taken over) Ego out of the simulation
  /// now and records why (failures()).
  void failEgo(const std::string& id, const std::string& reason);
  /// Replays a fault found in an earlier attempt of the same simulation: when
  /// `id`'s controller would next run at simulation time `time`, the Ego fails
  /// with `reason` instead (the controller is not called).
  void scheduleFailure(const std::string& id, double time, std::string reason);
  /// The reason scheduled for `id` at the current time, if any.
  std::optional<std::string> scheduledFailure(const std::string& id) const;
  /// Ego failures so far, in the order they happened. A controller that throws
  /// vsd::Error (other than ConfigError) fails its Ego; the simulation goes on.
  const std::vector<EgoFailure>& failures() const { return failures_; }
  bool controlled(const std::string& id) const { return drivers_.count(id) > 0; }

  /// Ids of every vehicle that departs, in departure order (a separate, SUMO-only run).
  static std::vector<std::string> listDepartures(const MapSimulationOptions& options);

 private:
  void releaseFinishedDrivers();
  /// Steps every closed-loop Ego's controller; failed ones are taken out.
  void driveEgos(double now);

  struct Impl;
  std::unique_ptr<TemporaryDirectory> placedFiles_;  ///< the placed road users' file (before impl_: outlives it)
  std::unique_ptr<Impl> impl_;
  std::vector<VehicleSnapshot> vehicles_;
  std::unordered_map<std::string, std::unique_ptr<class EgoDriver>> drivers_;
  std::vector<EgoFailure> scheduled_;
  std::vector<EgoFailure> failures_;
};

/// The SUMO command line (without the program) for a map simulation.
std::vector<std::string> mapSimulationArguments(const MapSimulationOptions& options);

}  // namespace vsd::sim
