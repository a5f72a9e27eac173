#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <regex>
#include <tuple>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

using namespace vsd;
using namespace vsd::scenario;
using ::testing::HasSubstr;

namespace {

std::string yamlWith(const std::string& others, const std::string& inputs = "", const std::string& road = "") {
  return fmt::format(R"(
name: users
inputs: [{}]
road: {{shape: arc, length: 200, lanes: 3{}}}
vehicles:
  ego: {{s: 20, lane: 1, speed: 10, controller: {{name: idm}}}}
  others:
{}
)",
                     inputs, road, others);
}

/// The message of the ConfigError loading (and sampling sample 0 of) a file with these other
/// road users throws; "" if none.
std::string errorOf(const std::string& others, const std::string& road = "") {
  try {
    const auto logical = parseLogicalScenario(yamlWith(others, "", road), "bad.yaml");
    sampleConcreteScenario(logical, 1, 0);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

}  // namespace

TEST(RoadUsers, EveryLibraryScenarioLoadsAndSamples) {
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::sourceDir() / "scenarios" / "alks")) {
    const auto logical = loadLogicalScenario(entry.path());
    for (std::uint64_t i = 0; i < 50; ++i) {
      const auto concrete = sampleConcreteScenario(logical, 1, i);
      EXPECT_EQ(concrete.others.size(), logical->others.size()) << entry.path();
    }
    ++files;
  }
  EXPECT_EQ(files, 15u);  // the fifteen functional scenarios of docs/alks-scenarios.md
}

TEST(RoadUsers, TypesSizesAndRelativePlacesResolvePerSample) {
  const auto logical = parseLogicalScenario(
      yamlWith("    - {id: t, type: truck, gap: 12, relative_lane: side, relative_speed: -2, width: 2.4}",
               "{name: side, choices: [1, -1]}"),
      "ok.yaml");
  const auto concrete = sampleConcreteScenario(logical, 1, 0);
  const auto& truck = concrete.others[0];
  EXPECT_EQ(truck.type, RoadUserType::Truck);
  EXPECT_EQ(truck.length, roadUserKind(RoadUserType::Truck).length);  // from the table
  EXPECT_EQ(truck.width, 2.4);                                        // given
  EXPECT_EQ(truck.lane, 1 + static_cast<int>(concrete.inputs[0]));
  EXPECT_EQ(truck.speed, 8.0);
  EXPECT_EQ(truck.along, VehicleSpec::Along::EgoGap);
}

// The issue's list of bad input: one line naming file, field, value and what is allowed.
TEST(RoadUsers, ATriggerNamingAMissingRoadUserOrActionIsRefused) {
  const auto missing_user = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{trigger: {gap: 10, to: ghost}, stop: {decel: 3}}]})");
  EXPECT_NE(missing_user.find("bad.yaml:"), std::string::npos) << missing_user;
  EXPECT_NE(missing_user.find("vehicles.others[0].actions[0].trigger.to: got 'ghost', expected another road user of "
                              "the file: ego, a"),
            std::string::npos)
      << missing_user;
  const auto missing_action = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{trigger: {after: nothing}, stop: {decel: 3}}]})");
  EXPECT_NE(missing_action.find("trigger.after: got 'nothing'"), std::string::npos) << missing_action;
}

TEST(RoadUsers, ACycleOfTriggersIsRefused) {
  const auto error = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{id: one, trigger: {after: two}, stop: {decel: 3}},
                 {id: two, trigger: {after: one}, speed: {target: 4, rate: 1}}]})");
  EXPECT_NE(error.find("a cycle of triggers (one -> two -> one)"), std::string::npos) << error;
}

// Triggers on motion and their combinations: bad input is one line naming the field, the
// value and what is allowed.
// A headway's `of` says whose headway counts: one of the two road users it relates.
TEST(RoadUsers, AHeadwayIsOfOneOfItsTwoRoadUsers) {
  const auto error = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{id: one, trigger: {headway: 1, of: b}, stop: {decel: 3}}]}
    - {id: b, gap: 40, relative_lane: 1, speed: 5})");
  EXPECT_NE(error.find("actions[0].trigger.of: got 'b', expected one of the headway's two road users: 'a' or 'ego'"),
            std::string::npos)
      << error;
}

TEST(RoadUsers, BadMotionTriggersAreRefused) {
  const auto with = [](const std::string& trigger) {
    return errorOf(fmt::format(R"(    - {{id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{{id: one, trigger: {}, stop: {{decel: 3}}}}]}})",
                               trigger));
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{speed_at_least: 5, of: ghost}", "actions[0].trigger.of: got 'ghost', expected a road user of the file: ego, a"},
      {"{relative_speed_at_least: 1, of: ego}", "trigger.to: got 'ego', expected another road user of the file"},
      {"{distance_at_most: -1, position: {s: 10, lane: 0}}", "trigger.distance_at_most"},
      {"{travelled: -3}", "trigger.travelled"},
      {"{all: []}", "trigger.all: expected a non-empty list of triggers"},
      {"{any: [{time: 1}, {all: [{gap: 5, delay: 1}]}]}",
       "trigger.any[1].all[0].delay: a delay on a condition inside 'all' (its members hold at one instant; a time or "
       "after may have one, a later moment): put it on the 'all'"},
      {"{speed_at_least: 5, position: {s: 1, lane: 0}}", "'position' goes with distance_at_most and distance_at_least"},
      {"{distance_at_least: 5}", "'position' goes with distance_at_most and distance_at_least"},
      {"{distance_at_most: 1, position: {s: 10}}", "trigger.position: expected {s, lane[, offset]} along the road or {x, y}"},
      {"{speed_at_least: 5, to: ego}", "trigger.to: 'to' names the other road user of a gap, headway, ttc or relative_speed"},
      {"{gap: 5, of: ego}", "trigger.of: 'of' names whose speed, acceleration, distance, road end or headway"},
      {"{distance_at_most: 1, position: {s: 10, lane: 3}}",
       "trigger.position.lane: got 3 in sample 0, expected a lane the road has (0 .. 2)"},
      {"{fast: 3}", "trigger.fast: unknown key 'fast' (allowed: accel_at_least"},
  };
  for (const auto& [trigger, message] : cases) {
    const std::string error = with(trigger);
    EXPECT_NE(error.find("bad.yaml:"), std::string::npos) << trigger << ": " << error;
    EXPECT_NE(error.find(message), std::string::npos) << trigger << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  // A cycle through an `all` (each member is needed) is a cycle; through an `any` it is not.
  const auto cycle = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{id: one, trigger: {all: [{after: two}, {time: 1}]}, stop: {decel: 3}},
                 {id: two, trigger: {after: one}, speed: {target: 4, rate: 1}}]})");
  EXPECT_NE(cycle.find("a cycle of triggers (one -> two -> one)"), std::string::npos) << cycle;
  EXPECT_EQ(errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{id: one, trigger: {any: [{after: two}, {time: 1}]}, stop: {decel: 3}},
                 {id: two, trigger: {after: one}, speed: {target: 4, rate: 1}}]})"),
            "");
}

// The Ego's lateral actions count from its own lane or name a lane of the road; the Ego's
// "ego_lane" would be its own, and a lane the road does not have is refused per sample.
TEST(RoadUsers, TheEgosLaneChangesNameItsOwnLaneOrTheRoads) {
  const auto ego_with = [](const std::string& action) {
    try {
      const auto logical = parseLogicalScenario(R"(
name: ego_lanes
time: {step: 0.2, duration: 5}
road: {shape: arc, length: 300, lanes: 3, lane_width: 3.5}
vehicles:
  ego: {s: 30, lane: 1, speed: 20, controller: {name: idm, params: {set_speed: 20}},
        actions: [{trigger: {time: 1}, )" + action + R"(}]}
)",
                                                "ego.yaml");
      sampleConcreteScenario(logical, 1, 0);
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_EQ(ego_with("lane_change: {lanes: -1, duration: 3}"), "");
  EXPECT_EQ(ego_with("lane_change: {lane: 2, shape: step}"), "");
  EXPECT_EQ(ego_with("lateral_offset: {offset: 0.5, duration: 1}"), "");
  EXPECT_NE(ego_with("lane_change: {ego_lane: 1, duration: 3}").find("the Ego's own lane: use lanes"),
            std::string::npos);
  EXPECT_NE(ego_with("lane_change: {lane: 3, duration: 3}")
                .find("vehicles.ego.actions[0].lane_change: got lane 3 in sample 0, that is lane 3; expected a lane "
                      "the road has (0 .. 2)"),
            std::string::npos)
      << ego_with("lane_change: {lane: 3, duration: 3}");
  EXPECT_NE(ego_with("cross: {speed: 1, to_offset: 3}").find("move the lane it keeps (lane_change, lateral_offset)"),
            std::string::npos);
}

TEST(RoadUsers, ALaneChangeToALaneTheRoadDoesNotHaveIsRefused) {
  const auto error = errorOf(R"(    - {id: a, gap: 20, relative_lane: 1, speed: 5,
       actions: [{trigger: {time: 1}, lane_change: {lanes: 1, duration: 3}}]})");
  EXPECT_NE(error.find("vehicles.others[0].actions[0].lane_change: got 1 lanes from lane 2 in sample 0, that is lane "
                       "3; expected a lane the road has (0 .. 2)"),
            std::string::npos)
      << error;
  const auto start = errorOf("    - {id: a, gap: 20, relative_lane: 2, speed: 5}");
  EXPECT_NE(start.find("relative_lane: got '2' = 2 in sample 0 (lane 3 from lane 1), expected a lane the road has"),
            std::string::npos)
      << start;
}

TEST(RoadUsers, NegativeOrNaNSpeedsAreRefused) {
  EXPECT_NE(errorOf("    - {id: a, gap: 20, relative_lane: 0, speed: -1}").find("speed: got '-1'"), std::string::npos);
  const auto relative = errorOf("    - {id: a, gap: 20, relative_lane: 0, relative_speed: -12}");
  EXPECT_NE(relative.find("relative_speed: got '-12' = -2 m/s in sample 0, expected a finite speed >= 0 m/s"),
            std::string::npos)
      << relative;
  const auto nan = errorOf("    - {id: a, gap: 20, relative_lane: 0, speed: sqrt(-1)}");
  EXPECT_NE(nan.find("speed"), std::string::npos) << nan;
}

TEST(RoadUsers, APedestrianNeedsAPlaceToCross) {
  const std::string walker = R"(    - {id: p, type: pedestrian, gap: 20, relative_lane: 0, offset: -6, heading_deg: 90,
       actions: [{trigger: {time: 1}, cross: {speed: 1.4, to_offset: 5}}]})";
  const auto error = errorOf(walker);
  EXPECT_NE(error.find("offset: got -6 m from lane 1's centre in sample 0, 0.75 m beyond the road's right edge where "
                       "road.shoulders.right is 0 m: a pedestrian on a road without a place to cross"),
            std::string::npos)
      << error;
  EXPECT_EQ(errorOf(walker, ", shoulders: {right: 1}"), "");
}

// Road users move along the road at their speed: one facing off it (a pedestrian facing
// across) stands until it crosses. A speed, or a speed action other than holding 0, would slide
// it along the road and turn it there at once; both are refused (the crossing of the test above
// passes, and so does facing along the road).
TEST(RoadUsers, ARoadUserFacingOffTheRoadStandsUntilItCrosses) {
  const std::string walker =
      R"(    - {id: p, type: pedestrian, gap: 20, relative_lane: 0, offset: -1, heading_deg: HEADING,
       speed: SPEED, actions: [{trigger: {time: 1}, ACTION}]})";
  const auto with = [&](const std::string& heading, const std::string& speed, const std::string& action) {
    std::string text = std::regex_replace(walker, std::regex("HEADING"), heading);
    text = std::regex_replace(text, std::regex("SPEED"), speed);
    return errorOf(std::regex_replace(text, std::regex("ACTION"), action));
  };
  const std::string cross = "cross: {speed: 1.4, to_offset: 1}";
  EXPECT_EQ(with("90", "0", cross), "");
  EXPECT_EQ(with("0", "1.5", "speed: {target: 2, duration: 1}"), "");
  EXPECT_EQ(with("90", "0", "speed: {target: 0, duration: 1}"), "");
  EXPECT_THAT(with("90", "1.5", cross), HasSubstr("speed: got 1.5 m/s in sample 0 for a pedestrian facing 90 deg off "
                                                  "the road: road users move along the road"));
  EXPECT_THAT(with("-45", "0", "speed: {target: 2, duration: 1}"),
              HasSubstr("a speed action for a pedestrian facing -45 deg off the road in sample 0"));
}

TEST(RoadUsers, LateralActionsNeedTheExactModel) {
  const auto error = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5, heading_noise_deg: {min: -1, max: 1},
       actions: [{trigger: {time: 1}, lane_change: {lanes: 1, duration: 3}}]})");
  EXPECT_NE(error.find("keeps its lane by pure pursuit"), std::string::npos) << error;
}

TEST(RoadUsers, AVehicleDrivesAgainstTheRoadFacingBack) {
  const auto logical = parseLogicalScenario(yamlWith(R"(
    - {id: a, gap: 50, relative_lane: 1, direction: against, speed: 5}
    - {id: b, gap: 80, relative_lane: 1, direction: along, speed: 5}
    - {id: c, type: model, gap: 110, relative_lane: 0, direction: against, speed: 5})",
                                                     "{name: model, choices: [car, pedestrian]}"),
                                            "oncoming.yaml");
  // A drawn type that is no vehicle is refused in the sample that draws it.
  std::string drawn_error;
  int cars = 0;
  for (std::uint64_t sample = 0; sample < 20; ++sample) {
    try {
      const auto concrete = sampleConcreteScenario(logical, 1, sample);
      EXPECT_TRUE(concrete.others[0].againstRoad);
      EXPECT_DOUBLE_EQ(concrete.others[0].heading, kPi);
      EXPECT_FALSE(concrete.others[1].againstRoad);
      EXPECT_DOUBLE_EQ(concrete.others[1].heading, 0.0);
      EXPECT_EQ(concrete.others[2].type, RoadUserType::Car);
      ++cars;
    } catch (const ConfigError& error) {
      drawn_error = error.what();
    }
  }
  EXPECT_GT(cars, 0);
  EXPECT_NE(drawn_error.find("direction: against with type pedestrian in sample"), std::string::npos) << drawn_error;

  const auto bad = errorOf("    - {id: a, gap: 20, relative_lane: 1, direction: backwards, speed: 5}");
  EXPECT_NE(bad.find("direction: got 'backwards', expected along or against"), std::string::npos) << bad;
  const auto walker = errorOf("    - {id: p, type: pedestrian, gap: 20, relative_lane: 1, direction: against}");
  EXPECT_NE(walker.find("a pedestrian does not drive in a lane"), std::string::npos) << walker;
  const auto noisy = errorOf(
      "    - {id: a, gap: 20, relative_lane: 1, direction: against, speed: 5,\n"
      "       heading_noise_deg: {min: -1, max: 1}}");
  EXPECT_NE(noisy.find("keeps its lane by pure pursuit along the road"), std::string::npos) << noisy;
}

TEST(RoadUsers, BadRelativeSpeedsAndReferencePointsAreRefused) {
  const auto with = [](const std::string& user, const std::string& action) {
    return errorOf(fmt::format(R"(    - {{id: a, gap: 20, relative_lane: 0, speed: 5{},
       actions: [{{id: one, speed: {}}}]}}
    - {{id: b, gap: 40, relative_lane: 1, speed: 5}})",
                               user, action));
  };
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"", "{relative_factor: 1.2, to: ghost, shape: step}",
       "actions[0].speed.to: got 'ghost', expected another road user"},
      {"", "{relative_target: 1, to: a, shape: step}", "actions[0].speed.to: got 'a', expected another road user"},
      {"", "{target: 3, to: b}", "speed.to: goes with relative_target and relative_factor (and only there)"},
      {"", "{delta: 3, continuous: true}", "speed.continuous: goes with relative_target and relative_factor"},
      {"", "{relative_factor: 1.2, to: b, continuous: true, rate: 2}",
       "speed.continuous: a continuous target follows the other's speed at once: shape step"},
      {"", "{relative_factor: 1.2, continuous: yes, shape: step}",
       "speed.continuous: got 'yes', expected true or false"},
      {"", "{relative_factor: -1, shape: step}", "speed.relative_factor"},
      {", reference_point: -2.6", "{target: 3, rate: 1}",
       "reference_point: got -2.6 m in sample 0, expected within half its length (2.5 m) of its centre"},
  };
  for (const auto& [user, action, message] : cases) {
    const std::string error = with(user, action);
    EXPECT_NE(error.find("bad.yaml:"), std::string::npos) << action << ": " << error;
    EXPECT_NE(error.find(message), std::string::npos) << action << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
  const auto between = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{trigger: {speed_at_least: 6, between: reference_points}, stop: {decel: 3}},
                 {trigger: {gap: 6, between: centres}, stop: {decel: 3}}]})");
  EXPECT_NE(between.find("trigger.between: 'between' goes with gap, headway and ttc"), std::string::npos) << between;
  const auto centres = errorOf(R"(    - {id: a, gap: 20, relative_lane: 0, speed: 5,
       actions: [{trigger: {gap: 6, between: centres}, stop: {decel: 3}}]})");
  EXPECT_NE(centres.find("trigger.between: got 'centres', expected bumpers or reference_points"), std::string::npos)
      << centres;
}

TEST(RoadUsers, TheEgosActionsSetItsControllersSetSpeedOnly) {
  const auto yaml = [](const std::string& ego_actions, const std::string& other_actions) {
    return fmt::format(R"(
name: users
road: {{shape: arc, length: 200, lanes: 3}}
vehicles:
  ego: {{s: 20, lane: 1, speed: 10, controller: {{name: idm}}, actions: {}}}
  others:
    - {{id: a, gap: 20, relative_lane: 0, speed: 5, actions: {}}}
)",
                       ego_actions, other_actions);
  };
  const auto logical = parseLogicalScenario(
      yaml("[{id: slower, trigger: {gap: 8, to: a}, set_speed: {target: 4}}, {trigger: {after: slower, delay: 2}, "
           "set_speed: {target: 12}}]",
           "[{id: brake, trigger: {after: slower}, stop: {decel: 2}}]"),
      "ok.yaml");
  const auto concrete = sampleConcreteScenario(logical, 1, 0);
  ASSERT_EQ(concrete.actions.size(), 3u);
  // The others' actions first, the Ego's last: `after` indices count them so.
  EXPECT_EQ(concrete.actions[0].id, "brake");
  EXPECT_EQ(concrete.actions[0].trigger.action, 1);
  EXPECT_EQ(concrete.actions[1].owner, -1);
  EXPECT_EQ(concrete.actions[1].kind, ActionSpec::Kind::SetSpeed);
  EXPECT_DOUBLE_EQ(concrete.actions[1].target, 4.0);
  EXPECT_EQ(concrete.actions[1].trigger.reference, 0);  // its gap to 'a'
  EXPECT_EQ(concrete.actions[2].trigger.action, 1);

  const auto error = [&](const std::string& ego_actions, const std::string& other_actions) {
    try {
      sampleConcreteScenario(parseLogicalScenario(yaml(ego_actions, other_actions), "bad.yaml"), 1, 0);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"[{speed: {target: 3, rate: 1}}]", "[]",
       "vehicles.ego.actions[0].speed: the Ego's controller drives it: the Ego's actions set its controller's set "
       "speed (set_speed)"},
      {"[]", "[{set_speed: {target: 3}}]",
       "actions[0].set_speed: only the Ego has a controller (set_speed and controller are actions of the Ego)"},
      {"[]", "[{controller: {name: idm}}]", "actions[0].controller: only the Ego has a controller"},
      {"[{controller: {name: idm, active_from: 2}}]", "[]",
       "controller.active_from: the action's trigger says when this controller drives"},
      {"[{controller: {params: {a: 1}}}]", "[]", "controller: missing 'name'"},
      {"[{set_speed: {target: -3}}]", "[]", "set_speed.target"},
      {"[{set_speed: {target: 3, rate: 2}}]", "[]", "set_speed"},
      {"[{set_speed: {}}]", "[]", "missing 'target'"},
      {"[{trigger: {gap: 5}, set_speed: {target: 3}}]", "[]",
       "trigger.to: got 'ego', expected another road user of the file"},
  };
  for (const auto& [ego_actions, other_actions, message] : cases) {
    const std::string got = error(ego_actions, other_actions);
    EXPECT_NE(got.find("bad.yaml:"), std::string::npos) << ego_actions << other_actions << ": " << got;
    EXPECT_NE(got.find(message), std::string::npos) << ego_actions << other_actions << ": " << got;
    EXPECT_EQ(got.find('\n'), std::string::npos) << got;
  }
}

TEST(RoadUsers, RepeatedActionsAndRisingTriggersAreReadAndCheckedAtLoad) {
  const auto yaml = [](const std::string& actions) {
    return fmt::format(R"(
name: users
road: {{shape: arc, length: 200, lanes: 3}}
vehicles:
  ego: {{s: 20, lane: 1, speed: 10, controller: {{name: idm}}}}
  others:
    - {{id: a, gap: 20, relative_lane: 0, speed: 5, actions: {}}}
)",
                       actions);
  };
  const auto logical = parseLogicalScenario(
      yaml("[{repeat: 4, trigger: {any: [{gap: 8, rising: true}, {speed_at_least: 9}]}, stop: {decel: 2}}]"),
      "ok.yaml");
  const auto concrete = sampleConcreteScenario(logical, 1, 0);
  ASSERT_EQ(concrete.actions.size(), 1u);
  EXPECT_EQ(concrete.actions[0].repeat, 4);
  EXPECT_TRUE(concrete.actions[0].trigger.members.at(0).rising);
  EXPECT_FALSE(concrete.actions[0].trigger.members.at(1).rising);

  const auto error = [&](const std::string& actions) {
    try {
      parseLogicalScenario(yaml(actions), "bad.yaml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"[{repeat: 0, trigger: {gap: 8}, stop: {decel: 2}}]", "vehicles.others[0].actions[0].repeat"},
      {"[{repeat: 1.5, trigger: {gap: 8}, stop: {decel: 2}}]", "vehicles.others[0].actions[0].repeat"},
      {"[{repeat: 2, trigger: {any: [{gap: 8}, {after: x}]}, stop: {decel: 2}}, {id: x, speed: {target: 3, rate: 1}}]",
       "a repeated action's trigger with a time or after inside 'any': it would start again at a moment that has "
       "passed"},
      {"[{repeat: 2, trigger: {all: [{any: [{time: 1}, {gap: 8}]}, {gap: 3}]}, stop: {decel: 2}}]",
       "a repeated action's trigger with a time or after inside 'any'"},
      {"[{trigger: {gap: 8, last: true}, stop: {decel: 2}}]", "trigger.last: 'last' goes with 'after'"},
      {"[{trigger: {after: x, last: maybe}, stop: {decel: 2}}, {id: x, speed: {target: 3, rate: 1}}]",
       "trigger.last: got 'maybe', expected true or false"},
      {"[{trigger: {time: 1, rising: true}, stop: {decel: 2}}]", "'rising' goes with a condition"},
      {"[{trigger: {all: [{gap: 8}], rising: true}, stop: {decel: 2}}]", "'rising' goes with a condition"},
      {"[{trigger: {gap: 8, rising: yes}, stop: {decel: 2}}]", "true or false"},
  };
  for (const auto& [actions, expected] : cases) {
    const std::string message = error(actions);
    EXPECT_NE(message.find(expected), std::string::npos) << actions << "\n -> " << message;
    EXPECT_NE(message.find("bad.yaml:"), std::string::npos) << message;
  }
}

TEST(RoadUsers, TheEgosControllerActivationIsATimeOfItsOwn) {
  const auto yaml = [](const std::string& active_from) {
    return fmt::format(R"(
name: users
inputs: [{{name: t_on, min: -1, max: -1}}]
road: {{shape: arc, length: 200, lanes: 3}}
vehicles:
  ego: {{s: 20, lane: 1, speed: 10, controller: {{name: idm, active_from: {}}}}}
)",
                       active_from);
  };
  const auto concrete = sampleConcreteScenario(parseLogicalScenario(yaml("2.5"), "ok.yaml"), 1, 0);
  EXPECT_DOUBLE_EQ(concrete.controllerActiveFrom, 2.5);
  const auto error = [&](const std::string& active_from) {
    try {
      sampleConcreteScenario(parseLogicalScenario(yaml(active_from), "bad.yaml"), 1, 0);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("-1").find("vehicles.ego.controller.active_from"), std::string::npos) << error("-1");
  EXPECT_NE(error("t_on").find("active_from: got -1 s in sample 0, expected a time >= 0 s"), std::string::npos)
      << error("t_on");
}
