// `keep_lane`: the Ego while no controller of its own drives it. It keeps its speed and
// follows the lane it keeps by pure pursuit (the Ego's default lane keeping) - what the Ego
// does before its controller's active_from. A controller action hands the Ego (or one of its
// domains) to it: OpenSCENARIO's ActivateControllerAction that switches a domain off, and the
// Ego's hand-overs to a controller that follows the script (esmini's default controller).

#include <memory>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

class KeepLaneController : public EgoController {
 public:
  void init(const ControllerParams& params) override { lateral_.init(params); }
  void reset() override {}
  Command step(const Observation& observation, double /*dt*/) override {
    return {0.0, lateral_.curvature(observation)};
  }

 private:
  PurePursuitLateral lateral_;
};

}  // namespace

void registerKeepLane(ControllerRegistry& registry) {
  registry.add("keep_lane", "keeps its speed and its lane (pure pursuit): the Ego before its controller drives",
               [] { return std::make_unique<KeepLaneController>(); });
}

}  // namespace vsd::sim
