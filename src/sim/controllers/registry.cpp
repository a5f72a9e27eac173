// The registry of built-in Ego controllers, one file each in this folder:
//   paper_ego, time_gap_p  paper_ego.cpp  the paper's time-gap P-controller (+ parts) and the plain one
//   idm                    idm.cpp        Intelligent Driver Model
// Their shared parts (lane keeping, time-gap following) are in lane_keeping.cpp and
// time_gap.cpp (declared in vsd/sim/builtin_controllers.hpp).

#include "builtins.hpp"

namespace vsd::sim {

ControllerRegistry ControllerRegistry::withBuiltins() {
  ControllerRegistry registry;
  registerPaperEgo(registry);
  registerIdm(registry);
  return registry;
}

}  // namespace vsd::sim
