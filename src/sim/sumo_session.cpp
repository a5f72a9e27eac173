#include "vsd/sim/sumo_session.hpp"

#include <fmt/format.h>
#include <libsumo/libsumo.h>

#include "vsd/core/activity.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/road/network.hpp"

namespace vsd::sim {

namespace {
// libsumo's simulation is process-global; this mirrors that fact (it is not a registry).
bool g_session_open = false;
}  // namespace

SumoSession::SumoSession(const std::vector<std::string>& arguments) {
  if (g_session_open) throw SumoError("internal: a libsumo simulation is already open in this process");
  road::ensureSumoHome();
  std::vector<std::string> args = {"--no-step-log", "true", "--duration-log.disable", "true", "--no-warnings", "true",
                                   "--verbose", "false"};
  args.insert(args.end(), arguments.begin(), arguments.end());
  faultPoint("sumo.load");
  const ActivityScope loading(Activity::SumoLoad);
  try {
    libsumo::Simulation::load(args);
  } catch (const std::exception& error) {
    throw SumoError(fmt::format("SUMO could not load the simulation ({}): {}", fmt::join(arguments, " "), error.what()));
  }
  if (!libsumo::Simulation::isLoaded()) {
    throw SumoError(fmt::format("SUMO could not load the simulation ({})", fmt::join(arguments, " ")));
  }
  open_ = true;
  g_session_open = true;
}

SumoSession::~SumoSession() {
  if (!open_) return;
  try {
    libsumo::Simulation::close();
  } catch (const std::exception&) {
    // Closing must not throw from a destructor; SUMO reports nothing useful here.
  }
  g_session_open = false;
}

void SumoSession::step() {
  faultPoint("sumo.step");
  const ActivityScope stepping(Activity::SumoStep);
  try {
    libsumo::Simulation::step();
  } catch (const std::exception& error) {
    throw SumoError(fmt::format("SUMO failed at t = {} s: {}", time(), error.what()));
  }
}

double SumoSession::time() const { return libsumo::Simulation::getTime(); }

std::string SumoSession::version() { return libsumo::Simulation::getVersion().second; }

LaneGeometry fetchLane(const std::string& lane_id, const Vec2& offset) {
  LaneGeometry lane;
  lane.id = lane_id;
  const auto shape = libsumo::Lane::getShape(lane_id);
  lane.centre.reserve(shape.value.size());
  for (const auto& point : shape.value) lane.centre.emplace_back(point.x - offset.x(), point.y - offset.y());
  lane.width = libsumo::Lane::getWidth(lane_id);
  return lane;
}

}  // namespace vsd::sim
