#include "vsd/sim/cut_in_harness.hpp"

#include <algorithm>
#include <cmath>

#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/vehicle_model.hpp"

namespace vsd::sim {

namespace {

/// The other vehicle at time t: on its lane's centre, then sideways at the lateral speed
/// until it is on the Ego's lane centre line (y = 0).
RoadUserState targetAt(const CutIn& cut_in, const RoadUserKind& kind, const RoadUserKind& ego, double t) {
  const double start_y = cut_in.fromLane * cut_in.laneWidth;
  const double moving = std::min(t, cut_in.laneWidth / cut_in.lateralSpeed);  // s spent moving sideways
  const double lateral_velocity = t < cut_in.laneWidth / cut_in.lateralSpeed ? -cut_in.fromLane * cut_in.lateralSpeed : 0.0;
  RoadUserState target;
  target.id = 1;
  target.type = cut_in.targetType;
  target.length = kind.length;
  target.width = kind.width;
  target.state.x = 0.5 * ego.length + cut_in.gap + 0.5 * kind.length + cut_in.targetSpeed * t;
  target.state.y = start_y - cut_in.fromLane * cut_in.lateralSpeed * moving;
  target.state.heading = std::atan2(lateral_velocity, cut_in.targetSpeed);
  target.state.speed = std::hypot(cut_in.targetSpeed, lateral_velocity);
  return target;
}

}  // namespace

double cutInTimeAtDeviation(const CutIn& cut_in, double deviation) { return deviation / cut_in.lateralSpeed; }

CutInOutcome simulateCutIn(EgoController& controller, const CutIn& cut_in, double decel_mark) {
  const RoadUserKind& ego_kind = roadUserKind(RoadUserType::Car);
  const RoadUserKind& target_kind = roadUserKind(cut_in.targetType);
  const MeasuredPolyline lane({{-1000.0, 0.0}, {5000.0, 0.0}});
  VehicleState ego{0.0, 0.0, 0.0, cut_in.egoSpeed, 0.0};
  CutInOutcome outcome;
  const auto steps = static_cast<int>(std::lround(cut_in.duration / cut_in.step));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * cut_in.step;
    const RoadUserState target = targetAt(cut_in, target_kind, ego_kind, t);
    const Footprint ego_box{ego.position(), ego.heading, ego_kind.length, ego_kind.width};
    const double clearance = footprintGap(ego_box, {target.state.position(), target.state.heading, target.length, target.width});
    outcome.minClearance = std::min(outcome.minClearance, clearance);
    if (clearance <= 0.0) {
      outcome.collision = true;
      outcome.collisionTime = t;
      outcome.impactSpeed = ego.speed * std::cos(ego.heading) - cut_in.targetSpeed;
      break;
    }
    if (k == steps) break;
    Observation observation;
    observation.time = t;
    observation.ego = ego;
    observation.egoLength = ego_kind.length;
    observation.egoWidth = ego_kind.width;
    observation.lane = observeLane(lane, lane.project(ego.position()), ego, cut_in.laneWidth);
    if (controller.observesObjects()) {
      observation.objects = observeObjects(lane, cut_in.laneWidth, ego_box, {target}, cut_in.sensor);
    }
    const Command command = controller.step(observation, cut_in.step);
    const double decel = -command.accel;
    if (decel > 1e-9 && std::isnan(outcome.brakeOnset)) outcome.brakeOnset = t;
    if (decel_mark > 0.0 && decel >= decel_mark - 1e-9 && std::isnan(outcome.decelMarkTime)) outcome.decelMarkTime = t;
    outcome.maxDecel = std::max(outcome.maxDecel, decel);
    ego = advanceKinematic(ego, command, cut_in.step, 0.0);
  }
  return outcome;
}

}  // namespace vsd::sim
