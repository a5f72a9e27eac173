#include "vsd/sim/map_simulation.hpp"

#include <fmt/format.h>
#include <libsumo/libsumo.h>

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace fs = std::filesystem;

namespace vsd::sim {

namespace {
void requireFile(const fs::path& path, const std::string& what) {
  if (path.empty()) return;
  if (!fs::is_regular_file(path)) throw ConfigError(fmt::format("{} '{}' does not exist", what, path.string()));
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

  Impl(const MapSimulationOptions& options) : session(mapSimulationArguments(options)), step(options.step) {
    const double map_end = libsumo::Simulation::getEndTime();
    if (options.end) end = options.end;
    else if (map_end >= 0.0) end = map_end;
  }
};

MapSimulation::MapSimulation(const MapSimulationOptions& options) : impl_(std::make_unique<Impl>(options)) {}

MapSimulation::~MapSimulation() {
  drivers_.clear();  // before the session closes: drivers talk to SUMO
}

std::vector<LaneGeometry> MapSimulation::lanes() const {
  std::vector<LaneGeometry> result;
  for (const auto& id : libsumo::Lane::getIDList()) result.push_back(fetchLane(id, Vec2::Zero()));
  return result;
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
