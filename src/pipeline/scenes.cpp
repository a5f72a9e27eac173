#include "vsd/pipeline/scenes.hpp"

#include <cmath>

#include "vsd/sim/scripted_vehicle.hpp"
#include "vsd/vector/vectorize.hpp"

namespace vsd::pipeline {

namespace {

vector::VectorizedScene generatedScene(const scenario::LogicalScenario& logical, const std::vector<double>& inputs,
                                       const Trace& trace, const std::vector<LaneGeometry>& lanes) {
  const auto [x_min, x_max] = road::regionXRange(logical, inputs);
  return vector::buildScene(logical.name, trace, 0, vector::regionLanePolylines(lanes, x_min, x_max));
}

VehicleTrack emptyTrack(const scenario::ConcreteVehicle& vehicle, VehicleRole role, std::size_t instants) {
  VehicleTrack track;
  track.id = vehicle.id;
  track.role = role;
  track.length = vehicle.length;
  track.width = vehicle.width;
  track.type = vehicle.type;
  track.states.assign(instants, VehicleState{});
  track.valid.assign(instants, 0);
  return track;
}

}  // namespace

vector::VectorizedScene simulatedScene(const scenario::LogicalScenario& logical, const ScenarioOutcome& outcome) {
  auto scene = generatedScene(logical, outcome.inputs, outcome.trace, outcome.lanes);
  scene.sample = outcome.index;
  scene.inputs = outcome.inputs;
  scene.metrics = outcome.metrics;
  return scene;
}

std::vector<LaneGeometry> plannedLanes(const road::RoadGeometry& road) {
  std::vector<LaneGeometry> lanes;
  for (int lane = 0; lane < road.lanes; ++lane) {
    lanes.push_back({std::to_string(lane), road.laneCentre(lane), road.laneWidthOf(lane)});
  }
  return lanes;
}

Trace plannedTrace(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road) {
  const double dt = concrete.step();
  const auto instants = static_cast<std::size_t>(concrete.steps()) + 1;
  Trace trace;
  trace.step = dt;

  VehicleTrack ego = emptyTrack(concrete.ego, VehicleRole::Ego, instants);
  const road::LaneFrame frame(road.centre);
  const auto ego_start = road::roadUserStart(road, frame, concrete, concrete.ego, 0.0, 0.0);
  ego.states[0] = {ego_start.position.x(), ego_start.position.y(), ego_start.heading, concrete.ego.speed, 0.0};
  ego.valid[0] = 1;
  trace.vehicles.push_back(std::move(ego));

  // The paths the simulation moves them on, with the Ego's stand-in for the Ego (sim/scripted_vehicle.hpp).
  auto paths = sim::plannedPaths(concrete, road);
  for (std::size_t o = 0; o < concrete.others.size(); ++o) {
    VehicleTrack track = emptyTrack(concrete.others[o], VehicleRole::Other, instants);
    track.states = std::move(paths[o]);
    track.valid.assign(instants, 1);
    fillAccelerationFromSpeed(track, dt);
    trace.vehicles.push_back(std::move(track));
  }
  return trace;
}

vector::VectorizedScene plannedScene(const scenario::ConcreteScenario& concrete) {
  const auto road = road::buildRoadGeometry(concrete);
  auto scene = generatedScene(*concrete.logical, concrete.inputs, plannedTrace(concrete, road), plannedLanes(road));
  scene.sample = concrete.index;
  scene.inputs = concrete.inputs;
  return scene;
}

namespace {

/// The metrics of a trace of the scene's vehicles, with the scene's lanes as context (one
/// path for futures of positions and of states: the same lane offsets on maps for both).
std::vector<double> metricsOfSceneTrace(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                        const Trace& trace) {
  const Polyline lane = vector::egoLaneCentre(scene);
  const std::vector<Polyline> boundaries = vector::laneBoundaryLines(scene);
  return metric_set.evaluate({trace, lane, &boundaries});
}

}  // namespace

std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const Polyline& future) {
  return metricsOfSceneTrace(metric_set, scene, vector::sceneTrace(scene, future));
}

metrics::Availability sceneAvailability(const std::string& dataset_kind) {
  // Other vehicles may or may not be in a given scene; metrics that need them yield NaN there.
  const bool generated = dataset_kind == "generated";
  return {/*otherVehicles=*/true, /*egoLane=*/generated, /*scenarioFrame=*/generated};
}

metrics::Availability scenarioAvailability(const scenario::LogicalScenario& logical) {
  return {/*otherVehicles=*/!logical.others.empty(), /*egoLane=*/true, /*scenarioFrame=*/true};
}

std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const std::vector<VehicleState>& future) {
  Polyline positions;
  positions.reserve(future.size());
  for (const auto& state : future) positions.push_back(state.position());
  Trace trace = vector::sceneTrace(scene, positions);
  auto& ego = trace.vehicles.front().states;
  for (std::size_t k = 0; k < future.size() && k + 1 < ego.size(); ++k) ego[k + 1] = future[k];
  if (!future.empty()) ego[0].accel = future.front().accel;  // a_0 = a_1, as for every recorded track
  return metricsOfSceneTrace(metric_set, scene, trace);
}

std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const Polyline& positions, const std::vector<VehicleState>& states) {
  return states.empty() ? metricsOfFuture(metric_set, scene, positions) : metricsOfFuture(metric_set, scene, states);
}

}  // namespace vsd::pipeline
