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

/// SUMO's vehicle class of a road user (the road-user table's).
const char* sumoClassOf(RoadUserType type) { return roadUserKind(type).sumoClass; }

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
  std::string route;  ///< SUMO route over the scenario's edge
  std::string egoId;
  std::vector<std::string> otherIds;
  /// The scripted road users, stepped with the Ego: traffic->states() are every other road
  /// user's states at the current instant (their types and sizes: run->scenario->others).
  std::optional<ScriptedTraffic> traffic;
  std::optional<EgoDriver> ego;
  /// The Ego's controller actions (index into the concrete scenario's actions) -> their controller's slot in `ego`.
  std::map<std::size_t, std::size_t> controllerSlots;
  std::size_t controllersHandedOver = 0;  ///< the Ego's controller actions applied so far
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

namespace {

/// One SUMO simulation of a batch of concrete scenarios, each on its own edge: the Egos and
/// scripted road users are stepped here and placed in SUMO, which steps them all at once.
class BatchRun {
 public:
  /// Adds every scenario's vehicles to `session` (loaded with the batch's network).
  BatchRun(SumoSession& session, const std::vector<ScenarioRun>& runs, ControllerRegistry& registry,
           const BatchOptions& options)
      : session_(session), registry_(registry), options_(options), instants_(static_cast<std::size_t>(options.steps) + 1),
        matchToLanes_(sumoIgnoresLateralPositions()), members_(runs.size()) {
    for (std::size_t m = 0; m < runs.size(); ++m) addScenario(m, runs[m]);
  }

  /// t = 0: SUMO inserts every vehicle at its start pose.
  void start() {
    session_.step();
    checkRemovals(0.0);
    record(0);
  }

  /// From instant k to k + 1: every scenario's road users and Ego move, then SUMO steps.
  void step(int k) {
    const double time = k * options_.step;
    reportSimulationTime(time);
    for (auto& member : members_) {
      if (member.active) driveScenario(member, k, time);
    }
    if (faultInjectionActive()) {
      for (const auto& member : members_) {
        if (member.active) faultPoint(fmt::format("sumo.step-with:{}", member.result.index));
      }
    }
    reportSubject(-1);
    session_.step();
    checkRemovals(time + options_.step);
    record(static_cast<std::size_t>(k) + 1);
  }

  std::vector<SimulatedScenario> results() {
    std::vector<SimulatedScenario> results;
    results.reserve(members_.size());
    for (auto& member : members_) {
      reportSubject(static_cast<std::int64_t>(member.result.index));
      member.ego.reset();  // a plugin's destroy() runs here, attributed to its scenario
      for (auto& track : member.result.trace.vehicles) fillAccelerationFromSpeed(track, options_.step);
      results.push_back(std::move(member.result));
    }
    return results;
  }


 private:
  void addScenario(std::size_t m, const ScenarioRun& run) {
    Member& member = members_[m];
    const auto& concrete = *run.scenario;
    member.run = &run;
    member.result.index = concrete.index;
    reportSubject(static_cast<std::int64_t>(concrete.index));
    const ActivityScope adding(Activity::SumoVehicles);
    member.result.trace.step = options_.step;
    member.edge = road::edgeIdFor(concrete.index);
    member.route = "r" + member.edge;
    libsumo::Route::add(member.route, {member.edge});
    if (run.lanes != nullptr && !run.lanes->empty()) {
      member.result.lanes = *run.lanes;
      for (const auto& lane : member.result.lanes) lanes_.put(lane);
    } else {
      for (int lane = 0; lane < run.road->lanes; ++lane) {
        member.result.lanes.push_back(fetchLane(fmt::format("{}_{}", member.edge, lane), run.offset));
      }
    }
    if (matchToLanes_) member.placement = SumoPlacement(member.result.lanes);
    // The scripted road users start where the scenario puts them; the Ego on its lane's
    // centre line at its x or s, heading along the lane.
    member.traffic.emplace(concrete, *run.road);
    member.result.trace.vehicles.resize(1 + concrete.others.size());
    addEgo(m, member);
    addOthers(m, member);
  }

  /// The Ego's controller: the scenario's, or the one --reference names for every scenario.
  std::unique_ptr<EgoController> egoController(const scenario::ConcreteScenario& concrete) {
    const auto& spec = *concrete.logical;
    const bool overridden = !options_.egoControllerOverride.empty();
    const ControllerParams params(overridden ? std::vector<std::pair<std::string, double>>{} : concrete.controllerParams,
                                  overridden ? "--reference " + options_.egoControllerOverride : spec.ego.controller.where);
    const ControllerNeeds needs = controllerNeeds(spec);
    return withStepCost(
        overridden ? makeController(registry_, options_.egoControllerOverride, {}, options_.scenarioDir, params, needs)
                   : makeController(registry_, spec.ego.controller.name, spec.ego.controller.library,
                                    options_.scenarioDir, params, needs),
        options_.egoStepCost);
  }

  /// The controllers the scenario's controller actions hand the Ego to, one per action (made
  /// like its own controller). A --reference run keeps the reference driver throughout.
  void addSwitchedControllers(Member& member) {
    if (!options_.egoControllerOverride.empty()) return;
    const auto& concrete = *member.run->scenario;
    std::size_t ego_action = 0;  // the Ego's actions come last, in its spec's order
    const std::size_t first = concrete.actions.size() - concrete.logical->ego.actions.size();
    for (std::size_t a = first; a < concrete.actions.size(); ++a, ++ego_action) {
      const auto& action = concrete.actions[a];
      if (action.kind != scenario::ActionSpec::Kind::Controller) continue;
      const auto& handover = concrete.logical->ego.actions[ego_action];
      const auto& spec = handover.controller;
      const ControllerParams params(action.controllerParams, spec.where);
      member.controllerSlots[a] = member.ego->addController(withStepCost(
          makeController(registry_, spec.name, spec.library, options_.scenarioDir, params,
                         controllerNeeds(*concrete.logical, handover)),
          options_.egoStepCost));
    }
  }

  void addEgo(std::size_t m, Member& member) {
    const auto& ego_spec = member.run->scenario->ego;
    member.egoId = member.edge + "." + ego_spec.id;
    addSumoVehicle(member.egoId, member.route, ego_spec);
    member.ego.emplace(member.egoId, egoController(*member.run->scenario), member.traffic->egoStart(), ego_spec.length,
                       ego_spec.width, member.run->offset);
    member.ego->placeBy(member.placement);
    std::vector<double> lane_offsets;
    for (int lane = 0; lane < member.run->road->lanes; ++lane) {
      lane_offsets.push_back(member.run->road->laneOffset(lane));
    }
    member.ego->knowRoad(member.edge, std::move(lane_offsets));
    member.ego->activateFrom(member.run->scenario->controllerActiveFrom);
    addSwitchedControllers(member);
    member.ego->enterSumo(member.result.lanes);
    owner_.emplace(member.egoId, m);
    expected_.insert(member.egoId);
    initTrack(member.result.trace.vehicles[0], ego_spec, VehicleRole::Ego, instants_);
  }

  /// Scripted road users are placed where the stepper moves them, like the Ego, so SUMO and
  /// the Ego's sensors see them there.
  void addOthers(std::size_t m, Member& member) {
    const auto& others = member.run->scenario->others;
    std::vector<std::string> against_road;
    for (std::size_t o = 0; o < others.size(); ++o) {
      const auto& other = others[o];
      const std::string id = member.edge + "." + other.id;
      addSumoVehicle(id, member.route, other);
      enterSumo(id, member.traffic->states()[o], other.length, other.width, member.run->offset, member.placement,
                member.result.lanes, other.againstRoad);
      member.otherIds.push_back(id);
      owner_.emplace(id, m);
      expected_.insert(id);
      initTrack(member.result.trace.vehicles[1 + o], other, VehicleRole::Other, instants_);
      if (other.againstRoad) against_road.push_back(id);
    }
    if (!against_road.empty()) member.ego->knowAgainstRoad(std::move(against_road));
  }

  /// A vehicle SUMO neither drives nor changes lanes for: vsd-sumo places it every step.
  void addSumoVehicle(const std::string& id, const std::string& route, const scenario::ConcreteVehicle& vehicle) {
    libsumo::Vehicle::add(id, route, types_.get(vehicle), "now", std::to_string(vehicle.lane), "base",
                          fmt::format("{}", vehicle.speed));
    libsumo::Vehicle::setSpeedMode(id, 0);
    libsumo::Vehicle::setLaneChangeMode(id, 0);
  }

  /// The road users as the Ego's sensors see them at the current instant.
  static std::vector<RoadUserState> roadUsersOf(const Member& member) {
    std::vector<RoadUserState> road_users;
    const auto& others = member.run->scenario->others;
    for (std::size_t o = 0; o < member.otherIds.size(); ++o) {
      road_users.push_back(
          {static_cast<int>(o) + 1, others[o].type, member.traffic->states()[o], others[o].length, others[o].width});
    }
    return road_users;
  }

  void driveScenario(Member& member, int k, double time) {
    reportSubject(static_cast<std::int64_t>(member.result.index));
    const ActivityScope driving(Activity::SumoVehicles);
    if (faultInjectionActive()) {
      const ActivityScope in_controller(Activity::Controller);
      faultPoint(fmt::format("controller.step:{}", member.result.index));
    }
    // The Ego's sensors see the other road users where they are at instant k.
    const std::vector<RoadUserState> road_users = roadUsersOf(member);
    // The others move on from instant k with the Ego where it is at k (triggers see it there).
    member.traffic->step(member.ego->state());
    if (const auto& placed = member.traffic->egoTeleported()) member.ego->teleport(*placed, member.result.lanes);
    member.ego->commandSetSpeed(member.traffic->egoSetSpeedAt(time));
    member.ego->commandLaneOffset(member.traffic->egoLaneOffsetAt(time));
    if (!member.controllerSlots.empty()) {
      for (const std::size_t a : member.traffic->egoControllersStarted(time, member.controllersHandedOver)) {
        member.ego->useController(member.controllerSlots.at(a), time, member.run->scenario->actions[a].domains);
        ++member.controllersHandedOver;
      }
    }
    try {
      member.ego->step(time, options_.step, member.run->scenario->ego.headingNoise[static_cast<std::size_t>(k)], lanes_,
                       road_users);
    } catch (const ConfigError&) {
      throw;
    } catch (const Error& error) {
      fail(member, fmt::format("Ego controller failed at t = {:.1f} s: {}", time, error.what()));
      return;
    }
    placeOthers(member, time);
  }

  void placeOthers(Member& member, double time) {
    const auto& others = member.run->scenario->others;
    for (std::size_t o = 0; o < member.otherIds.size() && member.active; ++o) {
      if (member.traffic->pastRoadEnd(o)) {
        fail(member, fmt::format("vehicle '{}' reached the end of its road at t = {:.1f} s", others[o].id,
                                 time + options_.step));
        break;
      }
      // Placed every step, standing or not: left alone, SUMO would turn a standing road
      // user back along its lane.
      placeInSumo(member.otherIds[o], member.traffic->states()[o], others[o].length, others[o].width, member.run->offset,
                  member.placement, others[o].againstRoad);
    }
  }

  void record(std::size_t k) {
    for (auto& member : members_) {
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
  }

  void fail(Member& member, const std::string& reason) {
    if (!member.active) return;
    member.active = false;
    member.result.failure = reason;
    // Take the scenario's remaining vehicles out so they cannot affect anything else.
    std::vector<std::string> ids = member.otherIds;
    ids.push_back(member.egoId);
    const auto alive = asSet(libsumo::Vehicle::getIDList());
    for (const auto& id : ids) {
      if (alive.count(id)) libsumo::Vehicle::remove(id);
      expected_.erase(id);
    }
  }

  /// A vehicle SUMO removed (end of road, collision with action remove/teleport) fails its
  /// scenario; the others go on.
  void checkRemovals(double time) {
    if (static_cast<std::size_t>(libsumo::Vehicle::getIDCount()) == expected_.size()) return;
    const auto alive = asSet(libsumo::Vehicle::getIDList());
    const auto arrived = asSet(libsumo::Simulation::getArrivedIDList());
    const auto colliding = asSet(libsumo::Simulation::getCollidingVehiclesIDList());
    const auto teleporting = asSet(libsumo::Simulation::getStartingTeleportIDList());
    std::vector<std::string> missing;
    for (const auto& id : expected_) {
      if (!alive.count(id)) missing.push_back(id);
    }
    std::sort(missing.begin(), missing.end());
    for (const auto& id : missing) {
      Member& member = members_[owner_.at(id)];
      const std::string vehicle = id.substr(member.edge.size() + 1);
      fail(member, fmt::format("SUMO removed vehicle '{}' at t = {:.1f} s ({})", vehicle, time,
                               removalReason(id, arrived, colliding, teleporting)));
    }
  }

  SumoSession& session_;
  ControllerRegistry& registry_;
  const BatchOptions& options_;
  const std::size_t instants_;
  const bool matchToLanes_;
  VehicleTypes types_;
  LaneCache lanes_;
  std::vector<Member> members_;
  std::unordered_map<std::string, std::size_t> owner_;  // SUMO vehicle id -> member
  std::unordered_set<std::string> expected_;             // vehicles that should be in the simulation
};

}  // namespace

ControllerNeeds controllerNeeds(const scenario::LogicalScenario& logical) {
  ControllerNeeds needs;
  for (std::size_t a = 0; a < logical.ego.actions.size() && !needs.setSpeed; ++a) {
    const auto& action = logical.ego.actions[a];
    if (action.kind != scenario::ActionSpec::Kind::SetSpeed) continue;
    needs.setSpeed = true;
    needs.where = action.where;
    needs.field = "set_speed";
    needs.value = action.target.text();
  }
  return needs;
}

ControllerNeeds controllerNeeds(const scenario::LogicalScenario& logical, const scenario::ActionSpec& handover) {
  ControllerNeeds needs = controllerNeeds(logical);
  if (!drives(handover.domains, ControlDomains::Longitudinal)) needs.setSpeed = false;
  return needs;
}

std::vector<SimulatedScenario> simulateBatch(const std::filesystem::path& net, const std::vector<ScenarioRun>& runs,
                                             ControllerRegistry& registry, const BatchOptions& options) {
  if (!(options.step > 0.0) || options.steps < 1) {
    throw Error(fmt::format("internal: batch simulation with step {} s and {} steps", options.step, options.steps));
  }
  const auto t_start = std::chrono::steady_clock::now();
  // Outside the per-scenario parts, faults belong to the simulation as a whole.
  reportSubject(-1);
  reportSimulationTime(0.0);
  const ActivityScope whole_batch(Activity::SumoStep);
  SumoSession session(sessionArguments(net, options));
  const double load_seconds = secondsSince(t_start);
  BatchRun batch(session, runs, registry, options);
  const double setup_seconds = secondsSince(t_start) - load_seconds;
  batch.start();
  for (int k = 0; k < options.steps; ++k) batch.step(k);
  const double step_seconds = secondsSince(t_start) - load_seconds - setup_seconds;
  spdlog::debug("simulateBatch: {} scenarios, load {:.3f} s, add vehicles {:.3f} s, {} steps {:.3f} s", runs.size(),
                load_seconds, setup_seconds, options.steps, step_seconds);
  return batch.results();
}

}  // namespace vsd::sim
