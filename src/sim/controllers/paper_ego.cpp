// `paper_ego` and `time_gap_p`: the paper's Ego - a time-gap car follower
// (TimeGapLongitudinal) with pure-pursuit lane keeping (PurePursuitLateral).
//   `paper_ego`:  every part on (P-term, relative-speed term, cruise cap, emergency brake);
//   `time_gap_p`: the plain time-gap P-controller the paper names (every extra part off).
// The lead is SUMO's leader unless `leader_from_objects: 1` (LeaderChoice): reading it from
// the object list changes the paper's scenarios' numbers (the gap along the Ego's lane centre
// line instead of SUMO's lane positions), so the paper's outputs keep SUMO's.

#include <string>
#include <utility>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

namespace {

class PaperEgoController final : public EgoController {
 public:
  PaperEgoController(std::string name, TimeGapLongitudinal::Parts parts) : name_(std::move(name)), longitudinal_(parts) {}

  void init(const ControllerParams& params) override {
    longitudinal_.init(params);
    lateral_.init(params);
    leader_.init(params);
    params.rejectUnknown(name_);
  }

  void reset() override { longitudinal_.reset(); }

  bool observesObjects() const override { return leader_.fromObjects(); }
  bool followsSetSpeed() const override { return true; }

  Command step(const Observation& observation, double /*dt*/) override {
    return {longitudinal_.accel(observation, leader_.leader(observation)), lateral_.curvature(observation)};
  }

 private:
  std::string name_;
  LeaderChoice leader_;
  TimeGapLongitudinal longitudinal_;
  PurePursuitLateral lateral_;
};

}  // namespace

void registerPaperEgo(ControllerRegistry& registry) {
  registry.add("paper_ego",
               "time-gap P-term + relative-speed term, cruise cap and emergency brake (each switchable) + "
               "pure-pursuit lane keeping",
               [] { return std::make_unique<PaperEgoController>("paper_ego", TimeGapLongitudinal::Parts{true, true, true}); });
  registry.add("time_gap_p", "plain time-gap P-controller (the paper's description) + pure-pursuit lane keeping",
               [] {
                 return std::make_unique<PaperEgoController>("time_gap_p", TimeGapLongitudinal::Parts{false, false, false});
               });
}

}  // namespace vsd::sim
