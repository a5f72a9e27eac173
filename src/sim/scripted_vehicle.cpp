#include "vsd/sim/scripted_vehicle.hpp"

#include "vsd/sim/builtin_controllers.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/vehicle_model.hpp"

namespace vsd::sim {

std::vector<VehicleState> scriptedPath(const scenario::ConcreteVehicle& vehicle, const road::RoadGeometry& road,
                                       double step, int steps) {
  const auto start = road::startPoseOnLane(road, vehicle.lane, vehicle.x, vehicle.id);
  const MeasuredPolyline centre(road.laneCentre(vehicle.lane));
  // The script sets the speed at every instant; limits must not bend it. Curvature keeps
  // the Ego's bound, which lane keeping on the generated roads never reaches.
  VehicleLimits limits;
  limits.maxAccel = 1e6;
  limits.maxDecel = 1e6;
  const PurePursuitLateral lane_keeping;  // the Ego's defaults: lookahead max(4 m, 0.4 s * v)

  std::vector<VehicleState> path;
  path.reserve(static_cast<std::size_t>(steps) + 1);
  VehicleState state{start.position.x(), start.position.y(), start.heading, vehicle.scriptedSpeed.at(0), 0.0};
  path.push_back(state);
  for (int k = 0; k < steps; ++k) {
    const auto index = static_cast<std::size_t>(k);
    Observation observation;
    observation.ego = state;
    observation.lane = observeLane(centre, centre.project(state.position()), state, road.laneWidth);
    Command command;
    command.accel = (vehicle.scriptedSpeed.at(index + 1) - state.speed) / step;
    command.curvature = lane_keeping.curvature(observation);
    const double disturbance = index < vehicle.headingNoise.size() ? vehicle.headingNoise[index] : 0.0;
    state = advanceKinematic(state, command, step, disturbance, limits);
    path.push_back(state);
  }
  if (path.size() > 1) path[0].accel = path[1].accel;  // as fillAccelerationFromSpeed does for every track
  return path;
}

}  // namespace vsd::sim
