#pragma once
// Simulates many concrete scenarios that share one SUMO network in one libsumo
// simulation. The Co (and any other scripted vehicle) is a SUMO vehicle on its
// lane following its scripted speed (speed mode 0); the Ego is driven by its
// EgoController through the kinematic model and placed with moveToXY.
//
// Everything returned is in each scenario's own frame.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/controller.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace vsd::sim {

/// One scenario of a batch: what to simulate and where its road sits in the net.
struct ScenarioRun {
  const scenario::ConcreteScenario* scenario = nullptr;
  const road::RoadGeometry* road = nullptr;
  Vec2 offset = Vec2::Zero();  ///< net coordinates of the scenario frame's origin
  /// The road's lanes as SUMO loads them (scenario frame; road::NetworkBuilder::lanesAsLoaded)
  /// when known without asking SUMO; null or empty: asked from SUMO.
  const std::vector<LaneGeometry>* lanes = nullptr;
};

struct SimulatedScenario {
  std::uint64_t index = 0;
  Trace trace;                     ///< vehicles[0] = Ego, then the others in scenario order
  std::vector<LaneGeometry> lanes; ///< the road's lanes as SUMO built them (scenario frame)
  std::string failure;             ///< empty if the run completed; otherwise why it did not
  bool ok() const { return failure.empty(); }
};

struct BatchOptions {
  double step = 0.0;                     ///< s (> 0); no default: from the logical scenario
  int steps = 0;                         ///< recorded steps (>= 1); no default: from the logical scenario
  std::string collisionAction = "warn";  ///< SUMO --collision.action
  std::vector<std::string> sumoOptions;  ///< appended to SUMO's command line
  std::filesystem::path fcdOutput;       ///< SUMO FCD XML for this batch (empty: none)
  std::filesystem::path scenarioDir;     ///< base for relative controller library paths
  double egoStepCost = 0.0;              ///< s of extra wall time per Ego step (withStepCost; 0: none)
  /// A built-in controller (with its default parameters) to drive every Ego instead of the
  /// scenario's own, e.g. the reference driver of --reference. Empty: the scenario's.
  std::string egoControllerOverride;
  /// m, SUMO's --lateral-resolution (its sublane model; 0: off). With it SUMO places a road
  /// user across lanes where it is - half-way through a lane change it occupies both - so
  /// its leaders, collisions and SSM devices see what the metrics see.
  double lateralResolution = 0.0;
};

/// What a scenario asks of its Ego's controller (ControllerRegistry::require): to follow the
/// set speed its Ego's set_speed actions command, if it has any.
ControllerNeeds controllerNeeds(const scenario::LogicalScenario& logical);
/// What the controller of the Ego's controller action `handover` must honour: the scenario's
/// needs, less the set speed where it drives the lateral domain only.
ControllerNeeds controllerNeeds(const scenario::LogicalScenario& logical, const scenario::ActionSpec& handover);

/// Runs all `runs` in one simulation of `net`. Per-scenario faults (a vehicle
/// SUMO removes, a controller that fails) are recorded in `failure`; faults of
/// the whole batch (SUMO cannot load the net, an unknown controller) throw.
std::vector<SimulatedScenario> simulateBatch(const std::filesystem::path& net, const std::vector<ScenarioRun>& runs,
                                             ControllerRegistry& registry, const BatchOptions& options);

}  // namespace vsd::sim
