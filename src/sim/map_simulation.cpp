#include "vsd/sim/map_simulation.hpp"

#include <fmt/format.h>
#include <libsumo/libsumo.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/svg.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace fs = std::filesystem;

namespace vsd::sim {

namespace {
void requireFile(const fs::path& path, const std::string& what) {
  if (path.empty()) return;
  if (!fs::is_regular_file(path)) throw ConfigError(fmt::format("{} '{}' does not exist", what, path.string()));
}

/// A route of this many edges is long enough for any scenario (and ends a loop-free search).
constexpr std::size_t kMaxRouteEdges = 10'000;
/// m/s: a placed road user's top speed (its type's maxSpeed) unless it starts faster.
constexpr double kMaxPlacedSpeed = 70.0;
/// TraCI lane-change mode: strategic changes (those its route needs) only, nothing else.
constexpr int kStrategicChangesOnly = 0b01;

/// How far a connection of SUMO's (its `dir`) turns off the road: straight on first, then
/// partial turns, then turns; a turn back (or anything else) never continues a road.
int turnRank(const std::string& direction) {
  if (direction == "s") return 0;
  if (direction == "L" || direction == "R") return 1;
  if (direction == "l" || direction == "r") return 2;
  return -1;
}

/// The connection onward from `lane` that turns least (first of equals), or none.
std::optional<libsumo::TraCIConnection> straightestLink(const std::string& lane) {
  std::optional<libsumo::TraCIConnection> best;
  for (const auto& link : libsumo::Lane::getLinks(lane)) {
    const int rank = turnRank(link.direction);
    if (rank >= 0 && (!best || rank < turnRank(best->direction))) best = link;
  }
  return best;
}

/// Edges from `lane`'s edge on along the road: the straightest connection of the lane, else of
/// its edge's other lanes, until a dead end, an edge already passed or kMaxRouteEdges.
std::vector<std::string> roadAhead(const std::string& lane) {
  std::vector<std::string> edges{libsumo::Lane::getEdgeID(lane)};
  std::unordered_set<std::string> passed(edges.begin(), edges.end());
  std::string current = lane;
  while (edges.size() < kMaxRouteEdges) {
    auto link = straightestLink(current);
    const std::string edge = libsumo::Lane::getEdgeID(current);
    for (int i = 0; !link && i < libsumo::Edge::getLaneNumber(edge); ++i) {
      link = straightestLink(fmt::format("{}_{}", edge, i));
    }
    if (!link) break;
    const std::string next = libsumo::Lane::getEdgeID(link->approachedLane);
    if (!passed.insert(next).second) break;
    edges.push_back(next);
    current = link->approachedLane;
  }
  return edges;
}

/// rad: the direction of `lane` at `pos` m along it.
double laneHeading(const std::string& edge, int lane, double pos, double lane_length) {
  const double a = std::clamp(pos - 0.5, 0.0, lane_length);
  const double b = std::clamp(pos + 0.5, 0.0, lane_length);
  const auto p = libsumo::Simulation::convert2D(edge, a, lane);
  const auto q = libsumo::Simulation::convert2D(edge, b, lane);
  return std::atan2(q.y - p.y, q.x - p.x);
}

/// Where SUMO is to insert a placed road user: its lane and route.
struct Placement {
  int laneIndex = 0;
  double front = 0.0;  ///< m along the lane of its front (SUMO places vehicles by it)
  std::vector<std::string> route;
};

/// ConfigError "WHERE: road user 'ID' at (X, Y) WHY".
[[noreturn]] void refusePlacement(const PlacedRoadUser& user, const std::string& why) {
  throw ConfigError(fmt::format("{}: road user '{}' at ({:.2f}, {:.2f}) {}", user.where, user.id, user.centre.x(),
                                user.centre.y(), why));
}

/// `user`'s lane (in the loaded network) and route, or ConfigError naming its `where`.
Placement placementOf(const PlacedRoadUser& user) {
  const auto fail = [&](const std::string& why) { refusePlacement(user, why); };
  libsumo::TraCIRoadPosition at;
  try {
    at = libsumo::Simulation::convertRoad(user.centre.x(), user.centre.y(), false, user.vehicleClass);
  } catch (const libsumo::TraCIException&) {
    at = {};  // SUMO finds no lane near it that its class may use
  }
  if (at.edgeID.empty()) fail(fmt::format("lies on no lane of the network that a {} may use", user.vehicleClass));
  if (at.edgeID.front() == ':') fail(fmt::format("lies inside a junction (lane {}_{})", at.edgeID, at.laneIndex));
  const std::string lane = fmt::format("{}_{}", at.edgeID, at.laneIndex);
  const auto foot = libsumo::Simulation::convert2D(at.edgeID, at.pos, at.laneIndex);
  const double off = (Vec2(foot.x, foot.y) - user.centre).norm();
  if (off > PlacedRoadUser::kMaxPlacementOffset) {
    fail(fmt::format("lies {:.2f} m beside the centre line of its lane {} (road users start on it: at most {} m off)",
                     off, lane, PlacedRoadUser::kMaxPlacementOffset));
  }
  const double lane_length = libsumo::Lane::getLength(lane);
  const double turn = std::abs(wrapAngle(user.heading - laneHeading(at.edgeID, at.laneIndex, at.pos, lane_length)));
  if (turn > 0.5 * kPi) {
    fail(fmt::format("faces against the direction of its lane {} ({:.0f} degrees off)", lane, turn * 180.0 / kPi));
  }
  const double front = at.pos + 0.5 * user.length;
  if (front > lane_length + 1e-6) {
    fail(fmt::format("reaches beyond the end of its lane {} ({:.2f} m long; its front at {:.2f} m)", lane, lane_length,
                     front));
  }
  return {at.laneIndex, front, roadAhead(lane)};
}

/// The placed road users as SUMO route-file XML: each its own type, route and vehicle, departing
/// at `begin` without SUMO's insertion checks (a scenario places them where it wants them).
std::string placedRoadUsersXml(const std::vector<PlacedRoadUser>& users, double begin) {
  std::string xml = "<additional>\n";
  for (const auto& user : users) {
    const Placement placement = placementOf(user);
    const std::string id = escapeXml(user.id);
    // Its class's default top speed (a bus: 85 km/h) must not refuse the speed the scenario gives it.
    xml += fmt::format("  <vType id=\"vsd_type_{}\" length=\"{}\" width=\"{}\" vClass=\"{}\" maxSpeed=\"{}\"/>\n", id,
                       user.length, user.width, escapeXml(user.vehicleClass), std::max(user.speed, kMaxPlacedSpeed));
    const std::string edges = escapeXml(fmt::format("{}", fmt::join(placement.route, " ")));
    xml += fmt::format("  <route id=\"vsd_route_{}\" edges=\"{}\"/>\n", id, edges);
    xml += fmt::format("  <vehicle id=\"{0}\" type=\"vsd_type_{0}\" route=\"vsd_route_{0}\" depart=\"{1}\" "
                       "departLane=\"{2}\" departPos=\"{3:.3f}\" departSpeed=\"{4}\" insertionChecks=\"none\"/>\n",
                       id, begin, placement.laneIndex, placement.front, user.speed);
  }
  return xml + "</additional>\n";
}

/// The SUMO arguments of `options` with its placed road users written into `work` as an
/// additional file (their lanes and routes found in a first, planning load of the map).
std::vector<std::string> argumentsWithPlaced(const MapSimulationOptions& options, const fs::path& work) {
  auto args = mapSimulationArguments(options);
  if (options.placed.empty()) return args;
  for (const auto& option : options.source.sumoOptions) {
    if (option == "--additional-files") throw Error("internal: placed road users with --additional-files of its own");
  }
  std::vector<std::string> additional;
  {
    const SumoSession planning(args);
    const std::string xml = placedRoadUsersXml(options.placed, libsumo::Simulation::getTime());
    writeTextFileAtomically(work / "placed.add.xml", xml);
    // A configuration's own additional files, as SUMO resolved them (relative to it).
    std::stringstream given(libsumo::Simulation::getOption("additional-files"));
    for (std::string file; std::getline(given, file, ',');) {
      if (!file.empty()) additional.push_back(file);
    }
  }
  additional.push_back((work / "placed.add.xml").string());
  args.insert(args.end(), {"--additional-files", fmt::format("{}", fmt::join(additional, ","))});
  // Scripted road users move as scripted, through whatever is in their way (as in the scenario
  // language); SUMO would take colliding vehicles out of the simulation.
  args.insert(args.end(), {"--collision.action", "none"});
  return args;
}
}  // namespace

std::vector<std::string> mapSimulationArguments(const MapSimulationOptions& options) {
  if (!(options.step > 0.0)) throw Error(fmt::format("internal: map simulation with step {} s", options.step));
  const auto& source = options.source;
  requireFile(source.config, "SUMO configuration");
  requireFile(source.net, "SUMO network");
  for (const auto& route : source.routes) requireFile(route, "route file");
  if (source.config.empty() && source.net.empty()) throw ConfigError("no map given (a .sumocfg, or a network)");
  std::vector<std::string> args;
  if (!source.config.empty()) {
    args = {"--configuration-file", source.config.string()};
  } else {
    args = {"--net-file", source.net.string()};
    if (!source.routes.empty()) {
      std::string routes;
      for (const auto& route : source.routes) routes += (routes.empty() ? "" : ",") + route.string();
      args.insert(args.end(), {"--route-files", routes});
    }
  }
  args.insert(args.end(), {"--step-length", fmt::format("{}", options.step), "--seed", std::to_string(options.seed),
                           "--xml-validation", "never", "--xml-validation.net", "never"});
  if (options.laneChangeDuration > 0.0) {
    args.insert(args.end(), {"--lanechange.duration", fmt::format("{}", options.laneChangeDuration)});
  }
  if (options.begin) args.insert(args.end(), {"--begin", fmt::format("{}", *options.begin)});
  if (options.end) args.insert(args.end(), {"--end", fmt::format("{}", *options.end)});
  args.insert(args.end(), source.sumoOptions.begin(), source.sumoOptions.end());
  return args;
}

struct MapSimulation::Impl {
  SumoSession session;
  double step;
  std::optional<double> end;
  LaneCache lanes;
  struct Dimensions {
    double length;
    double width;
    std::string type;
  };
  std::unordered_map<std::string, Dimensions> dimensions;
  /// Placed road users not yet seen departing (checked after the first step).
  std::vector<PlacedRoadUser> placing;

  Impl(const MapSimulationOptions& options, const fs::path& work)
      : session(argumentsWithPlaced(options, work)), step(options.step), placing(options.placed) {
    const double map_end = libsumo::Simulation::getEndTime();
    if (options.end) end = options.end;
    else if (map_end >= 0.0) end = map_end;
    for (const auto& user : placing) {
      if (!user.holdsSpeed) continue;
      libsumo::Vehicle::setSpeedMode(user.id, 0);
      // Only the changes its route needs: off a lane that ends, onto the lane that goes on.
      libsumo::Vehicle::setLaneChangeMode(user.id, kStrategicChangesOnly);
      libsumo::Vehicle::setSpeed(user.id, user.speed);
    }
  }

  /// After the first step: every placed road user departed (inserted without SUMO's checks, so at its place).
  void checkPlaced(const std::vector<std::string>& present) {
    const std::unordered_set<std::string> ids(present.begin(), present.end());
    for (const auto& user : placing) {
      if (ids.count(user.id)) continue;
      throw ConfigError(fmt::format("{}: road user '{}' could not start where it is placed (SUMO did not insert it "
                                    "at the first step)",
                                    user.where, user.id));
    }
    placing.clear();
  }
};

MapSimulation::MapSimulation(const MapSimulationOptions& options) {
  if (!options.placed.empty() && options.workDir.empty()) {
    placedFiles_ = std::make_unique<TemporaryDirectory>("vsd-placed");
  }
  impl_ = std::make_unique<Impl>(options, placedFiles_ ? placedFiles_->path() : options.workDir);
}

MapSimulation::~MapSimulation() {
  drivers_.clear();  // before the session closes: drivers talk to SUMO
}

std::vector<LaneGeometry> MapSimulation::lanes() const {
  std::vector<LaneGeometry> result;
  for (const auto& id : libsumo::Lane::getIDList()) result.push_back(fetchLane(id, Vec2::Zero()));
  return result;
}

const VehicleSnapshot* MapSimulation::vehicle(const std::string& id) const {
  const auto found = std::find_if(vehicles_.begin(), vehicles_.end(), [&](const auto& v) { return v.id == id; });
  return found == vehicles_.end() ? nullptr : &*found;
}

double MapSimulation::time() const { return impl_->session.time(); }

std::optional<double> MapSimulation::endTime() const { return impl_->end; }

void MapSimulation::takeOver(const std::string& id, std::unique_ptr<EgoController> controller) {
  for (const auto& vehicle : vehicles_) {
    if (vehicle.id != id) continue;
    libsumo::Vehicle::setSpeedMode(id, 0);
    libsumo::Vehicle::setLaneChangeMode(id, 0);
    drivers_[id] = std::make_unique<EgoDriver>(id, std::move(controller), vehicle.state, vehicle.length, vehicle.width,
                                               Vec2::Zero());
    return;
  }
  throw Error(fmt::format("internal: takeOver of vehicle '{}', which is not in the network", id));
}

void MapSimulation::failEgo(const std::string& id, const std::string& reason) {
  reportSubject(-1, id);
  const ActivityScope removing(Activity::SumoVehicles);
  failures_.push_back({id, time(), reason});
  drivers_.erase(id);  // a plugin's destroy() runs here
  for (const auto& present : libsumo::Vehicle::getIDList()) {
    if (present == id) libsumo::Vehicle::remove(id);
  }
}

void MapSimulation::scheduleFailure(const std::string& id, double time, std::string reason) {
  scheduled_.push_back({id, time, std::move(reason)});
}

std::optional<std::string> MapSimulation::scheduledFailure(const std::string& id) const {
  const double now = time();
  for (const auto& failure : scheduled_) {
    if (failure.id == id && std::abs(failure.time - now) < 1e-6) return failure.reason;
  }
  return std::nullopt;
}

void MapSimulation::driveEgos(double now) {
  reportSimulationTime(now);
  std::vector<std::pair<std::string, std::string>> failed;
  for (auto& [id, driver] : drivers_) {
    if (auto reason = scheduledFailure(id)) {
      failed.emplace_back(id, *reason);
      continue;
    }
    reportSubject(-1, id);
    const ActivityScope driving(Activity::SumoVehicles);
    if (faultInjectionActive()) {
      const ActivityScope in_controller(Activity::Controller);
      faultPoint("controller.step:" + id);
    }
    try {
      driver->step(now, impl_->step, 0.0, impl_->lanes);
    } catch (const ConfigError&) {
      throw;
    } catch (const Error& error) {
      failed.emplace_back(id, fmt::format("Ego controller failed at t = {:.1f} s: {}", now, error.what()));
    }
  }
  // In id order: the same failures are recorded in the same order however the map iterates.
  std::sort(failed.begin(), failed.end());
  for (const auto& [id, reason] : failed) failEgo(id, reason);
  reportSubject(-1);
}

bool MapSimulation::step() {
  const double now = time();
  if (impl_->end && now + 0.5 * impl_->step >= *impl_->end) return false;
  if (libsumo::Simulation::getMinExpectedNumber() <= 0) return false;
  // libsumo's work of the whole step is watched, with the Egos' parts attributed to them.
  const ActivityScope stepping(Activity::SumoStep);
  // Closed-loop Egos decide before SUMO moves everybody else.
  driveEgos(now);
  impl_->session.step();
  releaseFinishedDrivers();

  const auto ids = libsumo::Vehicle::getIDList();
  if (!impl_->placing.empty()) impl_->checkPlaced(ids);
  vehicles_.clear();
  vehicles_.reserve(ids.size());
  for (const auto& id : ids) {
    auto dims = impl_->dimensions.find(id);
    if (dims == impl_->dimensions.end()) {
      dims = impl_->dimensions
                 .emplace(id, Impl::Dimensions{libsumo::Vehicle::getLength(id), libsumo::Vehicle::getWidth(id),
                                               libsumo::Vehicle::getTypeID(id)})
                 .first;
    }
    VehicleSnapshot snapshot;
    snapshot.id = id;
    snapshot.length = dims->second.length;
    snapshot.width = dims->second.width;
    snapshot.type = dims->second.type;
    const auto driver = drivers_.find(id);
    if (driver != drivers_.end()) {
      snapshot.state = driver->second->state();
    } else {
      // getStopState: bit 0 stopped, bit 1 parking (TraCI's documented layout).
      snapshot.parked = (libsumo::Vehicle::getStopState(id) & 2) != 0;
      const auto front = libsumo::Vehicle::getPosition(id);
      const double heading = headingFromSumoAngle(libsumo::Vehicle::getAngle(id));
      const Vec2 centre = Vec2(front.x, front.y) - 0.5 * snapshot.length * headingVector(heading);
      snapshot.state = {centre.x(), centre.y(), heading, libsumo::Vehicle::getSpeed(id), 0.0};
    }
    vehicles_.push_back(std::move(snapshot));
  }
  if (!drivers_.empty() || impl_->dimensions.size() > 2 * ids.size() + 1000) {
    const std::unordered_set<std::string> present(ids.begin(), ids.end());
    // Controlled vehicles that SUMO removed for its own reasons (e.g. a collision) are released.
    for (auto it = drivers_.begin(); it != drivers_.end();) {
      it = present.count(it->first) ? std::next(it) : drivers_.erase(it);
    }
    // Dimensions of vehicles that left are forgotten once they outnumber the present ones.
    if (impl_->dimensions.size() > 2 * ids.size() + 1000) {
      for (auto it = impl_->dimensions.begin(); it != impl_->dimensions.end();) {
        it = present.count(it->first) ? std::next(it) : impl_->dimensions.erase(it);
      }
    }
  }
  return true;
}

void MapSimulation::releaseFinishedDrivers() {
  // A remote-controlled vehicle never "arrives" by itself: at the end of its route,
  // or once it has left the road, it is taken out as arrived.
  for (auto it = drivers_.begin(); it != drivers_.end();) {
    const std::string& id = it->first;
    const std::string lane = libsumo::Vehicle::getLaneID(id);
    bool finished = lane.empty();
    if (!finished && libsumo::Vehicle::getRouteIndex(id) + 1 >= static_cast<int>(libsumo::Vehicle::getRoute(id).size()) &&
        lane.front() != ':') {
      finished = libsumo::Vehicle::getLanePosition(id) >= libsumo::Lane::getLength(lane) - 1.0;
    }
    if (finished) {
      libsumo::Vehicle::remove(id, libsumo::REMOVE_ARRIVED);
      it = drivers_.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<std::string> MapSimulation::listDepartures(const MapSimulationOptions& options) {
  SumoSession session(mapSimulationArguments(options));
  std::optional<double> end = options.end;
  if (!end && libsumo::Simulation::getEndTime() >= 0.0) end = libsumo::Simulation::getEndTime();
  std::vector<std::string> departed;
  while (libsumo::Simulation::getMinExpectedNumber() > 0 && (!end || session.time() + 0.5 * options.step < *end)) {
    session.step();
    const auto ids = libsumo::Simulation::getDepartedIDList();
    departed.insert(departed.end(), ids.begin(), ids.end());
  }
  return departed;
}

}  // namespace vsd::sim
