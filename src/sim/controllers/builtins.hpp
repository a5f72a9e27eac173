#pragma once
// The built-in Ego controllers register themselves through these functions, one per file
// of this folder; registry.cpp calls them all (its comment lists every built-in).

#include "vsd/sim/controller.hpp"

namespace vsd::sim {

/// paper_ego.cpp: `paper_ego` and `time_gap_p`.
void registerPaperEgo(ControllerRegistry& registry);
/// idm.cpp: `idm`.
void registerIdm(ControllerRegistry& registry);

}  // namespace vsd::sim
