#include "vsd/sim/batch_simulation.hpp"

#include <fmt/format.h>
#include <libsumo/libsumo.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/road/network.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/scripted_vehicle.hpp"

namespace vsd::sim {

namespace {

/// SUMO's vehicle class of a road user (also what sumo-gui draws): pedestrians and objects
/// are SUMO vehicles too, so that SUMO's collision checks and SSM devices see them.
const char* sumoClassOf(RoadUserType type) {
  switch (type) {
    case RoadUserType::Car: return "passenger";
    case RoadUserType::Van: return "delivery";
    case RoadUserType::Truck: return "truck";
    case RoadUserType::Bus: return "bus";
    case RoadUserType::Motorbike: return "motorcycle";
    case RoadUserType::Pedestrian: return "pedestrian";
    case RoadUserType::StationaryObject: return "ignoring";
  }
  return "passenger";
}

/// SUMO vehicle types by (length, width, kind); scripted vehicles ignore SUMO's
/// car-following, so only the dimensions matter (minGap 0: gaps are bumper to bumper).
class VehicleTypes {
 public:
  const std::string& get(const scenario::ConcreteVehicle& vehicle) {
    const auto key = std::make_tuple(vehicle.length, vehicle.width, vehicle.type);
    auto it = types_.find(key);
    if (it != types_.end()) return it->second;
    // Cars keep the type ids of the paper's runs (FCD files name them).
    const std::string id = vehicle.type == RoadUserType::Car
                               ? fmt::format("vsd_{}x{}", vehicle.length, vehicle.width)
                               : fmt::format("vsd_{}_{}x{}", roadUserKind(vehicle.type).name, vehicle.length, vehicle.width);
    libsumo::VehicleType::copy("DEFAULT_VEHTYPE", id);
    libsumo::VehicleType::setLength(id, vehicle.length);
    libsumo::VehicleType::setWidth(id, vehicle.width);
    libsumo::VehicleType::setMinGap(id, 0.0);
    libsumo::VehicleType::setMaxSpeed(id, 100.0);
    libsumo::VehicleType::setSpeedFactor(id, 1.0);
    libsumo::VehicleType::setAccel(id, 20.0);
    libsumo::VehicleType::setDecel(id, 20.0);
    libsumo::VehicleType::setEmergencyDecel(id, 20.0);
    if (vehicle.type != RoadUserType::Car) {
      libsumo::VehicleType::setVehicleClass(id, sumoClassOf(vehicle.type));
      // SUMO has no drawing shape for its "ignoring" class: objects keep the default shape.
      if (vehicle.type != RoadUserType::StationaryObject) {
        libsumo::VehicleType::setShapeClass(id, sumoClassOf(vehicle.type));
      }
    }
    return types_.emplace(key, id).first->second;
  }

 private:
  std::map<std::tuple<double, double, RoadUserType>, std::string> types_;
};

struct Member {
  const ScenarioRun* run = nullptr;
  std::string edge;
  std::string egoId;
  std::vector<std::string> otherIds;
  /// The scripted road users, stepped with the Ego: traffic->states() are every other road
  /// user's states at the current instant (their types and sizes: run->scenario->others).
  std::optional<ScriptedTraffic> traffic;
  std::optional<EgoDriver> ego;
  SumoPlacement placement;  ///< how this scenario's vehicles are put on its road in SUMO
  SimulatedScenario result;
  bool active = true;
};

void initTrack(VehicleTrack& track, const scenario::ConcreteVehicle& vehicle, VehicleRole role, std::size_t instants) {
  track.id = vehicle.id;
  track.role = role;
  track.length = vehicle.length;
  track.width = vehicle.width;
  track.type = vehicle.type;
  track.states.assign(instants, VehicleState{});
  track.valid.assign(instants, 0);
}

std::vector<std::string> sessionArguments(const std::filesystem::path& net, const BatchOptions& options) {
  std::vector<std::string> args = {"--net-file", net.string(),
                                   "--step-length", fmt::format("{}", options.step),
                                   "--begin", "0",
                                   "--collision.action", options.collisionAction,
                                   "--collision.check-junctions", "false",
                                   "--time-to-teleport", "-1",       // no jam teleports: a stopped Co stays
                                   "--default.speeddev", "0",        // no random speed factors
                                   "--seed", "42",
                                   "--xml-validation", "never"};
  if (!options.fcdOutput.empty()) {
    args.insert(args.end(), {"--fcd-output", options.fcdOutput.string()});
  }
  if (options.lateralResolution > 0.0) {
    args.insert(args.end(), {"--lateral-resolution", fmt::format("{}", options.lateralResolution)});
  }
  args.insert(args.end(), options.sumoOptions.begin(), options.sumoOptions.end());
  return args;
}

/// Why SUMO removed `id` in the last step (best effort).
std::string removalReason(const std::string& id, const std::unordered_set<std::string>& arrived,
                          const std::unordered_set<std::string>& colliding,
                          const std::unordered_set<std::string>& teleporting) {
  if (colliding.count(id)) return "collision";
  if (teleporting.count(id)) return "teleport";
  if (arrived.count(id)) return "reached the end of its road";
  return "removed";
}

std::unordered_set<std::string> asSet(const std::vector<std::string>& ids) { return {ids.begin(), ids.end()}; }

}  // namespace

std::vector<SimulatedScenario> simulateBatch(const std::filesystem::path& net, const std::vector<ScenarioRun>& runs,
                                             ControllerRegistry& registry, const BatchOptions& options) {
  if (!(options.step > 0.0) || options.steps < 1) {
    throw Error(fmt::format("internal: batch simulation with step {} s and {} steps", options.step, options.steps));
  }
  const auto t_start = std::chrono::steady_clock::now();
  // Outside the per-scenario parts below, faults belong to the simulation as a whole.
  reportSubject(-1);
  reportSimulationTime(0.0);
  const ActivityScope whole_batch(Activity::SumoStep);
  SumoSession session(sessionArguments(net, options));
  const double load_seconds = secondsSince(t_start);
  const std::size_t instants = static_cast<std::size_t>(options.steps) + 1;
  const double dt = options.step;

  VehicleTypes types;
  LaneCache lanes;
  const bool match_to_lanes = sumoIgnoresLateralPositions();
  std::vector<Member> members(runs.size());
  std::unordered_map<std::string, std::size_t> owner;  // SUMO vehicle id -> member
  std::unordered_set<std::string> expected;             // vehicles that should be in the simulation

  for (std::size_t m = 0; m < runs.size(); ++m) {
    Member& member = members[m];
    const ScenarioRun& run = runs[m];
    const auto& concrete = *run.scenario;
    const auto& spec = *concrete.logical;
    member.run = &run;
    member.result.index = concrete.index;
    reportSubject(static_cast<std::int64_t>(concrete.index));
    const ActivityScope adding(Activity::SumoVehicles);
    member.result.trace.step = dt;
    member.edge = road::edgeIdFor(concrete.index);
    const std::string route = "r" + member.edge;
    libsumo::Route::add(route, {member.edge});

    for (int lane = 0; lane < run.road->lanes; ++lane) {
      member.result.lanes.push_back(fetchLane(fmt::format("{}_{}", member.edge, lane), run.offset));
    }
    if (match_to_lanes) member.placement = SumoPlacement(member.result.lanes);

    // The scripted road users start where the scenario puts them; the Ego on its lane's
    // centre line at its x or s, heading along the lane.
    member.traffic.emplace(concrete, *run.road);
    const auto& ego_spec = concrete.ego;
    member.egoId = member.edge + "." + ego_spec.id;
    libsumo::Vehicle::add(member.egoId, route, types.get(ego_spec), "now", std::to_string(ego_spec.lane), "base",
                          fmt::format("{}", ego_spec.speed));
    libsumo::Vehicle::setSpeedMode(member.egoId, 0);
    libsumo::Vehicle::setLaneChangeMode(member.egoId, 0);
    const bool overridden = !options.egoControllerOverride.empty();
    const ControllerParams params(overridden ? std::vector<std::pair<std::string, double>>{} : concrete.controllerParams,
                                  overridden ? "--reference " + options.egoControllerOverride : spec.ego.controller.where);
    auto controller = withStepCost(
        overridden ? makeController(registry, options.egoControllerOverride, {}, options.scenarioDir, params)
                   : makeController(registry, spec.ego.controller.name, spec.ego.controller.library,
                                    options.scenarioDir, params),
        options.egoStepCost);
    member.ego.emplace(member.egoId, std::move(controller), member.traffic->egoStart(), ego_spec.length,
                       ego_spec.width, run.offset);
    member.ego->placeBy(member.placement);
    member.ego->pushToSumo();
    owner.emplace(member.egoId, m);
    expected.insert(member.egoId);

    auto& trace = member.result.trace;
    trace.vehicles.resize(1 + concrete.others.size());
    initTrack(trace.vehicles[0], ego_spec, VehicleRole::Ego, instants);

    for (std::size_t o = 0; o < concrete.others.size(); ++o) {
      const auto& other = concrete.others[o];
      // Scripted road users are placed where the stepper moves them, like the Ego, so SUMO
      // and the Ego's sensors see them there.
      const std::string id = member.edge + "." + other.id;
      libsumo::Vehicle::add(id, route, types.get(other), "now", std::to_string(other.lane), "base",
                            fmt::format("{}", other.speed));
      libsumo::Vehicle::setSpeedMode(id, 0);
      libsumo::Vehicle::setLaneChangeMode(id, 0);
      placeInSumo(id, member.traffic->states()[o], other.length, other.width, run.offset, member.placement);
      member.otherIds.push_back(id);
      owner.emplace(id, m);
      expected.insert(id);
      initTrack(trace.vehicles[1 + o], other, VehicleRole::Other, instants);
    }
  }

  auto record = [&](std::size_t k) {
    for (auto& member : members) {
      if (!member.active) continue;
      reportSubject(static_cast<std::int64_t>(member.result.index));
      const ActivityScope reading(Activity::SumoVehicles);
      auto& trace = member.result.trace;
      trace.vehicles[0].states[k] = member.ego->state();
      trace.vehicles[0].valid[k] = 1;
      for (std::size_t o = 0; o < member.otherIds.size(); ++o) {
        trace.vehicles[1 + o].states[k] = member.traffic->states()[o];
        trace.vehicles[1 + o].valid[k] = 1;
      }
    }
  };

  auto fail = [&](Member& member, const std::string& reason) {
    if (!member.active) return;
    member.active = false;
    member.result.failure = reason;
    // Take the scenario's remaining vehicles out so they cannot affect anything else.
    std::vector<std::string> ids = member.otherIds;
    ids.push_back(member.egoId);
    const auto alive = asSet(libsumo::Vehicle::getIDList());
    for (const auto& id : ids) {
      if (alive.count(id)) libsumo::Vehicle::remove(id);
      expected.erase(id);
    }
  };

  // A vehicle SUMO removed (end of road, collision with action remove/teleport)
  // fails its scenario; the others go on.
  auto checkRemovals = [&](double time) {
    if (static_cast<std::size_t>(libsumo::Vehicle::getIDCount()) == expected.size()) return;
    const auto alive = asSet(libsumo::Vehicle::getIDList());
    const auto arrived = asSet(libsumo::Simulation::getArrivedIDList());
    const auto colliding = asSet(libsumo::Simulation::getCollidingVehiclesIDList());
    const auto teleporting = asSet(libsumo::Simulation::getStartingTeleportIDList());
    std::vector<std::string> missing;
    for (const auto& id : expected) {
      if (!alive.count(id)) missing.push_back(id);
    }
    std::sort(missing.begin(), missing.end());
    for (const auto& id : missing) {
      Member& member = members[owner.at(id)];
      const std::string vehicle = id.substr(member.edge.size() + 1);
      fail(member, fmt::format("SUMO removed vehicle '{}' at t = {:.1f} s ({})", vehicle, time,
                               removalReason(id, arrived, colliding, teleporting)));
    }
  };

  const double setup_seconds = secondsSince(t_start) - load_seconds;
  session.step();  // inserts every vehicle at its start pose: t = 0
  checkRemovals(0.0);
  record(0);

  for (int k = 0; k < options.steps; ++k) {
    const double time = k * dt;
    reportSimulationTime(time);
    for (auto& member : members) {
      if (!member.active) continue;
      reportSubject(static_cast<std::int64_t>(member.result.index));
      const ActivityScope driving(Activity::SumoVehicles);
      if (faultInjectionActive()) {
        const ActivityScope in_controller(Activity::Controller);
        faultPoint(fmt::format("controller.step:{}", member.result.index));
      }
      // The Ego's sensors see the other road users where they are at instant k.
      std::vector<RoadUserState> road_users;
      for (std::size_t o = 0; o < member.otherIds.size(); ++o) {
        const auto& other = member.run->scenario->others[o];
        road_users.push_back({static_cast<int>(o) + 1, other.type, member.traffic->states()[o], other.length,
                              other.width});
      }
      // The others move on from instant k with the Ego where it is at k (triggers see it there).
      member.traffic->step(member.ego->state());
      try {
        member.ego->step(time, dt, member.run->scenario->ego.headingNoise[static_cast<std::size_t>(k)], lanes,
                         road_users);
      } catch (const ConfigError&) {
        throw;
      } catch (const Error& error) {
        fail(member, fmt::format("Ego controller failed at t = {:.1f} s: {}", time, error.what()));
        continue;
      }
      const auto& others = member.run->scenario->others;
      for (std::size_t o = 0; o < member.otherIds.size() && member.active; ++o) {
        if (member.traffic->pastRoadEnd(o)) {
          fail(member, fmt::format("vehicle '{}' reached the end of its road at t = {:.1f} s", others[o].id, time + dt));
          break;
        }
        // Placed every step, standing or not: left alone, SUMO would turn a standing road
        // user back along its lane.
        placeInSumo(member.otherIds[o], member.traffic->states()[o], others[o].length, others[o].width,
                    member.run->offset, member.placement);
      }
    }
    if (faultInjectionActive()) {
      for (const auto& member : members) {
        if (member.active) faultPoint(fmt::format("sumo.step-with:{}", member.result.index));
      }
    }
    reportSubject(-1);
    session.step();
    checkRemovals(time + dt);
    record(static_cast<std::size_t>(k) + 1);
  }

  const double step_seconds = secondsSince(t_start) - load_seconds - setup_seconds;
  spdlog::debug("simulateBatch: {} scenarios, load {:.3f} s, add vehicles {:.3f} s, {} steps {:.3f} s",
                members.size(), load_seconds, setup_seconds, options.steps, step_seconds);
  std::vector<SimulatedScenario> results;
  results.reserve(members.size());
  for (auto& member : members) {
    reportSubject(static_cast<std::int64_t>(member.result.index));
    member.ego.reset();  // a plugin's destroy() runs here, attributed to its scenario
    for (auto& track : member.result.trace.vehicles) fillAccelerationFromSpeed(track, dt);
    results.push_back(std::move(member.result));
  }
  return results;
}

}  // namespace vsd::sim
