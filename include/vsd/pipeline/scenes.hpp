#pragma once
// Vectorized scenes of generated scenarios, from two sources that must agree:
//   - simulatedScene: what `run` stores in dataset.h5 — lanes as SUMO built them,
//     the Co as SUMO moved it, the Ego's simulated future as target;
//   - plannedScene: the same scene *before* simulating — lanes from the road
//     generator, the Co along its scripted path (the one the simulation places it
//     on), the Ego's initial vector; no target. This is what a
//     model sees for a scenario nobody has simulated (`vsd-sumo compare`).
// Both go through vector::buildScene, so their layout is identical; tests check
// that their vectors agree to millimetres.

#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::pipeline {

/// The scene `run` writes for a completed outcome (lanes clipped to the scenario region).
vector::VectorizedScene simulatedScene(const scenario::LogicalScenario& logical, const ScenarioOutcome& outcome);

/// The road's lanes as the generator builds them (centre over the whole edge, width).
std::vector<LaneGeometry> plannedLanes(const road::RoadGeometry& road);

/// Trace of a concrete scenario before simulation, in its scenario frame: the Ego valid
/// at t = 0 only (start pose on its lane, sampled speed); every other road user valid at
/// every instant, moved by the simulation's stepper (sim/scripted_vehicle.hpp) with the
/// Ego's stand-in - the Ego carrying on along its lane at its initial speed - wherever a
/// trigger relates to the Ego. Without such triggers these are exactly the paths the
/// simulation places them on. Throws ConfigError if a road user starts outside its road or
/// overlapping another (ScriptedTraffic's rule: two others may where one is let).
Trace plannedTrace(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road);

/// The scene of a concrete scenario before simulation (targets all invalid), with
/// its sample index and inputs set.
vector::VectorizedScene plannedScene(const scenario::ConcreteScenario& concrete);

/// Metrics of a scene's Ego moving along `future` (positions t_1..t_F in the scene frame,
/// valid where the scene's targetValid says; speeds and accelerations reconstructed from
/// positions, see core/trace.hpp), with the other vehicles as the scene holds them (their
/// sizes included) and the lane the Ego starts on. Scores predictions and recorded futures
/// with one code path.
std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const Polyline& future);

/// The same for a future that carries its own states at t_1..t_F (heading, speed and
/// acceleration, e.g. from the kinematic decoder): they are used as they are, nothing is
/// reconstructed from positions - a_min of such a prediction is the minimum of its
/// predicted accelerations.
std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const std::vector<VehicleState>& future);

/// A predicted future as a predictor returns it: its states when it carries them (kinematic
/// decoder, cv, ca), otherwise its positions (position-only decoders).
std::vector<double> metricsOfFuture(const metrics::MetricSet& metric_set, const vector::VectorizedScene& scene,
                                    const Polyline& positions, const std::vector<VehicleState>& states);

/// What metrics can rely on in scenes of a dataset of this kind ("generated" or "map").
metrics::Availability sceneAvailability(const std::string& dataset_kind);
/// What metrics can rely on in runs of a logical scenario (generated roads, its vehicles).
metrics::Availability scenarioAvailability(const scenario::LogicalScenario& logical);

}  // namespace vsd::pipeline
