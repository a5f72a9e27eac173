#pragma once
// Scripted (non-Ego) road users of generated scenarios: the paper's Co, and the vehicles,
// pedestrians and objects of docs/scenario-language.md with their triggered actions.
//
// One stepper (ScriptedTraffic) moves them instant by instant, in the simulation (with the
// real Ego, which triggers can relate to) and in planning (plannedPaths: with the Ego's
// stand-in, for scenes of scenarios nobody simulated). Each road user moves by one of two
// lateral models:
//   pure pursuit (a road user with heading_noise_deg, such as the paper's Co): "Ego and Co
//     use a lane keeping controller; the resulting vehicle orientations are varied randomly
//     with U(-2.9 deg, 2.9 deg)" - it drives like the Ego's kinematic model, with its
//     scripted speed exactly, pure-pursuit lane keeping on its lane's centre line (the Ego's
//     default lateral controller) and its per-step heading disturbance;
//   exact (everything else): it moves in the road's lane frame (road/lane_frame.hpp), its
//     offset d across the road following the commanded lateral profile exactly and its
//     position s along the road advancing with its longitudinal speed - so a lane change
//     reaches its lane with the commanded lateral speed, with no controller lag.
// Its speed at every instant is its scripted speed (profile + noise) until a speed action
// starts, then the action's speed (+ the same noise).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::sim {

/// Where no simulation drives the Ego (planned scenes), triggers relate to this stand-in:
/// the Ego carrying on from its start along its lane's centre line at its initial speed.
class EgoStandIn {
 public:
  EgoStandIn(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road);
  /// Its state at t = time (s).
  VehicleState at(double time) const;

 private:
  MeasuredPolyline lane_;
  double startArcLength_ = 0.0;
  double speed_ = 0.0;
};

/// The scripted road users of one concrete scenario, stepped instant by instant.
class ScriptedTraffic {
 public:
  /// At t = 0. Throws ConfigError (naming the file, the road user and the sample) if a road
  /// user starts outside its road or overlapping another road user (the Ego included; two
  /// others where one may start overlapping, VehicleSpec::mayStartOverlapping, are let be).
  ScriptedTraffic(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road);
  ScriptedTraffic(ScriptedTraffic&&) noexcept;
  ScriptedTraffic& operator=(ScriptedTraffic&&) noexcept;
  ~ScriptedTraffic();

  /// The Ego's start: centre on its lane (at its x or s), heading along the lane, initial speed.
  const VehicleState& egoStart() const;
  /// The current instant k (t = k * step).
  std::size_t instant() const;
  /// Every other road user's state at the current instant, in scenario order.
  const std::vector<VehicleState>& states() const;
  /// Advances every road user to the next instant. `ego`: the Ego's state at the current
  /// instant, which triggers relating to it see.
  void step(const VehicleState& ego);
  /// True if road user `other`'s front is at or beyond the end of its road at the current
  /// instant (SUMO would let it arrive there).
  bool pastRoadEnd(std::size_t other) const;

  /// When an action started and ended (s; NaN while not started; a repeated action waiting to
  /// start again: start NaN, end its latest end).
  struct ActionTiming {
    double start;
    double end;
  };
  /// Per action of ConcreteScenario::actions.
  const std::vector<ActionTiming>& timings() const;
  /// The road users that start overlapping where one of them may (VehicleSpec::mayStartOverlapping),
  /// one line per pair in scenario order ("'b' starts overlapping 'a' (clearance -2.50 m)",
  /// the clearance as the refusal gives it: minus the overlap's least depth); empty if none.
  const std::vector<std::string>& startOverlaps() const;
  /// The set speed (m/s) the Ego's latest set_speed action started by `time` (s) commands its
  /// controller; none before the first. Actions start while stepping to the instant after
  /// their start, so ask with the time the controller acts at.
  std::optional<double> egoSetSpeedAt(double time) const;
  /// The Ego's controller actions (index into ConcreteScenario::actions) that started by `time`
  /// (s), in start order, from the `first`-th one on (the ones a caller has not handed over
  /// yet); each hands the domains it drives to its controller. Asked as egoSetSpeedAt.
  std::vector<std::size_t> egoControllersStarted(double time, std::size_t first) const;
  /// Where the Ego's lane_change and lateral_offset actions started by `time` (s) have moved
  /// the lane its controller keeps: m across the road (the road's lane offsets, > 0 left) at
  /// `time`; none before the first (it keeps its own lane). Asked as egoSetSpeedAt.
  std::optional<double> egoLaneOffsetAt(double time) const;
  /// Where a teleport of the Ego that started over the last step() puts it at the instant that
  /// step started from (its controller drives on from there: the next instant lands it where the
  /// action says at its start); none if no teleport of the Ego started then.
  const std::optional<VehicleState>& egoTeleported() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The other road users' states at every instant t_0 .. t_steps ([road user][instant]) with
/// the Ego's stand-in (EgoStandIn): what a planned scene assumes. Throws like ScriptedTraffic.
std::vector<std::vector<VehicleState>> plannedPaths(const scenario::ConcreteScenario& concrete,
                                                    const road::RoadGeometry& road);

}  // namespace vsd::sim
