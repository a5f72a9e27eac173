// `alks`: an ALKS-like system under test, built from the parts of the other built-ins:
//   - keeps its lane: pure pursuit on the lane-centre preview;
//   - follows at the minimum time gap of UN R157 paragraph 5.2.3.3 (the speed-dependent
//     table for M1/N1; linear interpolation between its rows as the paragraph prescribes):
//     a = k_gap (gap - max(standstill_gap, t_R157(v) v)) + k_speed (v_lead - v), at most the
//     cruise command k_cruise (set_speed - v);
//   - brakes for road users ahead that reach into its lane, taken from the object list:
//     the lead is the nearest road user ahead whose lateral gap to the Ego's corridor is
//     below (lane width - Ego width) / 2, i.e. that crosses into the Ego's lane when the
//     Ego drives on its centre line. That is the "lane intrusion" UN R157 paragraph 5.2.5.2
//     measures its cut-in criterion from, earlier than the intrusion into the Ego's own
//     corridor (in path) at slow lateral speeds;
//   - emergency braking: when the constant deceleration that keeps `emergency_margin` to
//     the lead (assumed to keep braking) exceeds `emergency_trigger`, it brakes with at
//     least 1.1 times that, up to `max_decel` - 6 m/s^2 by default, the deceleration
//     paragraph 5.2.5.2 assumes for an ALKS (TTC_LaneIntrusion > v_rel / (2 * 6 m/s^2) + 0.35 s).
// Parameters and defaults: docs/controllers.md.

#include <algorithm>
#include <array>
#include <utility>

#include "builtins.hpp"
#include "vsd/sim/builtin_controllers.hpp"

namespace vsd::sim {

double r157MinimumTimeGap(double speed) {
  // UN R157 paragraph 5.2.3.3, M1/N1: present speed (km/h) -> minimum time gap (s).
  static constexpr std::array<std::pair<double, double>, 7> kTable{
      {{7.2, 1.0}, {10.0, 1.1}, {20.0, 1.2}, {30.0, 1.3}, {40.0, 1.4}, {50.0, 1.5}, {60.0, 1.6}}};
  const double kmh = speed * 3.6;
  if (kmh <= kTable.front().first) return kTable.front().second;
  for (std::size_t i = 1; i < kTable.size(); ++i) {
    if (kmh <= kTable[i].first) {
      const auto [v0, t0] = kTable[i - 1];
      const auto [v1, t1] = kTable[i];
      return t0 + (t1 - t0) * (kmh - v0) / (v1 - v0);
    }
  }
  return kTable.back().second;  // the original version's table ends at its 60 km/h limit
}

namespace {

class AlksController final : public EgoController {
 public:
  AlksController() : longitudinal_(TimeGapLongitudinal::Parts{true, true, true}) {
    longitudinal_.useTimeGap(r157MinimumTimeGap);
  }

  void init(const ControllerParams& params) override {
    FollowingParameters defaults;
    defaults.standstillGap = 2.0;  // the table's first row: 1.0 s at 2 m/s is 2 m
    defaults.maxDecel = 6.0;
    longitudinal_.init(params, defaults);
    lateral_.init(params);
    params.rejectUnknown("alks");
  }

  void reset() override { longitudinal_.reset(); }

  bool observesObjects() const override { return true; }
  bool followsSetSpeed() const override { return true; }

  Command step(const Observation& observation, double /*dt*/) override {
    return {longitudinal_.accel(observation, lead(observation)), lateral_.curvature(observation)};
  }

 private:
  static std::optional<Observation::Leader> lead(const Observation& observation) {
    const double lane_width = observation.lane ? observation.lane->width : observation.egoWidth;
    const double intrusion = 0.5 * (lane_width - observation.egoWidth);
    const ObservedObject* nearest = nullptr;
    for (const auto& object : observation.objects) {
      if (object.relation.longitudinalDistance <= 0.0 || object.relation.lateralGap >= intrusion) continue;
      if (nearest == nullptr || object.relation.longitudinalGap < nearest->relation.longitudinalGap) nearest = &object;
    }
    if (nearest == nullptr) return std::nullopt;
    return leaderOf(*nearest);
  }

  TimeGapLongitudinal longitudinal_;
  PurePursuitLateral lateral_;
};

}  // namespace

void registerAlks(ControllerRegistry& registry) {
  registry.add("alks",
               "ALKS-like system under test: lane keeping, UN R157 5.2.3.3 minimum time gap, braking (up to 6 m/s^2) "
               "for road users reaching into its lane, from the object list",
               [] { return std::make_unique<AlksController>(); });
}

}  // namespace vsd::sim
