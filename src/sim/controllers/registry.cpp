// The registry of built-in Ego controllers, one file each in this folder:
//   paper_ego, time_gap_p  paper_ego.cpp              the paper's time-gap P-controller (+ parts) and the plain one
//   idm                    idm.cpp                    Intelligent Driver Model
//   alks                   alks.cpp                   an ALKS-like system under test (UN R157 time gap, object list)
//   r157_reference_driver  r157_reference_driver.cpp  UN R157's competent and careful human driver
//   fsm                    fuzzy_safety_model.cpp     the Fuzzy Safety Model (Mattas et al. 2022)
//   keep_lane              keep_lane.cpp              keeps its speed and lane (the Ego before its controller drives)
// Their shared parts (lane keeping, time-gap following) are in lane_keeping.cpp and
// time_gap.cpp (declared in vsd/sim/builtin_controllers.hpp).

#include "builtins.hpp"

namespace vsd::sim {

ControllerRegistry ControllerRegistry::withBuiltins() {
  ControllerRegistry registry;
  registerPaperEgo(registry);
  registerIdm(registry);
  registerAlks(registry);
  registerR157ReferenceDriver(registry);
  registerFuzzySafetyModel(registry);
  registerKeepLane(registry);
  return registry;
}

}  // namespace vsd::sim
