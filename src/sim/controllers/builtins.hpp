#pragma once
// The built-in Ego controllers register themselves through these functions, one per file
// of this folder; registry.cpp calls them all (its comment lists every built-in).

#include "vsd/sim/controller.hpp"

namespace vsd::sim {

/// paper_ego.cpp: `paper_ego` and `time_gap_p`.
void registerPaperEgo(ControllerRegistry& registry);
/// idm.cpp: `idm`.
void registerIdm(ControllerRegistry& registry);
/// alks.cpp: `alks`.
void registerAlks(ControllerRegistry& registry);
/// r157_reference_driver.cpp: `r157_reference_driver`.
void registerR157ReferenceDriver(ControllerRegistry& registry);
/// fuzzy_safety_model.cpp: `fsm`.
void registerFuzzySafetyModel(ControllerRegistry& registry);
/// keep_lane.cpp: `keep_lane`.
void registerKeepLane(ControllerRegistry& registry);

}  // namespace vsd::sim
