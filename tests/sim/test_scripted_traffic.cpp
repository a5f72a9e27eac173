#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/scripted_vehicle.hpp"

using namespace vsd;
using namespace vsd::sim;

namespace {

/// A three-lane arc road (curvature `curvature`) with the Ego on lane 1 at 10 m/s and the road
/// users of `others` (YAML of vehicles.others), over `duration` s.
std::shared_ptr<const scenario::LogicalScenario> scenarioWith(const std::string& others, double curvature = 0.0,
                                                              double duration = 10.0, const std::string& inputs = "") {
  const std::string yaml = fmt::format(R"(
name: stepper
time: {{step: 0.2, duration: {}}}
inputs: [{}]
road: {{shape: arc, curvature: {}, length: 300, lanes: 3, lane_width: 3.5, shoulders: {{right: 3}}}}
vehicles:
  ego: {{s: 30, lane: 1, speed: 10, controller: {{name: idm}}}}
  others:
{}
)",
                                       duration, inputs, curvature, others);
  return scenario::parseLogicalScenario(yaml, "stepper.yaml");
}

struct Planned {
  scenario::ConcreteScenario concrete;
  road::RoadGeometry road;
  std::vector<std::vector<VehicleState>> paths;
};

Planned plan(const std::shared_ptr<const scenario::LogicalScenario>& logical, std::uint64_t sample = 0) {
  Planned run;
  run.concrete = scenario::sampleConcreteScenario(logical, 1, sample);
  run.road = road::buildRoadGeometry(run.concrete);
  run.paths = plannedPaths(run.concrete, run.road);
  return run;
}

/// The Ego (alks, 10 m/s, at s = 30 m on lane 1 of a straight road of 3 lanes of 3.5 m, lane 1's
/// centre on the road's centre line) with `ego_actions` and the road users of `others`, planned.
Planned egoWith(const std::string& name, double duration, const std::string& ego_actions, const std::string& others) {
  return plan(scenario::parseLogicalScenario(fmt::format(R"(
name: {}
time: {{step: 0.2, duration: {}}}
road: {{shape: arc, length: 300, lanes: 3, lane_width: 3.5}}
vehicles:
  ego: {{s: 30, lane: 1, speed: 10, controller: {{name: alks}}, actions: {}}}
  others:
{}
)",
                                                         name, duration, ego_actions, others),
                                             name + ".yaml"));
}

/// The one line loading and planning a scenario with the road users of `others` is refused with
/// ("" if it is not).
std::string refusalOf(const std::string& others) {
  return test::configErrorOf([&] { plan(scenarioWith(others)); });
}

/// The actions' timings after `instants` instants (0.2 s) of the stand-in Ego.
std::vector<ScriptedTraffic::ActionTiming> timingsAfter(const Planned& run, int instants) {
  ScriptedTraffic traffic(run.concrete, run.road);
  const EgoStandIn ego(run.concrete, run.road);
  for (int k = 0; k < instants; ++k) traffic.step(ego.at(0.2 * k));
  return traffic.timings();
}

/// A run stepped with the stand-in Ego: the traffic after `instants` instants (0.2 s), and
/// `places[k][u]`: road user u's (s, offset) in the road's lane frame at instant k.
struct SteppedRun {
  ScriptedTraffic traffic;
  std::vector<std::vector<std::pair<double, double>>> places;
};

SteppedRun stepped(const Planned& run, int instants) {
  SteppedRun out{ScriptedTraffic(run.concrete, run.road), {}};
  const EgoStandIn ego(run.concrete, run.road);
  const road::LaneFrame frame(run.road.centre);
  for (int k = 0; k < instants; ++k) {
    auto& at = out.places.emplace_back();
    for (const auto& state : out.traffic.states()) at.push_back(frame.coordinates(state.position()));
    out.traffic.step(ego.at(0.2 * k));
  }
  return out;
}

/// Offset (m, > 0 left) of a state from the road centre line.
double offsetOf(const road::RoadGeometry& road, const VehicleState& state) {
  return road::LaneFrame(road.centre).coordinates(state.position()).second;
}

}  // namespace

// The issue's number: a scripted lane change reaches the target lane with the commanded
// lateral speed (within 5 %), on a straight road and on the regulation's tightest bend.
TEST(ScriptedTraffic, ALaneChangeReachesItsLaneWithTheCommandedLateralSpeed) {
  for (const double curvature : {0.0, 0.004, -0.004}) {
    for (const double lateral_speed : {0.5, 1.5, 3.0}) {
      const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, gap: 20, relative_lane: -1, relative_speed: 0,
       actions: [{{trigger: {{time: 0.4}}, lane_change: {{ego_lane: 0, lateral_speed: {}}}}}]}})",
                                                    lateral_speed),
                                        curvature, 14.0);
      const Planned run = plan(logical);
      const auto& path = run.paths[0];
      double peak = 0.0;
      for (std::size_t k = 1; k < path.size(); ++k) {
        peak = std::max(peak, std::abs(offsetOf(run.road, path[k]) - offsetOf(run.road, path[k - 1])) / 0.2);
      }
      EXPECT_NEAR(peak, lateral_speed, 0.05 * lateral_speed) << "curvature " << curvature;
      EXPECT_NEAR(offsetOf(run.road, path.back()), run.road.laneOffset(1), 0.01) << "curvature " << curvature;
      // Its speed along the road stays the Ego's 10 m/s: it moves as its speed allows.
      for (std::size_t k = 1; k < path.size(); ++k) {
        const double step = (path[k].position() - path[k - 1].position()).norm();
        ASSERT_LE(step, 0.2 * std::max(path[k].speed, path[k - 1].speed) * 1.01 + 1e-3) << k;
      }
    }
  }
}

TEST(ScriptedTraffic, AGapTriggerFiresWhenTheStandInEgoComesClose) {
  // The mover waits 40 m ahead at 5 m/s; the stand-in Ego closes at 5 m/s: the gap reaches
  // 30 m after 2 s.
  const auto logical = scenarioWith(R"(
    - {id: mover, gap: 40, relative_lane: 1, speed: 5,
       actions: [{id: cut, trigger: {gap: 30}, lane_change: {ego_lane: 0, duration: 3}},
                 {trigger: {after: cut, delay: 1}, stop: {decel: 2}}]})");
  const Planned run = plan(logical);
  ScriptedTraffic traffic(run.concrete, run.road);
  const EgoStandIn ego(run.concrete, run.road);
  for (int k = 0; k < 50; ++k) traffic.step(ego.at(0.2 * k));
  const auto& timings = traffic.timings();
  EXPECT_NEAR(timings[0].start, 2.0, 0.2 + 1e-9);
  EXPECT_NEAR(timings[0].end - timings[0].start, 3.0, 1e-9);
  EXPECT_NEAR(timings[1].start, timings[0].end + 1.0, 1e-9);  // after cut, plus its delay
  EXPECT_NEAR(traffic.states()[0].speed, 0.0, 1e-9);           // stopped at 2 m/s^2 within 2.5 s
}

TEST(ScriptedTraffic, AtLeastRelationTriggersFireWhenTheGapOpens) {
  // The mover starts 10 m ahead at 15 m/s; the stand-in Ego follows at 10 m/s: the gap opens at
  // 5 m/s - 30 m after 4 s, a headway (gap / the Ego's 10 m/s) of 2.5 s after 3 s - and the two
  // never close in (the time to collision is undefined: it holds no bound, so `apart` never starts).
  const auto logical = scenarioWith(R"(
    - {id: mover, gap: 10, relative_lane: 1, speed: 15,
       actions: [{id: wide, trigger: {gap_at_least: 30}, stop: {decel: 1}},
                 {id: slow, trigger: {headway_at_least: 2.5}, lateral_offset: {offset: 0.5, duration: 1}},
                 {id: apart, trigger: {ttc_at_least: 100}, lateral_offset: {offset: 0, duration: 1}, }]})");
  const auto timings = timingsAfter(plan(logical), 30);
  EXPECT_NEAR(timings[0].start, 4.0, 1e-9);
  EXPECT_NEAR(timings[1].start, 3.0, 1e-9);
  EXPECT_TRUE(std::isnan(timings[2].start)) << timings[2].start;
}

// A headway `of` one road user is its own, to the other ahead of it, and undefined while the
// other is not ahead (OpenSCENARIO's); without `of` it is the rear one's, whichever that is.
// The passer (5 m long, as the Ego) starts 25.5 m (centres) behind the stand-in Ego at 15 m/s
// to its 10 m/s: it closes in at 5 m/s and is ahead after 5.1 s.
TEST(ScriptedTraffic, AHeadwayOfOneRoadUserIsUndefinedWhileTheOtherIsNotAheadOfIt) {
  const auto logical = scenarioWith(R"(
    - {id: passer, ds: -25.5, relative_lane: 1, speed: 15,
       actions: [{id: rear, trigger: {headway_at_least: 0.5}, lateral_offset: {offset: 0.1, duration: 1}},
                 {id: egos, trigger: {headway_at_least: 0.5, of: ego}, lateral_offset: {offset: 0.2, duration: 1}},
                 {id: close, trigger: {headway: 1, of: ego}, lateral_offset: {offset: 0.3, duration: 1}},
                 {id: own, trigger: {headway: 1, of: passer}, lateral_offset: {offset: 0.4, duration: 1}}]})");
  const auto timings = timingsAfter(plan(logical), 50);
  // The rear one's (the passer's) at once: 20.5 m / 15 m/s >= 0.5 s.
  EXPECT_NEAR(timings[0].start, 0.0, 1e-9);
  // The Ego's, once the passer is 5 m (bumper to bumper) ahead: 35.5 m closed at 5 m/s (7.1 s).
  EXPECT_NEAR(timings[1].start, 7.2, 1e-9);
  // The Ego's at most 1 s: undefined until the passer is ahead (after 5.1 s), then at once.
  EXPECT_NEAR(timings[2].start, 5.2, 1e-9);
  // The passer's own, to the Ego ahead of it: (20.5 - 5 t) / 15 <= 1 from t = 1.1.
  EXPECT_NEAR(timings[3].start, 1.2, 1e-9);
}

// Road users driving against the road (oncoming traffic on lane 2, an overtaker behind a slow
// one, a vehicle leaving at the road's start) move back along it, facing back, and their
// relations count the speeds with which they close in. Straight road: x = s.
TEST(ScriptedTraffic, RoadUsersDrivingAgainstTheRoadMoveBackAlongItAndCloseInOnWhatIsAhead) {
  const std::string mark = "lateral_offset: {offset: 0, duration: 0.2}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: oncoming, s: 130, lane: 2, length: 5, direction: against, speed: 10,
       actions: [{{id: ttc3, trigger: {{ttc: 3}}, {0}}},
                 {{id: own_headway, trigger: {{headway: 2, of: oncoming}}, {0}}},
                 {{id: egos_headway, trigger: {{headway: 1, of: ego}}, {0}}}]}}
    - {{id: overtaker, s: 200, lane: 1, length: 5, direction: against, speed: 20,
       actions: [{{id: closing, trigger: {{ttc: 1, to: slow}}, lane_change: {{lane: 0, duration: 2}}}},
                 {{id: to_slow, trigger: {{headway: 1, of: overtaker, to: slow}}, {0}}},
                 {{id: slows_own, trigger: {{headway: 100, of: slow, to: slow}}, {0}}}]}}
    - {{id: slow, s: 171.5, lane: 2, length: 5, direction: against, speed: 10}}
    - {{id: leaver, s: 8, lane: 0, length: 5, direction: against, speed: 10,
       actions: [{{id: left, trigger: {{end_of_road: 0}}, {0}}}]}})",
                                                mark),
                                    0.0, 6.0);
  const Planned run = plan(logical);
  const auto& oncoming = run.paths[0];
  EXPECT_NEAR(oncoming[0].x, 130.0, 1e-9);
  EXPECT_NEAR(oncoming[10].x, 110.0, 1e-9);  // 2 s at 10 m/s
  EXPECT_NEAR(std::abs(wrapAngle(oncoming[10].heading)), kPi, 1e-9);
  EXPECT_NEAR(oncoming[10].speed, 10.0, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, oncoming[10]), run.road.laneOffset(2), 1e-9);
  const auto timings = timingsAfter(run, 30);
  std::map<std::string, double> start;
  for (std::size_t a = 0; a < run.concrete.actions.size(); ++a) start[run.concrete.actions[a].id] = timings[a].start;
  // Against the stand-in Ego at 10 m/s: bumpers 95 m apart, closing at 20 m/s.
  EXPECT_NEAR(start["ttc3"], 1.8, 1e-9);          // (95 - 20 t) / 20 <= 3 from t = 1.75
  EXPECT_NEAR(start["own_headway"], 3.8, 1e-9);   // (95 - 20 t) / 10 <= 2 from t = 3.75
  EXPECT_NEAR(start["egos_headway"], 4.4, 1e-9);  // (95 - 20 t) / 10 <= 1 from t = 4.25: instant 4.4
  // The overtaker (on the next lane) 23.5 m behind the slow one, closing at 10 m/s.
  EXPECT_NEAR(start["closing"], 1.4, 1e-9);  // (23.5 - 10 t) / 10 <= 1 from t = 1.35
  EXPECT_NEAR(start["to_slow"], 0.4, 1e-9);  // (23.5 - 10 t) / 20 <= 1 from t = 0.35
  // The slow one's own headway is undefined while the overtaker is behind it (in its direction of
  // travel): it holds once the overtaker has passed it, 200 - 20 t < 171.5 - 10 t after 2.85 s.
  EXPECT_NEAR(start["slows_own"], 3.0, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, run.paths[1][30]), run.road.laneOffset(0), 1e-9);  // changed lanes by 3.4 s
  // The leaver's front (at 5.5 m) reaches the region's start at 0.55 s.
  EXPECT_NEAR(start["left"], 0.6, 1e-9);
}

TEST(ScriptedTraffic, APedestrianCrossesAtItsSpeedFacingAcross) {
  const auto logical = scenarioWith(R"(
    - {id: walker, type: pedestrian, gap: 30, relative_lane: 0, offset: -4, heading_deg: 90,
       actions: [{trigger: {time: 1}, cross: {speed: 1.5, to_offset: 4}}]})");
  const Planned run = plan(logical);
  const auto& path = run.paths[0];
  EXPECT_NEAR(path[0].speed, 0.0, 1e-12);
  EXPECT_NEAR(path[20].speed, 1.5, 1e-9);                   // t = 4 s: walking
  EXPECT_NEAR(wrapAngle(path[20].heading - kPi / 2), 0.0, 1e-6);
  EXPECT_NEAR(path[20].x, path[0].x, 1e-6);                 // straight across the road
  EXPECT_NEAR(offsetOf(run.road, path.back()), 4.0, 1e-6);  // 8 m at 1.5 m/s: arrived after 6.3 s
  EXPECT_NEAR(path.back().speed, 0.0, 1e-12);
}

TEST(ScriptedTraffic, ASwerveGoesOutAndBackWithTheCommandedLateralAcceleration) {
  const auto logical = scenarioWith(R"(
    - {id: lead, gap: 20, relative_lane: 0, relative_speed: 0,
       actions: [{id: out, trigger: {time: 0}, lateral_offset: {offset: 1.5, lateral_accel: 1.0}},
                 {trigger: {after: out}, lateral_offset: {offset: 0, lateral_accel: 1.0}}]})");
  const Planned run = plan(logical);
  double widest = 0.0;
  for (const auto& state : run.paths[0]) widest = std::max(widest, offsetOf(run.road, state));
  EXPECT_NEAR(widest, 1.5, 0.01);
  // Out and back take 2 * pi * sqrt(1.5 / 2) = 5.44 s.
  EXPECT_NEAR(offsetOf(run.road, run.paths[0][28]), 0.0, 0.02);
}

TEST(ScriptedTraffic, TypesDrawnFromInputsTakeTheirSizesFromTheTable) {
  const auto logical = scenarioWith(R"(
    - {id: lead, type: model, gap: 20, relative_lane: 0, relative_speed: 0})",
                                    0.0, 5.0, "{name: model, choices: [truck, pedestrian]}");
  bool truck = false;
  bool pedestrian = false;
  for (std::uint64_t i = 0; i < 20; ++i) {
    const auto concrete = scenario::sampleConcreteScenario(logical, 1, i);
    const auto& lead = concrete.others[0];
    const auto& kind = roadUserKind(lead.type);
    EXPECT_EQ(lead.length, kind.length);
    EXPECT_EQ(lead.width, kind.width);
    truck |= lead.type == RoadUserType::Truck;
    pedestrian |= lead.type == RoadUserType::Pedestrian;
  }
  EXPECT_TRUE(truck && pedestrian);
}

TEST(ScriptedTraffic, RoadUsersOverlappingAtTheStartAreRefused) {
  const auto logical = scenarioWith(R"(
    - {id: lead, gap: 20, relative_lane: 0, relative_speed: 0}
    - {id: twin, ds: 1, from: lead, relative_lane: 0, relative_speed: 0})");
  const auto concrete = scenario::sampleConcreteScenario(logical, 1, 3);
  const auto road = road::buildRoadGeometry(concrete);
  const std::string error = test::configErrorOf([&] { ScriptedTraffic traffic(concrete, road); });
  EXPECT_NE(error.find("stepper.yaml: sample 3: road user 'twin' starts overlapping 'lead'"), std::string::npos)
      << error;
}

// `may_start_overlapping: true` (obstacles an OpenSCENARIO file places closer than their lengths)
// lets a road user start inside another, named and measured; never inside the Ego.
TEST(ScriptedTraffic, RoadUsersThatMayStartOverlappingDoSoButNeverInsideTheEgo) {
  const auto logical = scenarioWith(R"(
    - {id: lead, gap: 20, relative_lane: 0, relative_speed: 0}
    - {id: twin, ds: 1, from: lead, relative_lane: 0, relative_speed: 0, may_start_overlapping: true})");
  const auto concrete = scenario::sampleConcreteScenario(logical, 1, 3);
  const auto road = road::buildRoadGeometry(concrete);
  const ScriptedTraffic traffic(concrete, road);
  ASSERT_EQ(traffic.startOverlaps().size(), 1u);
  // Two cars of the table's 5 m x 1.8 m one metre apart in one lane: 4 m inside each other along
  // the lane, 1.8 m across, the clearance minus the lesser depth.
  EXPECT_EQ(traffic.startOverlaps()[0], "'twin' starts overlapping 'lead' (clearance -1.80 m)");

  const auto onto_ego = scenarioWith(R"(
    - {id: twin, ds: 1, relative_lane: 0, relative_speed: 0, may_start_overlapping: true})");
  const auto concrete_ego = scenario::sampleConcreteScenario(onto_ego, 1, 3);
  const auto road_ego = road::buildRoadGeometry(concrete_ego);
  const std::string error = test::configErrorOf([&] { ScriptedTraffic refused(concrete_ego, road_ego); });
  EXPECT_NE(error.find("road user 'twin' starts overlapping 'ego'"), std::string::npos) << error;

  const std::string flag = test::configErrorOf([&] {
    scenarioWith("\n    - {id: twin, ds: 30, relative_lane: 0, relative_speed: 0, may_start_overlapping: yes}");
  });
  EXPECT_NE(flag.find("may_start_overlapping: got 'yes', expected true or false"), std::string::npos) << flag;
}

// Triggers on motion (docs/scenario-language.md "Actions and triggers"), in planning: the
// others move as scripted and the Ego is its stand-in (s = 30 on lane 1 at 10 m/s). Every
// start time is derived by hand from the numbers, to the recorded instant (step 0.2 s). The
// actions (a lateral offset of 0) change nothing, so each trigger sees the scripted motion.
TEST(ScriptedTraffic, MotionTriggersFireWhereTheNumbersSay) {
  const std::string mark = "lateral_offset: {offset: 0, duration: 0.2}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: slow, s: 60, lane: 0, length: 5, speed_profile: {{initial: 10, phases: [{{duration: 2, accel: 0}}, {{duration: 3, accel: 2}}]}},
       actions: [{{id: pushes, trigger: {{accel_at_least: 1.5}}, {0}}},
                 {{id: at11, trigger: {{speed_at_least: 11}}, {0}}},
                 {{id: ego_went, trigger: {{travelled: 24, of: ego}}, {0}}},
                 {{id: both, trigger: {{all: [{{relative_speed_at_least: 1.5, to: ego}}, {{time: 2.5}}]}}, {0}}},
                 {{id: first, trigger: {{any: [{{time: 4}}, {{travelled: 24, of: ego, delay: 1}}]}}, {0}}}]}}
    - {{id: mover, s: 200, lane: 2, length: 5, speed: 5,
       actions: [{{id: there, trigger: {{distance_at_most: 0.5, position: {{s: 210, lane: 2}}}}, {0}}},
                 {{id: away, trigger: {{distance_at_least: 6, position: {{x: 200, y: 3.5}}}}, {0}}},
                 {{id: ego_slow, trigger: {{speed_at_most: 10, of: ego}}, {0}}}]}}
    - {{id: ender, s: 250, lane: 0, length: 5, speed: 20,
       actions: [{{id: ended, trigger: {{end_of_road: 1}}, {0}}}]}})",
                                                mark),
                                    0.0, 5.0);
  const Planned run = plan(logical);
  const auto timings = timingsAfter(run, 25);
  std::map<std::string, double> start;
  for (std::size_t a = 0; a < run.concrete.actions.size(); ++a) start[run.concrete.actions[a].id] = timings[a].start;
  EXPECT_NEAR(start["pushes"], 2.2, 1e-9);    // the first step of 2 m/s^2 ends at 2.2 s
  EXPECT_NEAR(start["at11"], 2.6, 1e-9);      // 10 + 2 (t - 2) = 11 at 2.5 s, between instants: 2.6 s
  EXPECT_NEAR(start["ego_went"], 2.4, 1e-9);  // the stand-in at 10 m/s: 24 m at 2.4 s
  EXPECT_NEAR(start["both"], 2.8, 1e-9);      // 11.6 - 10 >= 1.5 first at 2.8 s, after 2.5 s
  EXPECT_NEAR(start["first"], 3.4, 1e-9);     // 2.4 + 1 before 4
  EXPECT_NEAR(start["there"], 2.0, 1e-9);     // 10 m at 5 m/s (1 m short at 1.8 s)
  EXPECT_NEAR(start["away"], 1.2, 1e-9);      // 6 m at 5 m/s
  EXPECT_NEAR(start["ego_slow"], 0.0, 1e-9);  // the stand-in's 10 m/s from t = 0
  // Front at 252.5 m + 20 m/s reaches the region's end (300 m) at 2.375 s: instant 2.4 s, plus 1 s.
  EXPECT_NEAR(start["ended"], 3.4, 1e-9);
}

// The example of the brief: accelerating at 1 m/s^2 from 20 m/s, `speed_at_least: 25` starts
// its action at t = 5 s (25 steps of 0.2 s), in planning.
TEST(ScriptedTraffic, ASpeedTriggerStartsItsActionWhenTheSpeedIsReached) {
  const Planned run = plan(scenarioWith(R"(
    - {id: fast, s: 100, lane: 2, length: 5, speed_profile: {initial: 20, phases: [{duration: 10, accel: 1}]},
       actions: [{id: at25, trigger: {speed_at_least: 25}, stop: {decel: 5, shape: linear}}]})",
                                        0.0, 6.0));
  const auto& path = run.paths[0];
  EXPECT_NEAR(path[25].speed, 25.0, 1e-9);  // t = 5 s: still accelerating
  EXPECT_NEAR(path[26].speed, 24.0, 1e-9);  // braking at 5 m/s^2 from t = 5 s
}

// A continuous target keeps up with the other's speed (one step behind it: a road user moves
// on what it sees at the instant) until another speed action replaces it, which ends it and
// starts what waits for its end. `lead` accelerates at 1 m/s^2 from 10 m/s: the follower's
// speed at instant k + 1 is 1.5 times the lead's at instant k, until its stop at t = 4 s.
TEST(ScriptedTraffic, AContinuousTargetFollowsTheOthersSpeedUntilReplaced) {
  const Planned run = plan(scenarioWith(R"(
    - {id: lead, s: 150, lane: 2, speed_profile: {initial: 10, phases: [{duration: 10, accel: 1}]},
       actions: [{id: after_track, trigger: {after: track}, lateral_offset: {offset: 0.5, duration: 1}}]}
    - {id: follower, s: 100, lane: 0, speed: 3,
       actions: [{id: track, speed: {relative_factor: 1.5, to: lead, continuous: true, shape: step}},
                 {id: brake, trigger: {time: 4}, stop: {decel: 5, shape: linear}},
                 {id: fixed, trigger: {time: 7}, speed: {relative_target: -2, to: lead, shape: step}},
                 {id: after_brake, trigger: {after: brake}, lateral_offset: {offset: 0.5, duration: 1}}]})",
                                        0.0, 9.0));
  const auto& lead = run.paths[0];
  const auto& follower = run.paths[1];
  EXPECT_NEAR(follower[0].speed, 3.0, 1e-9);
  for (std::size_t k = 0; k < 20; ++k) {
    EXPECT_NEAR(lead[k].speed, 10.0 + 0.2 * static_cast<double>(k), 1e-9) << k;
    EXPECT_NEAR(follower[k + 1].speed, 1.5 * lead[k].speed, 1e-9) << k;
  }
  EXPECT_NEAR(follower[21].speed, 1.5 * lead[19].speed - 1.0, 1e-9);  // braking at 5 m/s^2 from t = 4 s
  // Not continuous: the lead's speed as the step to t = 7 s starts (16.8 m/s) less 2, fixed from then on.
  EXPECT_NEAR(follower[35].speed, 14.8, 1e-9);
  EXPECT_NEAR(follower[45].speed, 14.8, 1e-9);
  // In file order: after_track, track, brake, fixed, after_brake.
  const auto timings = timingsAfter(run, 45);
  EXPECT_NEAR(timings[1].start, 0.0, 1e-9);
  EXPECT_NEAR(timings[1].end, 4.0, 1e-9);  // replaced by the stop
  EXPECT_NEAR(timings[0].start, 4.0, 1e-9);
  // The stop (from 20.7 m/s at 5 m/s^2: 4.14 s) ends where the fixed target replaces it, at 7 s
  // (as esmini ends an action a later one overrides), and an `after` on it fires then.
  EXPECT_NEAR(timings[2].end, 7.0, 1e-9);
  EXPECT_NEAR(timings[4].start, 7.0, 1e-9);
  // Tracking that is never replaced never ends.
  const auto open = timingsAfter(plan(scenarioWith(R"(
    - {id: follower, s: 100, lane: 0, speed: 3,
       actions: [{id: track, speed: {relative_target: 1, continuous: true, shape: step}},
                 {trigger: {after: track}, lateral_offset: {offset: 0.5, duration: 1}}]})")),
                                  50);
  EXPECT_TRUE(std::isinf(open[0].end)) << open[0].end;
  EXPECT_TRUE(std::isnan(open[1].start)) << open[1].start;
}

// `between: reference_points` measures from each road user's reference point (here the
// chaser's lies 1 m behind its centre, the Ego's at its centre) instead of bumper to bumper.
// The chaser starts 30.3 m (centres) behind the stand-in Ego at 15 m/s to its 10 m/s: the
// reference points are 31.3 - 5t apart, the bumpers (5 m cars) 25.3 - 5t.
TEST(ScriptedTraffic, RelationsBetweenReferencePointsCountFromThem) {
  const auto logical = scenarioWith(R"(
    - {id: chaser, ds: -30.3, relative_lane: 1, speed: 15, reference_point: -1,
       actions: [{trigger: {headway: 1.5, of: chaser, between: reference_points},
                  lateral_offset: {offset: 0.1, duration: 1}},
                 {trigger: {headway: 1.5, of: chaser}, lateral_offset: {offset: 0.2, duration: 1}},
                 {trigger: {gap: 20, between: reference_points}, lateral_offset: {offset: 0.3, duration: 1}},
                 {trigger: {ttc: 4, between: reference_points}, lateral_offset: {offset: 0.4, duration: 1}}]})");
  const auto timings = timingsAfter(plan(logical), 30);
  EXPECT_NEAR(timings[0].start, 1.8, 1e-9);  // (31.3 - 5t) / 15 <= 1.5 from t = 1.76
  EXPECT_NEAR(timings[1].start, 0.6, 1e-9);  // (25.3 - 5t) / 15 <= 1.5 from t = 0.56
  EXPECT_NEAR(timings[2].start, 2.4, 1e-9);  // 31.3 - 5t <= 20 from t = 2.26
  EXPECT_NEAR(timings[3].start, 2.4, 1e-9);  // (31.3 - 5t) / 5 <= 4 from t = 2.26
}

// `measure: straight_line` (OpenSCENARIO's euclidianDistance) counts the lateral distance too:
// the chaser drives one lane (3.5 m) left of the stand-in Ego, its reference point 31.3 - 5t
// behind the Ego's along the lane, its body 25.3 - 5t behind and 3.5 - 1.8 = 1.7 m beside
// it. Markers hold the chaser's lane offset at 0, so each trigger's time is its own.
TEST(ScriptedTraffic, StraightLineRelationsCountTheLateralDistanceToo) {
  const std::string marker = "lateral_offset: {offset: 0, duration: 1}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: chaser, ds: -30.3, relative_lane: 1, speed: 15, reference_point: -1,
       actions: [{{trigger: {{gap: 5, between: reference_points, measure: straight_line}}, {0}}},
                 {{trigger: {{gap: 5, between: reference_points}}, {0}}},
                 {{trigger: {{gap: 2, measure: straight_line}}, {0}}},
                 {{trigger: {{gap: 2, measure: along_lane}}, {0}}},
                 {{trigger: {{headway: 0.5, of: chaser, between: reference_points, measure: straight_line}}, {0}}},
                 {{trigger: {{ttc: 1, between: reference_points, measure: straight_line}}, {0}}}]}})",
                                                marker));
  const auto timings = timingsAfter(plan(logical), 35);
  EXPECT_NEAR(timings[0].start, 5.6, 1e-9);  // sqrt((31.3 - 5t)^2 + 3.5^2) <= 5 from t = 5.55
  EXPECT_NEAR(timings[1].start, 5.4, 1e-9);  // 31.3 - 5t <= 5 from t = 5.26
  EXPECT_NEAR(timings[2].start, 5.0, 1e-9);  // sqrt((25.3 - 5t)^2 + 1.7^2) <= 2 from t = 4.85
  EXPECT_NEAR(timings[3].start, 4.8, 1e-9);  // 25.3 - 5t <= 2 from t = 4.66
  EXPECT_NEAR(timings[4].start, 5.0, 1e-9);  // sqrt((31.3 - 5t)^2 + 3.5^2) / 15 <= 0.5 from t = 4.93
  EXPECT_NEAR(timings[5].start, 5.6, 1e-9);  // sqrt((31.3 - 5t)^2 + 3.5^2) / 5 <= 1 from t = 5.55
}

// `measure: lateral` (OpenSCENARIO's lateral relative distance) counts across the Ego's lane.
// The mover, a car (5 x 1.8 m) beside the stand-in Ego one lane (3.5 m) to its left, both at
// 10 m/s, changes into the Ego's lane from 1 s over 4 s at 0.875 m/s: its reference point is
// 3.5 - 0.875 (t - 1) m from the Ego's across the lane. Meanwhile it heads atan(0.875 / 10) =
// 0.0872 rad off the lane, so its half extent across is (5 sin + 1.8 cos) / 2 = 1.114 m and
// the gap between the sides 3.5 - 0.875 (t - 1) - 1.114 - 0.9. Markers are speed actions that
// keep its speed, so each trigger's time is its own.
TEST(ScriptedTraffic, LateralRelationsMeasureAcrossTheEgosLane) {
  const std::string marker = "speed: {target: 10, rate: 1}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, ds: 0, relative_lane: 1, speed: 10,
       actions: [{{trigger: {{time: 1}}, lane_change: {{ego_lane: 0, duration: 4, shape: linear}}}},
                 {{trigger: {{gap: 2, between: reference_points, measure: lateral}}, {0}}},
                 {{trigger: {{gap: 0.5, measure: lateral}}, {0}}},
                 {{trigger: {{gap_at_least: 3, between: reference_points, measure: lateral, falling: true}}, {0}}}]}})",
                                                marker));
  const auto timings = timingsAfter(plan(logical), 30);
  EXPECT_NEAR(timings[1].start, 2.8, 1e-9);  // 3.5 - 0.875 (t - 1) <= 2 from t = 2.71
  EXPECT_NEAR(timings[2].start, 2.2, 1e-9);  // 1.486 - 0.875 (t - 1) <= 0.5 from t = 2.13
  EXPECT_NEAR(timings[3].start, 1.6, 1e-9);  // 3.5 - 0.875 (t - 1) >= 3 until t = 1.57
  const std::string error = refusalOf("    - {id: mover, ds: 0, relative_lane: 1, speed: 10,\n"
                                      "       actions: [{trigger: {ttc: 1, measure: lateral}, stop: {decel: 1}}]}");
  EXPECT_NE(error.find("'measure: lateral' goes with gap, gap_at_least and the distance triggers"), std::string::npos)
      << error;
  const std::string unknown = refusalOf("    - {id: mover, ds: 0, relative_lane: 1, speed: 10,\n"
                                        "       actions: [{trigger: {gap: 1, measure: sideways}, stop: {decel: 1}}]}");
  EXPECT_NE(unknown.find("got 'sideways', expected along_lane, straight_line or lateral"), std::string::npos)
      << unknown;
}

// A distance to a place measured along the Ego's lane or across it, from the centre or from the
// body (OpenSCENARIO's DistanceCondition with relativeDistanceType and freespace). The mover's
// centre starts 20 m before the place along the road and 7 m left of it (lane 2 against lane 0),
// at 5 m/s; its body is 5 m long and 2 m wide. The rear's reference point lies 1.5 m behind its
// centre: 21.5 m before its place at 5 m/s. The sider's place is 5 m ahead of the stand-in Ego
// and 3.5 m to its left (lane 2, where the sider drives): 25 - 10 t m from the sider's centre.
TEST(ScriptedTraffic, DistancesToAPlaceMeasureAlongOrAcrossTheLaneFromTheCentreOrTheBody) {
  const std::string marker = "lateral_offset: {offset: 0, duration: 0.2}";
  const std::string place = "position: {s: 220, lane: 0}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, s: 200, lane: 2, length: 5, width: 2, speed: 5,
       actions: [{{trigger: {{distance_at_most: 9.5, {1}, measure: along_lane}}, {0}}},
                 {{trigger: {{distance_at_most: 9.4, {1}, measure: along_lane, from: body}}, {0}}},
                 {{trigger: {{distance_at_most: 8, {1}, from: body}}, {0}}},
                 {{trigger: {{distance_at_least: 6.5, {1}, measure: lateral}}, {0}}},
                 {{trigger: {{distance_at_least: 6.5, {1}, measure: lateral, from: body}}, {0}}},
                 {{trigger: {{distance_at_most: 6.5, {1}, measure: lateral, from: body}}, {0}}}]}}
    - {{id: chaser, s: 10, lane: 0, speed: 20,
       actions: [{{trigger: {{distance_at_most: 1, position: {{from: ego, ds: 0, lanes: -1}}, measure: along_lane}},
                   {0}}}]}}
    - {{id: sider, s: 10, lane: 2, speed: 20,
       actions: [{{trigger: {{distance_at_most: 1, position: {{from: ego, dx: 5, dy: 3.5}}}}, {0}}}]}}
    - {{id: rear, s: 200, lane: 1, length: 5, width: 2, reference_point: -1.5, speed: 5,
       actions: [{{trigger: {{distance_at_most: 9.5, position: {{s: 220, lane: 1}}, measure: along_lane,
                             from: reference_point}}, {0}}}]}})",
                                                marker, place));
  const auto timings = timingsAfter(plan(logical), 30);
  // A place beside the stand-in Ego moves with it: 30 + 10 t - (10 + 20 t) <= 1 from t = 1.9.
  EXPECT_NEAR(timings[6].start, 2.0, 1e-9);
  EXPECT_NEAR(timings[0].start, 2.2, 1e-9);  // 20 - 5 t <= 9.5 from t = 2.1
  EXPECT_NEAR(timings[1].start, 1.8, 1e-9);  // 20 - 5 t - 2.5 <= 9.4 from t = 1.62
  EXPECT_NEAR(timings[2].start, 2.6, 1e-9);  // sqrt((17.5 - 5 t)^2 + 6^2) <= 8 from t = 2.44
  EXPECT_NEAR(timings[3].start, 0.0, 1e-9);  // 7 m across from its centre
  EXPECT_TRUE(std::isnan(timings[4].start));  // 7 - 1 = 6 m across from its side
  EXPECT_NEAR(timings[5].start, 0.0, 1e-9);
  EXPECT_NEAR(timings[7].start, 2.4, 1e-9);  // |25 - 10 t| <= 1 from t = 2.4
  EXPECT_NEAR(timings[8].start, 2.4, 1e-9);  // 21.5 - 5 t <= 9.5 from t = 2.4
  const auto refused = [](const std::string& trigger) {
    return test::configErrorOf([&] {
      scenarioWith("    - {id: mover, ds: 0, relative_lane: 1, speed: 10,\n"
                   "       actions: [{trigger: " + trigger + ", stop: {decel: 1}}]}");
    });
  };
  EXPECT_NE(refused("{gap: 1, from: body}").find("'from' goes with distance_at_most and distance_at_least"),
            std::string::npos);
  EXPECT_NE(refused("{distance_at_most: 1, position: {s: 20, lane: 0}, from: front}")
                .find("got 'front', expected centre, body or reference_point"),
            std::string::npos);
  EXPECT_NE(refused("{distance_at_most: 1, position: {from: nobody, ds: 0, dd: 0}}")
                .find("position.from: got 'nobody', expected a road user of the file"),
            std::string::npos);
}

// A lane change may end beside its lane's centre (`offset`, OpenSCENARIO's targetLaneOffset) and
// may be paced by a distance along the road, covered at the speed it has when it starts: from
// lane 0 (3.5 m right of the centre line) to 0.5 m left of lane 1's centre (on the centre line)
// over 40 m at 10 m/s, in 4 s.
TEST(ScriptedTraffic, ALaneChangeOverADistanceEndsWhereItsOffsetSays) {
  for (const std::string shape : {"linear", "smooth"}) {
    const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, s: 60, lane: 0, speed: 10,
       actions: [{{trigger: {{time: 1}}, lane_change: {{lane: 1, offset: 0.5, distance: 40, shape: {}}}}}]}})",
                                                  shape));
    const auto [traffic, place] = stepped(plan(logical), 35);
    EXPECT_NEAR(traffic.timings()[0].end, 5.0, 1e-9) << shape;
    EXPECT_NEAR(place[25][0].first - place[5][0].first, 40.0, 0.05) << shape;
    EXPECT_NEAR(place[5][0].second, -3.5, 1e-9) << shape;
    EXPECT_NEAR(place[25][0].second, 0.5, 1e-9) << shape;
    EXPECT_NEAR(place[34][0].second, 0.5, 1e-9) << shape;
  }
  const std::string standing =
      refusalOf("    - {id: mover, s: 60, lane: 0, speed: 0,\n"
                "       actions: [{trigger: {time: 1}, lane_change: {lane: 1, distance: 40}}]}");
  EXPECT_NE(standing.find("lane_change.distance: at t = 1.0 s it stands and covers no distance"), std::string::npos)
      << standing;
}

// A teleport moves a road user at once; it drives on from its landing place in its direction,
// a speed or lateral action under way ends (it keeps its speed and its landing place across the
// road), and neither the distance it has travelled nor its road's end counts the jump.
// `jumper` (10 m/s) lands on lane 2's centre + 0.2 m (3.7 m left of the centre line) at s = 50
// at 1.1 s: 51 m at 1.2 s; travelled counts 11 m by then and 25 m at 2.5 s (instant 2.6).
// `ender`'s front passes the region's end (300 m) at 0.375 s; back at s = 100 it never reaches it.
// `speeder` speeds up from 10 m/s at 1 m/s^2 and keeps the 12 m/s it has at 2 s. `oncoming`
// (against the road at 10 m/s) lands at s = 230 at 1 s and is at 228 m at 1.2 s. Relative to
// road users where they are: `follower` lands 20 m ahead of the stand-in Ego (at s = 50 at 2 s),
// a lane right of it, 0.3 m left of that lane's centre (3.2 m right of the centre line);
// `shadow` lands 10 m behind `speeder` (at 272 m at 3 s) and 1 m right of it (2.5 m left).
TEST(ScriptedTraffic, ATeleportMovesARoadUserAtOnceAndItDrivesOnFromThere) {
  const std::string marker = "speed: {target: 10, rate: 1}";
  const auto logical = scenarioWith(fmt::format(R"(
    - {{id: jumper, s: 100, lane: 0, speed: 10,
       actions: [{{id: jump, trigger: {{time: 1.1}}, teleport: {{s: 50, lane: 2, offset: 0.2}}}},
                 {{trigger: {{time: 0.5}}, lane_change: {{lane: 1, duration: 4}}}},
                 {{trigger: {{after: jump}}, {0}}},
                 {{trigger: {{travelled: 25}}, {0}}}]}}
    - {{id: ender, s: 290, lane: 1, speed: 20,
       actions: [{{trigger: {{time: 1}}, teleport: {{s: 100, lane: 1}}}},
                 {{trigger: {{end_of_road: 2}}, {0}}}]}}
    - {{id: speeder, s: 200, lane: 2, speed: 10,
       actions: [{{trigger: {{time: 0}}, speed: {{target: 20, rate: 1, shape: linear}}}},
                 {{trigger: {{time: 2}}, teleport: {{s: 260, lane: 2}}}}]}}
    - {{id: oncoming, s: 250, lane: 0, speed: 10, direction: against,
       actions: [{{trigger: {{time: 1}}, teleport: {{s: 230, lane: 0}}}}]}}
    - {{id: follower, s: 150, lane: 2, speed: 10,
       actions: [{{trigger: {{time: 2}}, teleport: {{from: ego, ds: 20, lanes: -1, offset: 0.3}}}}]}}
    - {{id: shadow, s: 20, lane: 2, speed: 10,
       actions: [{{trigger: {{time: 3}}, teleport: {{from: speeder, ds: -10, dd: -1}}}}]}}
    - {{id: hopper, s: 150, lane: 0, speed: 10, reference_point: -1,
       actions: [{{trigger: {{time: 1}}, teleport: {{from: ego, dx: 20, dy: 3.5}}}}]}})",
                                                marker),
                                    0.0, 5.0);
  const auto [traffic, place] = stepped(plan(logical), 25);
  // s from the region's start: the jumper starts at 100 m.
  const auto s_at = [&, &place = place](int k, std::size_t user) {
    return place[k][user].first - place[0][0].first + 100.0;
  };
  EXPECT_NEAR(s_at(5, 0), 110.0, 1e-6);
  EXPECT_NEAR(s_at(6, 0), 51.0, 1e-6);
  EXPECT_NEAR(place[6][0].second, 3.7, 1e-9);
  EXPECT_NEAR(place[24][0].second, 3.7, 1e-9);  // the lane change under way ended
  EXPECT_NEAR(s_at(24, 0), 51.0 + 18 * 2.0, 1e-6);
  EXPECT_NEAR(traffic.states()[0].heading, 0.0, 1e-9);
  EXPECT_NEAR(s_at(10, 2), 260.0, 1e-6);
  EXPECT_NEAR(traffic.states()[2].speed, 12.0, 1e-9);
  EXPECT_NEAR(s_at(6, 3), 228.0, 1e-6);
  EXPECT_NEAR(std::abs(traffic.states()[3].heading), kPi, 1e-9);
  EXPECT_NEAR(s_at(10, 4), 70.0, 1e-6);
  EXPECT_NEAR(place[10][4].second, -3.2, 1e-9);
  EXPECT_NEAR(s_at(15, 5), 262.0, 1e-6);
  EXPECT_NEAR(place[15][5].second, 2.5, 1e-9);
  // 20 m ahead of the stand-in Ego (s = 30 + 10 t) and 3.5 m to its left at 1 s: its reference
  // point (1 m behind its centre) lands at s = 60 on lane 2's centre; its centre is at 61 m.
  EXPECT_NEAR(s_at(6, 6), 61.0 + 2.0, 1e-6);
  EXPECT_NEAR(place[6][6].second, 3.5, 1e-9);
  const auto& timings = traffic.timings();
  EXPECT_NEAR(timings[0].start, 1.1, 1e-9);
  EXPECT_NEAR(timings[0].end, 1.1, 1e-9);
  EXPECT_NEAR(timings[1].end, 1.1, 1e-9);  // the lane change under way ended there
  EXPECT_NEAR(timings[6].end, 2.0, 1e-9);  // so did the speeder's speed change (10 s planned)
  EXPECT_NEAR(timings[2].start, 1.1, 1e-9);
  EXPECT_NEAR(timings[3].start, 2.6, 1e-9);
  EXPECT_TRUE(std::isnan(timings[5].start));
  // Lanes count from a shoulder as from a lane beyond the outer one (esmini counts lane ids):
  // one lane left of a pedestrian on the right shoulder is lane 0 (3.5 m right of the centre).
  const Planned beside = plan(scenarioWith(R"(
    - {id: walker, type: pedestrian, s: 100, lane: 0, offset: -3}
    - {id: mover, s: 60, lane: 2, speed: 10,
       actions: [{trigger: {time: 1}, teleport: {from: walker, ds: 10, lanes: 1}}]})",
                                           0.0, 2.0));
  const road::LaneFrame beside_frame(beside.road.centre);
  EXPECT_NEAR(beside_frame.coordinates(beside.paths[1].back().position()).second, -3.5, 1e-9);
  // In the walker's own axes (it faces across the road, to the left) or in the frame's: 6.5 m
  // ahead of it and 10 m to its right is 10 m along the road and 6.5 m left, on lane 1's centre.
  const Planned axes = plan(scenarioWith(R"(
    - {id: walker, type: pedestrian, s: 100, lane: 0, offset: -3, heading_deg: 90}
    - {id: own, s: 60, lane: 2, speed: 0, actions: [{trigger: {time: 1}, teleport: {from: walker, dx: 6.5, dy: -10}}]}
    - {id: framed, s: 20, lane: 2, speed: 0,
       actions: [{trigger: {time: 1}, teleport: {from: walker, dx: 10, dy: 6.5, axes: frame}}]}
    - {id: crosser, type: pedestrian, s: 140, lane: 0, offset: -3, heading_deg: 90, reference_point: 0.2,
       actions: [{trigger: {time: 1}, teleport: {from: walker, dx: 0, dy: -10}}]})",
                                         0.0, 2.0));
  const road::LaneFrame axes_frame(axes.road.centre);
  const auto walker_at = axes_frame.coordinates(axes.paths[0].back().position());
  for (const std::size_t user : {std::size_t{1}, std::size_t{2}}) {
    const auto landed = axes_frame.coordinates(axes.paths[user].back().position());
    EXPECT_NEAR(landed.first - walker_at.first, 10.0, 1e-9) << user;
    EXPECT_NEAR(landed.second, 0.0, 1e-9) << user;
  }
  // A standing pedestrian facing across keeps facing so: its reference point (0.2 m ahead of its
  // centre, across the road) lands 10 m along from the walker, its centre 0.2 m right of that.
  const auto crossed = axes_frame.coordinates(axes.paths[3].back().position());
  EXPECT_NEAR(crossed.first - walker_at.first, 10.0, 1e-9);
  EXPECT_NEAR(crossed.second, -6.5 - 0.2, 1e-9);
  // Standing on a bend, it keeps its heading to the road: along the road where it lands.
  const auto bend = scenarioWith(R"(
    - {id: stand, s: 100, lane: 0, speed: 0, actions: [{trigger: {time: 1}, teleport: {s: 150, lane: 0}}]})",
                                 0.004, 2.0);
  const Planned on_bend = plan(bend);
  const road::LaneFrame bend_frame(on_bend.road.centre);
  const VehicleState& landed = on_bend.paths[0].back();
  const double s_landed = bend_frame.coordinates(landed.position()).first;
  EXPECT_NEAR(landed.heading, bend_frame.heading(s_landed, on_bend.road.laneOffset(0)), 1e-9);
  EXPECT_GT(std::abs(landed.heading - on_bend.paths[0].front().heading), 0.19);  // 50 m of 0.004 / m
}

// Bad teleports and lane-change offsets are one line each, before or when they start.
TEST(ScriptedTraffic, TeleportsAndLaneChangeOffsetsStayOnTheRoad) {
  const auto refused = [](const std::string& user, const std::string& action) {
    return test::configErrorOf([&] {
      plan(scenarioWith("    - {id: mover, " + user + ",\n       actions: [{trigger: {time: 1}, " + action + "}]}"));
    });
  };
  const std::string moving = "s: 60, lane: 0, speed: 5";
  EXPECT_NE(refused(moving, "teleport: {s: 10}").find("expected {s, lane[, offset]}: where along the road it lands"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {x: 10, y: 0}").find("teleport.x: unknown key 'x' (allowed: lane, offset, s)"),
            std::string::npos);
  EXPECT_NE(refused("s: 60, lane: 0, type: stationary_object", "teleport: {s: 10, lane: 0}")
                .find("a stationary object does not move"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {s: 10, lane: 3}")
                .find("teleport.lane: got 3 in sample 0, expected a lane the road has (0 .. 2)"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {s: -500, lane: 0}").find("teleport: it lands -500.0 m along a road of"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: nobody, ds: 1, lanes: 0}")
                .find("teleport.from: got 'nobody', expected a road user of the file: ego, mover"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: ego, ds: 1}")
                .find("expected {from, ds, lanes[, offset]}, {from, ds, dd} or {from, dx, dy[, axes]}"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: ego, dx: 1, ds: 2}")
                .find("expected {from, ds, lanes[, offset]}, {from, ds, dd} or {from, dx, dy[, axes]}"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: ego, ds: 10, lanes: 5}")
                .find("teleport.lanes: lane 6 from the lane of 'ego', expected a lane the road has (0 .. 2)"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: ego, ds: 10, dd: 20}")
                .find("m left of its centre line: expected a place on"),
            std::string::npos);
  EXPECT_NE(refused(moving, "teleport: {from: '', ds: 10, dd: 0}").find("teleport.from: expected a road user's id"),
            std::string::npos);
  // After a relative teleport its lane is known when it lands: what depends on it is checked then.
  const auto after_jump = [&](const std::string& action) {
    return test::configErrorOf([&] {
      plan(scenarioWith("    - {id: mover, " + moving + ",\n       actions: [{trigger: {time: 1}, teleport: "
                        "{from: ego, ds: 40, lanes: 0}}, {trigger: {time: 2}, " + action + "}]}"));
    });
  };
  EXPECT_NE(after_jump("lane_change: {lanes: 0.5, duration: 1}").find("got 0.5 lanes in sample 0, expected a whole"),
            std::string::npos);
  EXPECT_NE(after_jump("lane_change: {lanes: 0, offset: 40, duration: 1}")
                .find("lane_change.offset: at t = 2.0 s it would end 40.00 m left of the road's centre"),
            std::string::npos);
  // The road: three lanes of 3.5 m and a 3 m right shoulder.
  EXPECT_NE(refused(moving, "teleport: {s: 10, lane: 0, offset: -5}")
                .find("teleport.offset: got -5 m from lane 0's centre in sample 0, 3.25 m beyond the road's right "
                      "edge where road.shoulders.right is 3 m: a road user off the road"),
            std::string::npos);
  EXPECT_NE(refused(moving, "lane_change: {lane: 2, offset: 40, duration: 2}")
                .find("lane_change.offset: got 40 m from lane 2's centre"),
            std::string::npos);
}

namespace {

std::shared_ptr<const scenario::LogicalScenario> unequalLanes(const std::string& road_keys, const std::string& others) {
  return scenario::parseLogicalScenario(fmt::format(R"(
name: widths
time: {{step: 0.2, duration: 8}}
road: {{shape: arc, length: 300, lanes: 3, {}}}
vehicles:
  ego: {{s: 30, lane: 1, speed: 10, controller: {{name: idm}}}}
  others:
{}
)",
                                                    road_keys, others),
                                        "widths.yaml");
}

std::string loadErrorOf(const std::string& road_keys) {
  try {
    const auto logical = unequalLanes(road_keys, "    - {id: a, gap: 20, relative_lane: 0, speed: 5}");
    scenario::sampleConcreteScenario(logical, 1, 0);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

}  // namespace

// `lane_widths` gives each lane its own width (lane 0 first): lanes lie side by side around the
// road centre, and a lane change, `ego_lane` included, ends on its target lane's centre.
// Lanes 3.9, 3.5 and 3.65 m wide (esmini's e6mini.xodr): 11.05 m in all, lane 0's centre
// 11.05 / 2 - 3.9 / 2 = 3.575 m right of the centre, lane 2's 3.7 m left of it.
TEST(ScriptedTraffic, LanesOfTheirOwnWidthsLieSideBySide) {
  const Planned run = plan(unequalLanes("lane_widths: [3.9, 3.5, 3.65]", R"(
    - {id: mover, gap: 10, relative_lane: -1, speed: 12,
       actions: [{trigger: {time: 1}, lane_change: {ego_lane: 1, duration: 3}}]})"));
  EXPECT_EQ(run.concrete.laneWidths, (std::vector<double>{3.9, 3.5, 3.65}));
  EXPECT_NEAR(run.road.laneOffset(0), -3.575, 1e-12);
  EXPECT_NEAR(run.road.laneOffset(1), -3.575 + 3.9 / 2 + 3.5 / 2, 1e-12);
  EXPECT_NEAR(run.road.laneOffset(2), 3.7, 1e-12);
  EXPECT_EQ(run.road.laneAt(-3.575 + 1.94), 0);
  EXPECT_EQ(run.road.laneAt(-3.575 + 1.96), 1);
  const auto& mover = run.paths[0];
  EXPECT_NEAR(offsetOf(run.road, mover.front()), -3.575, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, mover.back()), 3.7, 1e-9);  // the lane left of the Ego's
  EXPECT_NE(loadErrorOf("lane_widths: [3.9, 3.5]").find("road.lane_widths: expected a list of 3 widths (road.lanes)"),
            std::string::npos);
  EXPECT_NE(loadErrorOf("lane_width: 3.5, lane_widths: [3.9, 3.5, 3.65]")
                .find("road.lane_widths: either lane_widths or lane_width (with its noise), not both"),
            std::string::npos);
  EXPECT_NE(loadErrorOf("lane_widths: [3.9, 0.4, 3.65]").find("road.lane_widths[1]: got '0.4', expected a width in "
                                                             "(0.5, 50] m"),
            std::string::npos)
      << loadErrorOf("lane_widths: [3.9, 0.4, 3.65]");
}

// lateral_offset with continuous: true holds its offset and never ends on its own (OpenSCENARIO's
// continuous LaneOffsetAction): its end, and an `after` on it, come where a later lateral action
// replaces it (4 s), not where it has got there (2 s); never replaced, it never ends.
TEST(ScriptedTraffic, AContinuousOffsetEndsOnlyWhereSomethingEndsIt) {
  const auto holder = [](const std::string& more) {
    return R"(
    - {id: holder, s: 100, lane: 0, speed: 10,
       actions: [{id: hold, trigger: {time: 1}, lateral_offset: {offset: 0.5, duration: 1, continuous: true}},
                 {id: after_hold, trigger: {after: hold}, speed: {target: 5, rate: 5}})" +
           more + "]}";
  };
  const auto replaced =
      timingsAfter(plan(scenarioWith(holder(", {trigger: {time: 4}, lateral_offset: {offset: 0, duration: 1}}"))), 40);
  EXPECT_NEAR(replaced[0].end, 4.0, 1e-9);
  EXPECT_NEAR(replaced[1].start, 4.0, 1e-9);
  const Planned never = plan(scenarioWith(holder("")));
  const auto held = timingsAfter(never, 40);
  EXPECT_TRUE(std::isinf(held[0].end));
  EXPECT_TRUE(std::isnan(held[1].start));
  EXPECT_NEAR(offsetOf(never.road, never.paths[0].back()), -3.0, 1e-9);
}

// An action's `ends` end the listed actions under way where it starts (OpenSCENARIO's Event
// priority overwrite): their road user keeps the speed and the place across the road they have
// reached. By hand: the tracker follows 1.5 times the lead's speed one step behind (10 + t m/s),
// until the swerve at 2.2 s ends that: 1.5 * 12 = 18 m/s from then on. The drifter's smooth
// lane change to lane 1 (3.5 m left) over 4 s from 1 s stops at 2 s, 3.5 * 0.5 * (1 - cos(pi / 4))
// m left of lane 0's centre (y = -3.5), still in lane 0: its offset at 5 s, not under way at 2 s,
// counts from lane 0's centre (so does an offset that replaces such a lane change: 'replaced').
// An offset ended half-way leaves its road user in its lane, though beside it, as esmini keeps
// its lane id: the nudger's 3 m swerve right from lane 2 (y = 3.5), stopped at 2.6 s, and the
// offset 0 after it bring it back to lane 2's centre.
TEST(ScriptedTraffic, AnActionEndsTheListedActionsUnderWayWhereItStarts) {
  const Planned run = plan(scenarioWith(R"(
    - {id: lead, s: 150, lane: 1, speed_profile: {initial: 10, phases: [{duration: 10, accel: 1}]}}
    - {id: tracker, s: 100, lane: 2, speed: 3,
       actions: [{id: track, speed: {relative_factor: 1.5, to: lead, continuous: true, shape: step}},
                 {id: swerve, trigger: {time: 2.2}, lateral_offset: {offset: 0.5, duration: 1}, ends: [track]}]}
    - {id: drifter, s: 60, lane: 0, speed: 10,
       actions: [{id: drift, trigger: {time: 1}, lane_change: {lane: 1, duration: 4}},
                 {id: slow, trigger: {time: 2}, speed: {target: 5, rate: 1}, ends: [drift, later, swerve]},
                 {id: later, trigger: {time: 5}, lateral_offset: {offset: 0.5, duration: 1}}]}
    - {id: replaced, s: 250, lane: 0, speed: 10,
       actions: [{trigger: {time: 1}, lane_change: {lane: 1, duration: 4}},
                 {trigger: {time: 2}, lateral_offset: {offset: 0.3, duration: 1}}]}
    - {id: nudger, s: 20, lane: 2, speed: 10,
       actions: [{id: wide, trigger: {time: 1}, lateral_offset: {offset: -3, duration: 2}},
                 {trigger: {time: 2.6}, speed: {target: 8, rate: 1}, ends: [wide]},
                 {trigger: {time: 4}, lateral_offset: {offset: 0, duration: 1}}]})",
                                        0.0, 8.0));
  const auto& tracker = run.paths[1];
  EXPECT_NEAR(tracker[11].speed, 18.0, 1e-9);
  EXPECT_NEAR(tracker[20].speed, 18.0, 1e-9);
  EXPECT_NEAR(tracker[40].speed, 18.0, 1e-9);
  const auto& drifter = run.paths[2];
  const double stopped = -3.5 + 3.5 * 0.5 * (1.0 - std::cos(kPi / 4.0));
  EXPECT_NEAR(offsetOf(run.road, drifter[15]), stopped, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, drifter[24]), stopped, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, drifter[30]), -3.0, 1e-9);
  EXPECT_NEAR(drifter[20].speed, 10.0 - 1.0 * 2.0, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, run.paths[3][20]), -3.2, 1e-9);
  EXPECT_NEAR(offsetOf(run.road, run.paths[4][15]), 3.5 - 3.0 * 0.5 * (1.0 - std::cos(0.8 * kPi)), 1e-9);
  EXPECT_NEAR(offsetOf(run.road, run.paths[4][30]), 3.5, 1e-9);
  const auto timings = timingsAfter(run, 40);  // track, swerve, drift, slow, later
  EXPECT_NEAR(timings[0].end, 2.2, 1e-9);
  EXPECT_NEAR(timings[1].end, 3.2, 1e-9);  // the swerve, listed by slow, was not under way at 2 s
  EXPECT_NEAR(timings[2].end, 2.0, 1e-9);
  EXPECT_NEAR(timings[4].start, 5.0, 1e-9);
  // An id the file does not have is one line.
  const std::string refused = refusalOf("    - {id: a, s: 60, lane: 0, speed: 10,\n"
                                        "       actions: [{id: go, speed: {target: 5, rate: 1}, ends: [gone]}]}");
  EXPECT_NE(refused.find("actions[0].ends: got 'gone', expected the id of another action of the file: go"),
            std::string::npos)
      << refused;
}

// shape: cubic follows 3 tau^2 - 2 tau^3 (OpenSCENARIO's cubic, as esmini evaluates it), paced as
// esmini paces it. By hand: 10 -> 16 m/s at a peak 3 m/s^2 lasts 1.5 * 6 / 3 = 3 s from 1 s; a
// lane change of 3.5 m at a peak 1.75 m/s lasts 1.5 * 3.5 / 1.75 = 3 s from 1 s; an offset of
// 0.6 m at a peak 1.2 m/s^2 lasts sqrt(6 * 0.6 / 1.2) = sqrt(3) s from 1 s. A linear offset paced
// by a lateral acceleration (it has no peak: its speed jumps) lasts as long, as esmini paces it.
TEST(ScriptedTraffic, ACubicChangeFollowsItsPolynomialAtItsPace) {
  const Planned run = plan(scenarioWith(R"(
    - {id: speeder, s: 100, lane: 2, speed: 10,
       actions: [{trigger: {time: 1}, speed: {target: 16, rate: 3, shape: cubic}}]}
    - {id: changer, s: 150, lane: 0, speed: 10,
       actions: [{trigger: {time: 1}, lane_change: {lanes: 1, lateral_speed: 1.75, shape: cubic}}]}
    - {id: swerver, s: 200, lane: 2, speed: 10,
       actions: [{trigger: {time: 1}, lateral_offset: {offset: 0.6, lateral_accel: 1.2, shape: cubic}}]}
    - {id: linear, s: 250, lane: 2, speed: 10,
       actions: [{trigger: {time: 1}, lateral_offset: {offset: 0.6, lateral_accel: 1.2, shape: linear}}]})",
                                        0.0, 6.0));
  const auto cubic = [](double tau) { return tau * tau * (3.0 - 2.0 * tau); };
  for (const int k : {5, 8, 10, 13, 20}) {
    const double tau = std::clamp((0.2 * k - 1.0) / 3.0, 0.0, 1.0);
    EXPECT_NEAR(run.paths[0][static_cast<std::size_t>(k)].speed, 10.0 + 6.0 * cubic(tau), 1e-9) << "instant " << k;
    EXPECT_NEAR(offsetOf(run.road, run.paths[1][static_cast<std::size_t>(k)]), -3.5 + 3.5 * cubic(tau), 1e-9)
        << "instant " << k;
    const double share = std::clamp((0.2 * k - 1.0) / std::sqrt(3.0), 0.0, 1.0);
    EXPECT_NEAR(offsetOf(run.road, run.paths[2][static_cast<std::size_t>(k)]), 3.5 + 0.6 * cubic(share), 1e-9)
        << "instant " << k;
    EXPECT_NEAR(offsetOf(run.road, run.paths[3][static_cast<std::size_t>(k)]), 3.5 + 0.6 * share, 1e-9)
        << "instant " << k;
  }
}

// The Ego's set_speed actions start like any action and hand their target to its controller
// from their start on: one at t = 2.1 s (between instants), one when the gap to 'a' (40 m
// at t = 0, closing at 10 - 5 = 5 m/s) is at most 20.5 m, i.e. at the instant t = 4.0 s.
TEST(ScriptedTraffic, TheEgosSetSpeedActionsCommandItsSetSpeedFromTheirStart) {
  const Planned run = egoWith("set_speeds", 10, R"([
      {id: slower, trigger: {time: 2.1}, set_speed: {target: 7}},
      {trigger: {gap: 20.5, to: a}, set_speed: {target: 4}}])",
                               R"(    - {id: a, gap: 40, relative_lane: 0, speed: 5,
       actions: [{trigger: {after: slower}, lateral_offset: {offset: 0.5, duration: 1}}]}
)");
  ScriptedTraffic traffic(run.concrete, run.road);
  const EgoStandIn ego(run.concrete, run.road);
  EXPECT_FALSE(traffic.egoSetSpeedAt(0.0));
  std::vector<std::optional<double>> commanded;  // what the Ego's controller sees at instant k
  for (int k = 0; k < 30; ++k) {
    traffic.step(ego.at(0.2 * k));
    commanded.push_back(traffic.egoSetSpeedAt(0.2 * k));
  }
  for (int k = 0; k < 30; ++k) {
    const double t = 0.2 * k;
    const std::optional<double> expected =
        t < 2.1 ? std::nullopt : t < 4.0 - 1e-9 ? std::optional<double>(7.0) : std::optional<double>(4.0);
    EXPECT_EQ(commanded[static_cast<std::size_t>(k)], expected) << "t = " << t;
  }
  EXPECT_EQ(traffic.egoSetSpeedAt(2.1), std::optional<double>(7.0));
  const auto& timings = traffic.timings();  // a's lateral offset, then the Ego's two
  EXPECT_NEAR(timings[1].start, 2.1, 1e-9);
  EXPECT_NEAR(timings[1].end, 2.1, 1e-9);
  EXPECT_NEAR(timings[0].start, 2.1, 1e-9);  // `after` a set speed: at once
  EXPECT_NEAR(timings[2].start, 4.0, 1e-9);
}

// The Ego's lateral actions end where a later one, or a teleport of it, replaces them; the lane
// its controller keeps is the latest one's. By hand, 3 lanes of 3.5 m (lane 1's centre on the
// road's centre line, lane 2's 3.5 m left): the lane change from 1 s (3 s) is replaced at 2 s
// by the offset (4 s), which the teleport at 5.1 s replaces: the Ego lands on lane 0's centre,
// put at the instant 5.0 s 1 m before it (10 m/s), and keeps that lane from then on. 'a' hops at
// 5.15 s to 10 m ahead of the Ego, one lane left, where the Ego is then (20.5 m): later in the
// same step, it sees the Ego where it was put; at 5 m/s it is at 30.5 + 5 * 2.85 m at 8 s.
TEST(ScriptedTraffic, TheEgosLateralActionsEndWhereALaterOneOrATeleportReplacesThem) {
  const Planned run = egoWith("ego_moves", 8, R"([
      {id: left, trigger: {time: 1}, lane_change: {lanes: 1, duration: 3}},
      {id: nudge, trigger: {time: 2}, lateral_offset: {offset: 0.5, duration: 4}},
      {id: back, trigger: {time: 5.1}, teleport: {s: 20, lane: 0}}])",
                               R"(    - {id: a, s: 100, lane: 0, speed: 5,
       actions: [{id: after_left, trigger: {after: left}, lateral_offset: {offset: 0.5, duration: 1}},
                 {id: hop, trigger: {time: 5.15}, teleport: {from: ego, ds: 10, lanes: 1}}]}
)");
  ScriptedTraffic traffic(run.concrete, run.road);
  const EgoStandIn ego(run.concrete, run.road);
  std::map<std::string, ScriptedTraffic::ActionTiming> timing_of;
  for (int k = 0; k < 40; ++k) {
    traffic.step(ego.at(0.2 * k));
    EXPECT_EQ(traffic.egoTeleported().has_value(), k == 25) << "instant " << k;
    if (k == 25) {
      const road::LaneFrame frame(run.road.centre);
      const auto [s, d] = frame.coordinates(traffic.egoTeleported()->position());
      EXPECT_NEAR(s - frame.coordinates(ego.at(0.0).position()).first, 20.0 - 30.0 - 1.0, 1e-6);
      EXPECT_NEAR(d, -3.5, 1e-9);
    }
  }
  const road::LaneFrame frame(run.road.centre);
  const auto [a_s, a_d] = frame.coordinates(traffic.states()[0].position());
  EXPECT_NEAR(a_s - frame.coordinates(ego.at(0.0).position()).first + 30.0, 30.5 + 5.0 * 2.85, 1e-6);
  EXPECT_NEAR(a_d, 0.0, 1e-9);
  for (std::size_t a = 0; a < run.concrete.actions.size(); ++a) {
    timing_of[run.concrete.actions[a].id] = traffic.timings()[a];
  }
  EXPECT_NEAR(timing_of["left"].end, 2.0, 1e-9);
  EXPECT_NEAR(timing_of["after_left"].start, 2.0, 1e-9);
  EXPECT_NEAR(timing_of["nudge"].end, 5.1, 1e-9);
  EXPECT_NEAR(timing_of["back"].start, 5.1, 1e-9);
  EXPECT_NEAR(*traffic.egoLaneOffsetAt(1.9), 3.5 * 0.5 * (1.0 - std::cos(kPi * 0.9 / 3.0)), 1e-9);
  EXPECT_NEAR(*traffic.egoLaneOffsetAt(5.0), -3.5, 1e-9);  // from the instant it is put there
  EXPECT_NEAR(*traffic.egoLaneOffsetAt(7.8), -3.5, 1e-9);
  // An action that ends the offset at 3 s (`ends`) leaves the kept lane where the move has got
  // to: from 0.875 m (where the lane change was at 2 s, still in lane 1, whose centre the offset
  // counts from, as esmini finds the lane from where it is) towards 0.5 m, a quarter of its 4 s.
  const Planned halted = egoWith("ego_halted", 8, R"([
      {id: left, trigger: {time: 1}, lane_change: {lanes: 1, duration: 3}},
      {id: nudge, trigger: {time: 2}, lateral_offset: {offset: 0.5, duration: 4}}])",
                                 "    - {id: a, s: 100, lane: 0, speed: 5, actions: [{id: halt, trigger: {time: 3}, "
                                 "speed: {target: 0, rate: 5}, ends: [nudge]}]}\n");
  ScriptedTraffic halting(halted.concrete, halted.road);
  const EgoStandIn stand_in(halted.concrete, halted.road);
  for (int k = 0; k < 25; ++k) halting.step(stand_in.at(0.2 * k));
  const double at_two = 3.5 * 0.5 * (1.0 - std::cos(kPi / 3.0));
  EXPECT_NEAR(*halting.egoLaneOffsetAt(4.6), at_two + (0.5 - at_two) * 0.5 * (1.0 - std::cos(kPi / 4.0)), 1e-9);
  EXPECT_NEAR(halting.timings()[2].end, 3.0, 1e-9);  // a's halt, then the Ego's: left, nudge
}

// OpenSCENARIO's rising edge: a condition that holds when first checked waits until it has
// stopped holding. The mover starts 30 m behind the stand-in Ego (centres), 5 m/s faster,
// one lane to its right: its gap to the Ego is >= 10 m at once, then it draws level, and the
// gap is 10 m again once it is ahead by 10 m plus the two half lengths.
TEST(ScriptedTraffic, ARisingTriggerWaitsForItsConditionToBecomeTrue) {
  for (const bool rising : {false, true}) {
    const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, ds: -30, relative_lane: -1, speed: 15,
       actions: [{{trigger: {{gap_at_least: 10, rising: {}}}, lane_change: {{ego_lane: 0, duration: 2}}}}]}})",
                                                  rising ? "true" : "false"),
                                      0.0, 14.0);
    const Planned run = plan(logical);
    const auto timings = timingsAfter(run, 70);
    if (!rising) {
      EXPECT_DOUBLE_EQ(timings[0].start, 0.0);
      continue;
    }
    const double half_lengths = 0.5 * (run.concrete.ego.length + run.concrete.others[0].length);
    const double expected = (30.0 + 10.0 + half_lengths) / 5.0;  // s: 40 m plus the half lengths at 5 m/s
    EXPECT_GE(timings[0].start, expected - 1e-9);
    EXPECT_LT(timings[0].start, expected + 0.2 + 1e-9);  // the first instant at or after it
  }
}

// A falling trigger fires when its condition stops holding (OpenSCENARIO's falling edge), and
// one both rising and falling at either change. The stand-in Ego (10 m/s) closes on a standing
// mover 35 m ahead: the gap is at least 20 m until 1.5 s, so the falling edge is seen at the
// instant 1.6 s (instants every 0.2 s); the either-edge on the gap within 10.5 m rises at the
// instant 2.6 s (gap 9 m). A time or an action's end holds from a moment on: an edge on it is
// refused.
TEST(ScriptedTraffic, AFallingTriggerFiresWhenItsConditionStopsHolding) {
  const auto logical = scenarioWith(R"(
    - {id: mover, gap: 35, relative_lane: 0, speed: 0,
       actions: [{trigger: {gap_at_least: 20, falling: true}, stop: {decel: 1}},
                 {trigger: {gap: 10.5, rising: true, falling: true}, speed: {target: 1, rate: 1}}]})",
                                    0.0, 10.0);
  const auto timings = timingsAfter(plan(logical), 20);
  EXPECT_NEAR(timings[0].start, 1.6, 1e-9);
  EXPECT_NEAR(timings[1].start, 2.6, 1e-9);
  const std::string error = refusalOf("    - {id: mover, gap: 35, relative_lane: 0, speed: 0,\n"
                                      "       actions: [{trigger: {time: 1, falling: true}, stop: {decel: 1}}]}");
  EXPECT_NE(error.find("trigger.falling: 'falling' goes with a condition (not time, after, all or any"),
            std::string::npos)
      << error;
}

// A speed change over a distance (OpenSCENARIO's dynamicsDimension="distance") lasts 2 d / (v0 + v1):
// linear and smooth profiles both average the two speeds. By hand: from 20 to 10 m/s over 60 m
// takes 4 s, from t = 1 s to 5 s, and covers 60 m; a stop from 20 m/s within 30 m takes 3 s.
TEST(ScriptedTraffic, ASpeedChangeOverADistanceCoversThatDistance) {
  for (const std::string shape : {"linear", "smooth"}) {
    const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, s: 60, lane: 2, speed: 20,
       actions: [{{trigger: {{time: 1}}, speed: {{target: 10, distance: 60, shape: {0}}}}}]}}
    - {{id: stopper, s: 60, lane: 0, speed: 20,
       actions: [{{trigger: {{time: 1}}, stop: {{distance: 30, shape: {0}}}}}]}}
    - {{id: keeper, s: 90, lane: 0, speed: 20,
       actions: [{{trigger: {{time: 1}}, speed: {{target: 20, distance: 60, shape: {0}}}}}]}})",
                                                  shape),
                                      0.0, 8.0);
    const auto [traffic, place] = stepped(plan(logical), 30);
    EXPECT_NEAR(traffic.timings()[0].start, 1.0, 1e-9) << shape;
    EXPECT_NEAR(traffic.timings()[0].end, 5.0, 1e-9) << shape;
    EXPECT_NEAR(traffic.timings()[1].end, 4.0, 1e-9) << shape;
    EXPECT_NEAR(traffic.timings()[2].end, 1.0, 1e-9) << shape;  // no change: it ends at once (as esmini)
    EXPECT_NEAR(place[25][0].first - place[5][0].first, 60.0, 0.05) << shape;
    EXPECT_NEAR(place[25][1].first - place[5][1].first, 30.0, 0.05) << shape;
    EXPECT_NEAR(traffic.states()[0].speed, 10.0, 1e-9) << shape;
    EXPECT_NEAR(traffic.states()[1].speed, 0.0, 1e-9) << shape;
  }
  const auto refused = [](const std::string& speed) {
    return test::configErrorOf([&] {
      scenarioWith("    - {id: mover, s: 60, lane: 2, speed: 20,\n"
                   "       actions: [{trigger: {time: 1}, speed: " + speed + "}]}");
    });
  };
  EXPECT_NE(refused("{target: 10, distance: 0}").find("speed.distance"), std::string::npos);
  EXPECT_NE(refused("{target: 10, distance: 5, shape: step}").find("a step changes the speed at once"),
            std::string::npos);
}

namespace {

/// The start times (s) each of the first `actions` actions of `traffic` has had, one per run,
/// over `steps` steps of 0.2 s beside the stand-in Ego of `run`.
std::vector<std::vector<double>> runStarts(const Planned& run, ScriptedTraffic& traffic, int steps,
                                           std::size_t actions) {
  const EgoStandIn ego(run.concrete, run.road);
  std::vector<std::vector<double>> starts(actions);
  for (int k = 0; k < steps; ++k) {
    traffic.step(ego.at(0.2 * k));
    for (std::size_t a = 0; a < actions; ++a) {
      const double start = traffic.timings()[a].start;
      if (!std::isnan(start) && (starts[a].empty() || starts[a].back() != start)) starts[a].push_back(start);
    }
  }
  return starts;
}

}  // namespace

// OpenSCENARIO's maximumExecutionCount: an action starts again once it has ended and its
// trigger fires again, up to `repeat` times. The stand-in Ego (10 m/s) closes on a standing
// mover; within 20 m the mover speeds off to 20 m/s, beyond 30 m it stops again, and so on.
TEST(ScriptedTraffic, ARepeatedActionStartsAgainUpToItsRepeatCount) {
  for (const int repeat : {1, 3}) {
    const auto logical = scenarioWith(fmt::format(R"(
    - {{id: mover, gap: 35, relative_lane: 0, speed: 0,
       actions: [{{id: go, repeat: {0}, trigger: {{gap: 20, rising: true}},
                   speed: {{target: 20, rate: 10, shape: linear}}}},
                 {{id: halt, repeat: {0}, trigger: {{gap_at_least: 30, rising: true}},
                   stop: {{decel: 10, shape: linear}}}}]}})",
                                                  repeat),
                                      0.0, 40.0);
    const Planned run = plan(logical);
    ScriptedTraffic traffic(run.concrete, run.road);
    const auto starts = runStarts(run, traffic, 200, 2);
    ASSERT_EQ(starts[0].size(), static_cast<std::size_t>(repeat)) << "go";
    ASSERT_EQ(starts[1].size(), static_cast<std::size_t>(repeat)) << "halt";
    for (int n = 0; n < repeat; ++n) {
      EXPECT_LT(starts[0][n], starts[1][n]);                    // go, then halt, in turns
      if (n > 0) {
        EXPECT_GT(starts[0][n], starts[1][n - 1] + 2.0 - 1e-9);  // after the halt before it ended
      }
    }
    EXPECT_DOUBLE_EQ(traffic.states()[0].speed, 0.0);  // halted for good after its last start
  }
}

// A repeated action whose trigger is a moment that has come (a time, an action's end) starts
// again where its run ends, as esmini restarts an Event whose start still holds (an empty
// StartTrigger). `after` fires at the first end of a repeated action (inside `all` too: a moment
// that stays while it runs again), `after` with `last: true` at the end of its last run
// (OpenSCENARIO's completeState); a delay on an `after` inside `all` is a later moment. By hand:
// +2 m/s over 1 s from t = 1, three times: runs [1, 2], [2, 3], [3, 4], 10 -> 16 m/s; `first`
// starts at 2, `mid` at the first instant the mover has 14.9 m/s (3.6 s: 15.2), `done` at 4,
// `later` at 4 + 1.6 = 5.6 s.
TEST(ScriptedTraffic, ARepeatedActionOnAMomentStartsAgainAtItsEndAndLastWaitsForItsLastRun) {
  const auto logical = scenarioWith(R"(
    - {id: mover, s: 60, lane: 0, speed: 10,
       actions: [{id: speed_up, repeat: 3, trigger: {time: 1}, speed: {delta: 2, duration: 1, shape: linear}}]}
    - {id: watcher, s: 60, lane: 2, speed: 10,
       actions: [{id: first, trigger: {after: speed_up}, speed: {delta: 1, duration: 0.4}},
                 {id: done, trigger: {after: speed_up, last: true}, speed: {delta: 1, duration: 0.4}},
                 {id: later, speed: {delta: 1, duration: 0.4},
                  trigger: {all: [{after: speed_up, last: true, delay: 1.6}, {speed_at_least: 15.9, of: mover}]}},
                 {id: mid, trigger: {all: [{after: speed_up}, {speed_at_least: 14.9, of: mover}]},
                  speed: {delta: 1, duration: 0.4}}]})",
                                    0.0, 10.0);
  const Planned run = plan(logical);
  ScriptedTraffic traffic(run.concrete, run.road);
  const auto runs = runStarts(run, traffic, 40, 1).front();
  ASSERT_EQ(runs.size(), 3u);
  for (std::size_t n = 0; n < 3; ++n) EXPECT_NEAR(runs[n], 1.0 + static_cast<double>(n), 1e-9) << n;
  EXPECT_NEAR(traffic.timings()[0].end, 4.0, 1e-9);
  EXPECT_NEAR(traffic.states()[0].speed, 16.0, 1e-9);
  EXPECT_NEAR(traffic.timings()[1].start, 2.0, 1e-9);
  EXPECT_NEAR(traffic.timings()[2].start, 4.0, 1e-9);
  EXPECT_NEAR(traffic.timings()[3].start, 5.6, 1e-9);
  EXPECT_NEAR(traffic.timings()[4].start, 3.6, 1e-9);
  EXPECT_NEAR(traffic.states()[1].speed, 14.0, 1e-9);
}

// An `after` with `last: true` waits for the last run itself, not the end of the run before it
// when that run is replaced: `a` (twice) is replaced by `c` at 1 s, starts again there (the
// instant it ended at) and replaces `c`, and runs to 3 s; `b` starts there (before, an `any`
// offered while `a` started again saw the replaced run's end, 1 s, and started at once).
TEST(ScriptedTraffic, ALastRunIsWaitedForWhenTheRunBeforeItWasReplaced) {
  const auto logical = scenarioWith(R"(
    - {id: mover, s: 60, lane: 0, speed: 10,
       actions: [{id: a, repeat: 2, trigger: {time: 0}, speed: {target: 25, duration: 2}},
                 {id: c, trigger: {time: 1}, speed: {target: 15, duration: 5}},
                 {id: b, trigger: {any: [{after: a, last: true}, {gap_at_least: 500}]},
                  lateral_offset: {offset: 0.5, duration: 1}}]})",
                                    0.0, 10.0);
  const Planned run = plan(logical);
  ScriptedTraffic traffic(run.concrete, run.road);
  const auto starts = runStarts(run, traffic, 30, 3);
  ASSERT_EQ(starts[0].size(), 2u);
  EXPECT_NEAR(starts[0][1], 1.0, 1e-9);
  ASSERT_EQ(starts[2].size(), 1u);
  EXPECT_NEAR(starts[2][0], 3.0, 1e-9);
}

// A repeated action's rising conditions start afresh when it is re-armed (esmini resets a
// trigger's conditions when it fires): the first check after its end never fires. The stand-in
// Ego (10 m/s) has travelled 10 m at 1 s, which starts the 4 s offset; meanwhile the gap to the
// standing mover falls to 30 m (3 s). At the re-arm (5 s) the gap condition holds, but it rose
// while nobody checked it, and it holds from then on: the action does not start again.
TEST(ScriptedTraffic, ARepeatedActionsRisingConditionsStartAfreshWhenItIsReArmed) {
  const auto logical = scenarioWith(R"(
    - {id: mover, gap: 60, relative_lane: 0, speed: 0,
       actions: [{id: dodge, repeat: 2, lateral_offset: {offset: 0.5, duration: 4},
                  trigger: {any: [{gap: 30, rising: true}, {travelled: 10, of: ego, rising: true}]}}]})",
                                    0.0, 10.0);
  const Planned run = plan(logical);
  ScriptedTraffic traffic(run.concrete, run.road);
  const auto starts = runStarts(run, traffic, 50, 1).front();
  ASSERT_EQ(starts.size(), 1u);
  EXPECT_NEAR(starts[0], 1.0, 0.2 + 1e-9);
}
