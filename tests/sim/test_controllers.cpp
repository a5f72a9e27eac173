#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/sim/builtin_controllers.hpp"
#include "vsd/sim/controller.hpp"
#include "vsd/sim/vehicle_model.hpp"

using namespace vsd;
using namespace vsd::sim;

namespace {

std::filesystem::path pluginFile(const std::string& name) { return test::binaryDir() / "plugins" / name; }

/// A car of the object list at bumper gap `gap` ahead, `lateral_gap` beside the Ego's path.
ObservedObject objectAhead(int id, double gap, double speed, double lateral_gap) {
  ObservedObject object;
  object.id = id;
  object.state = {gap + 5.0, lateral_gap + 1.8, 0.0, speed, 0.0};
  object.length = 5.0;
  object.width = 1.8;
  object.relation.longitudinalDistance = gap + 5.0;
  object.relation.longitudinalGap = gap;
  object.relation.lateralDistance = lateral_gap + 1.8;
  object.relation.lateralGap = lateral_gap;
  object.relation.objectOffset = lateral_gap + 1.8;
  object.relation.relativeLane = lateral_gap + 1.8 > 1.75 ? 1 : 0;
  object.relation.inPath = lateral_gap < 0.0;
  return object;
}

/// Observation on a straight lane along +x, Ego at lateral offset `offset`.
Observation straightLane(double speed, double offset) {
  Observation observation;
  observation.ego = {0.0, offset, 0.0, speed, 0.0};
  Observation::Lane lane;
  lane.lateralOffset = offset;
  for (int i = 0; i < kPreviewPoints; ++i) {
    lane.preview[static_cast<std::size_t>(i)] = Vec2(lane.previewSpacing * (i + 1), -offset);
  }
  observation.lane = lane;
  return observation;
}

}  // namespace

TEST(ControllerRegistry, UnknownNameListsTheAvailableControllers) {
  const auto registry = ControllerRegistry::withBuiltins();
  const auto message = test::configErrorOf([&] { registry.create("paper_eggo"); });
  EXPECT_NE(message.find("unknown controller 'paper_eggo'"), std::string::npos) << message;
  EXPECT_NE(message.find("idm, keep_lane, paper_ego"), std::string::npos) << message;
}

TEST(ControllerParams, OutOfRangeAndUnknownParametersAreNamed) {
  auto registry = ControllerRegistry::withBuiltins();
  const auto range = test::configErrorOf([&] {
    makeController(registry, "paper_ego", "", "", ControllerParams({{"time_gap", -2.0}}, "acc.yaml:40: controller"));
  });
  EXPECT_NE(range.find("params.time_gap: got -2"), std::string::npos) << range;
  EXPECT_NE(range.find("acc.yaml:40"), std::string::npos) << range;
  const auto unknown = test::configErrorOf([&] {
    makeController(registry, "paper_ego", "", "", ControllerParams({{"time_gapp", 2.0}}, "controller"));
  });
  EXPECT_NE(unknown.find("params.time_gapp: unknown parameter"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("time_gap"), std::string::npos) << unknown;
}

TEST(ControllerPlugin, ExampleLibraryIsLoadedAndDrives) {
  auto registry = ControllerRegistry::withBuiltins();
  auto controller = makeController(registry, "cautious_ego", test::cautiousEgoPlugin(), "",
                                   ControllerParams({{"time_gap", 3.0}, {"set_speed", 12.0}}, "controller"));
  EXPECT_TRUE(registry.contains("cautious_ego"));
  // Left of the lane centre: steers right. Slower than the set speed: accelerates.
  auto command = controller->step(straightLane(10.0, 0.8), 0.2);
  EXPECT_LT(command.curvature, 0.0);
  EXPECT_GT(command.accel, 0.0);
  // A road user in its path closer than the 3 s gap: brakes.
  Observation close = straightLane(12.0, 0.0);
  close.objects.push_back(objectAhead(1, 15.0, 12.0, -1.8));
  EXPECT_LT(controller->step(close, 0.2).accel, 0.0);
}

// The example built against version 1 of the ABI (the header before the object list):
// it loads, reads the leader and the lane as before, and never gets objects.
TEST(ControllerPlugin, VersionOnePluginLoadsAndDrivesUnchanged) {
  auto registry = ControllerRegistry::withBuiltins();
  auto controller = makeController(registry, "cautious_ego", pluginFile("libvsd_cautious_ego_v1.so"), "",
                                   ControllerParams({{"time_gap", 3.0}, {"set_speed", 12.0}}, "controller"));
  EXPECT_EQ(registry.abiVersion("cautious_ego"), 1);
  EXPECT_FALSE(controller->observesObjects());
  EXPECT_LT(controller->step(straightLane(10.0, 0.8), 0.2).curvature, 0.0);
  Observation close = straightLane(12.0, 0.0);
  close.leader = Observation::Leader{15.0, 12.0, 0.0};
  EXPECT_LT(controller->step(close, 0.2).accel, 0.0);
  // A road user in its path that SUMO does not report as leader does not exist for it.
  Observation cut_in = straightLane(12.0, 0.0);
  cut_in.objects.push_back(objectAhead(1, 10.0, 8.0, -0.5));
  EXPECT_GT(controller->step(cut_in, 0.2).accel, -1e-12);
  std::vector<vsd_object> buffer;
  const auto abi = toAbi(cut_in, 1, buffer);
  EXPECT_EQ(abi.object_count, 0);
  EXPECT_EQ(abi.objects, nullptr);
}

// Built against this header, the same example reads version 2: its leader is the nearest
// road user of the object list in its path.
TEST(ControllerPlugin, VersionTwoPluginFollowsTheObjectList) {
  auto registry = ControllerRegistry::withBuiltins();
  auto controller = makeController(registry, "cautious_ego", test::cautiousEgoPlugin(), "",
                                   ControllerParams({{"time_gap", 3.0}, {"set_speed", 12.0}}, "controller"));
  EXPECT_EQ(registry.abiVersion("cautious_ego"), 2);
  EXPECT_TRUE(controller->observesObjects());
  Observation cut_in = straightLane(12.0, 0.0);
  cut_in.objects.push_back(objectAhead(1, 30.0, 8.0, 1.5));   // beside the path
  cut_in.objects.push_back(objectAhead(2, 10.0, 8.0, -0.5));  // in it
  const double braking = controller->step(cut_in, 0.2).accel;
  EXPECT_NEAR(braking, 0.25 * (10.0 - (3.0 + 3.0 * 12.0)) + 0.6 * (8.0 - 12.0), 1e-9);
  std::vector<vsd_object> buffer;
  const auto abi = toAbi(cut_in, 2, buffer);
  ASSERT_EQ(abi.object_count, 2);
  EXPECT_EQ(abi.objects[1].id, 2);
  EXPECT_EQ(abi.objects[1].in_path, 1);
  EXPECT_EQ(abi.objects[1].longitudinal_gap, 10.0);
  EXPECT_EQ(abi.objects[0].relative_lane, 1);
  EXPECT_EQ(abi.objects[0].type, VSD_OBJECT_CAR);
}

TEST(ControllerPlugin, UnknownAbiVersionIsRefusedWithTheVersionsAllowed) {
  auto registry = ControllerRegistry::withBuiltins();
  const auto message = test::configErrorOf([&] { registry.loadLibrary(pluginFile("libvsd_future_ego.so")); });
  EXPECT_NE(message.find("controller #0 has ABI version 3, expected 1 to 2"), std::string::npos) << message;
}

// A scenario setting that needs the object list (the Ego's sensor) refuses a version-1
// controller in one line: file, field, value and what would be allowed.
TEST(ControllerPlugin, VersionTwoSettingOnAVersionOneControllerIsOneLine) {
  auto registry = ControllerRegistry::withBuiltins();
  const ControllerNeeds needs{2, "scenarios/alks/cut_in.yaml:21", "ego.sensor", "{forward_range: 80}"};
  const auto message = test::configErrorOf([&] {
    makeController(registry, "cautious_ego", pluginFile("libvsd_cautious_ego_v1.so"), "",
                   ControllerParams({}, "controller"), needs);
  });
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_NE(message.find("scenarios/alks/cut_in.yaml:21: ego.sensor: {forward_range: 80}: controller 'cautious_ego' "
                         "reads version 1 of the observation, the setting needs version 2 or later (allowed: "),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("paper_ego"), std::string::npos) << message;
  EXPECT_NE(message.find("or a plugin declaring abi_version 2)"), std::string::npos) << message;
  // Built-ins and version-2 plugins are accepted.
  EXPECT_NO_THROW(makeController(registry, "paper_ego", "", "", ControllerParams({}, "c"), needs));
  auto fresh = ControllerRegistry::withBuiltins();
  EXPECT_NO_THROW(makeController(fresh, "cautious_ego", test::cautiousEgoPlugin(), "", ControllerParams({}, "c"), needs));
}

TEST(ControllerPlugin, PluginParameterErrorsReachTheUser) {
  auto registry = ControllerRegistry::withBuiltins();
  const auto message = test::configErrorOf([&] {
    makeController(registry, "cautious_ego", test::cautiousEgoPlugin(), "", ControllerParams({{"gain", 1.0}}, "c"));
  });
  EXPECT_NE(message.find("unknown parameter 'gain'"), std::string::npos) << message;
}

TEST(ControllerPlugin, MissingBrokenAndForeignLibrariesAreRejected) {
  TemporaryDirectory dir;
  auto registry = ControllerRegistry::withBuiltins();
  EXPECT_NE(test::configErrorOf([&] { registry.loadLibrary(dir.path() / "nope.so"); }).find("does not exist"), std::string::npos);
  const auto broken = test::writeFile(dir.path() / "broken.so", "this is not an ELF file");
  EXPECT_NE(test::configErrorOf([&] { registry.loadLibrary(broken); }).find("cannot be loaded"), std::string::npos);
  const auto foreign = test::configErrorOf([&] { registry.loadLibrary("/usr/lib/x86_64-linux-gnu/libyaml-cpp.so"); });
  EXPECT_NE(foreign.find("does not export vsd_controller_entry"), std::string::npos) << foreign;
}

TEST(VehicleModel, IntegratesSpeedPositionAndHeading) {
  const VehicleState start{0.0, 0.0, 0.0, 10.0, 0.0};
  const auto straight = advanceKinematic(start, {-5.0, 0.0}, 0.2, 0.0);
  EXPECT_NEAR(straight.speed, 9.0, 1e-12);
  EXPECT_NEAR(straight.x, 1.9, 1e-12);  // trapezoid: (10 + 9) / 2 * 0.2
  EXPECT_NEAR(straight.accel, -5.0, 1e-12);
  // Stops within the step and never reverses.
  const auto stop = advanceKinematic({0.0, 0.0, 0.0, 1.0, 0.0}, {-9.0, 0.0}, 0.2, 0.0);
  EXPECT_EQ(stop.speed, 0.0);
  EXPECT_NEAR(stop.x, 1.0 / 18.0, 1e-12);
  // Curvature turns left; heading noise is added on top.
  const auto turn = advanceKinematic(start, {0.0, 0.1}, 0.2, 0.0);
  EXPECT_NEAR(turn.heading, 0.2, 1e-12);
  EXPECT_GT(turn.y, 0.0);
  const auto noisy = advanceKinematic(start, {0.0, 0.0}, 0.2, 0.05);
  EXPECT_NEAR(noisy.heading, 0.05, 1e-12);
  EXPECT_NEAR(noisy.y, 0.0, 1e-12);  // the disturbance acts from the next step on
  // Commands beyond the limits are clamped.
  EXPECT_NEAR(advanceKinematic(start, {-50.0, 0.0}, 0.2, 0.0).accel, -9.0, 1e-12);
}

TEST(TimeGapLongitudinal, RequiredDecelerationMatchesKinematics) {
  // Stationary obstacle 20 m ahead at 10 m/s: v^2 / (2 d) = 2.5 m/s^2.
  EXPECT_NEAR(requiredDeceleration(20.0, 10.0, 0.0, 0.0, 0.0, 9.0), 2.5, 1e-6);
  // Same speed, no braking: nothing required.
  EXPECT_EQ(requiredDeceleration(5.0, 10.0, 10.0, 0.0, 1.0, 9.0), 0.0);
  // Closing on a slower leader: relative kinematics (v_rel^2 / (2 (d - margin))).
  EXPECT_NEAR(requiredDeceleration(11.0, 14.0, 10.0, 0.0, 1.0, 9.0), 16.0 / 20.0, 1e-6);
  // Unavoidable: reports infinity.
  EXPECT_TRUE(std::isinf(requiredDeceleration(1.0, 20.0, 0.0, 0.0, 0.5, 9.0)));
}

TEST(PaperEgo, KeepsTheTimeGapCruisesAndKeepsTheLane) {
  auto registry = ControllerRegistry::withBuiltins();
  auto made = registry.create("paper_ego");
  EgoController& controller = *made;
  controller.init(ControllerParams({{"set_speed", 12.0}}, "c"));
  controller.reset();
  // At exactly 2 s gap behind an equally fast leader: no action.
  Observation following = straightLane(12.0, 0.0);
  following.leader = Observation::Leader{24.0, 12.0, 0.0};
  EXPECT_NEAR(controller.step(following, 0.2).accel, 0.0, 1e-9);
  // Too close: brakes; far behind a fast leader: accelerates up to the set speed only.
  following.leader->gap = 12.0;
  EXPECT_LT(controller.step(following, 0.2).accel, 0.0);
  Observation free_road = straightLane(10.0, 0.0);
  EXPECT_GT(controller.step(free_road, 0.2).accel, 0.0);
  EXPECT_NEAR(controller.step(straightLane(12.0, 0.0), 0.2).accel, 0.0, 1e-12);
  // Lane keeping steers towards the centre.
  EXPECT_LT(controller.step(straightLane(12.0, 0.5), 0.2).curvature, 0.0);
  EXPECT_GT(controller.step(straightLane(12.0, -0.5), 0.2).curvature, 0.0);
  // Emergency: a stopped obstacle 15 m ahead at 12 m/s needs > 4.8 m/s^2.
  Observation emergency = straightLane(12.0, 0.0);
  emergency.leader = Observation::Leader{15.0, 0.0, 0.0};
  EXPECT_LT(controller.step(emergency, 0.2).accel, -5.0);
}

// Each part of paper_ego can be switched off in the scenario; time_gap_p is the paper's
// plain P-controller on the time gap (every extra part off unless switched on).
TEST(PaperEgo, PartsAreSwitchableAndTimeGapPIsThePlainPController) {
  auto registry = ControllerRegistry::withBuiltins();
  auto command = [&](const std::string& name, std::vector<std::pair<std::string, double>> params,
                     const Observation& observation) {
    auto controller = registry.create(name);
    params.emplace_back("set_speed", 12.0);
    controller->init(ControllerParams(params, "c"));
    controller->reset();
    return controller->step(observation, 0.2).accel;
  };
  // 2 m/s slower leader 20 m ahead at 12 m/s: P-term 0.3 (20 - 24) = -1.2; relative-speed term 0.8 (10 - 12) = -1.6.
  Observation closing = straightLane(12.0, 0.0);
  closing.leader = Observation::Leader{20.0, 10.0, 0.0};
  EXPECT_NEAR(command("paper_ego", {}, closing), -2.8, 1e-9);
  EXPECT_NEAR(command("paper_ego", {{"relative_speed_term", 0.0}}, closing), -1.2, 1e-9);
  EXPECT_NEAR(command("time_gap_p", {}, closing), -1.2, 1e-9);
  EXPECT_NEAR(command("time_gap_p", {{"relative_speed_term", 1.0}}, closing), -2.8, 1e-9);
  // Far behind a fast leader: the cruise cap limits the P-term's acceleration to k_cruise (12 - 10).
  Observation far = straightLane(10.0, 0.0);
  far.leader = Observation::Leader{60.0, 14.0, 0.0};
  EXPECT_NEAR(command("paper_ego", {}, far), 0.5 * 2.0, 1e-9);
  EXPECT_NEAR(command("paper_ego", {{"cruise_cap", 0.0}}, far), 2.0, 1e-9);  // 0.3 (60 - 20) + 0.8 * 4, clamped to max_accel
  EXPECT_NEAR(command("time_gap_p", {}, far), 2.0, 1e-9);
  // A stopped obstacle 15 m ahead at 12 m/s: only the emergency brake reacts that hard.
  Observation obstacle = straightLane(12.0, 0.0);
  obstacle.leader = Observation::Leader{15.0, 0.0, 0.0};
  EXPECT_LT(command("paper_ego", {}, obstacle), -5.0);
  EXPECT_NEAR(command("paper_ego", {{"emergency_brake", 0.0}, {"relative_speed_term", 0.0}}, obstacle),
              0.3 * (15.0 - 24.0), 1e-9);
  EXPECT_NEAR(command("time_gap_p", {}, obstacle), 0.3 * (15.0 - 24.0), 1e-9);
  // A switch is 0 or 1.
  EXPECT_THROW(command("paper_ego", {{"cruise_cap", 2.0}}, far), ConfigError);
}


// The paper's controllers follow SUMO's leader unless `leader_from_objects: 1`; then the
// nearest road user in the Ego's path is the lead - a cut-in SUMO has not yet moved to the
// Ego's lane included.
TEST(PaperEgo, LeaderComesFromSumoUnlessTheObjectListIsSwitchedOn) {
  auto registry = ControllerRegistry::withBuiltins();
  for (const char* name : {"paper_ego", "time_gap_p", "idm"}) {
    auto from_sumo = makeController(registry, name, "", "", ControllerParams({{"set_speed", 12.0}}, "c"));
    auto from_objects = makeController(registry, name, "", "",
                                       ControllerParams({{"set_speed", 12.0}, {"leader_from_objects", 1.0}}, "c"));
    EXPECT_FALSE(from_sumo->observesObjects()) << name;
    EXPECT_TRUE(from_objects->observesObjects()) << name;
    Observation cut_in = straightLane(12.0, 0.0);
    cut_in.objects.push_back(objectAhead(1, 8.0, 8.0, -0.3));  // in the path, not SUMO's leader yet
    EXPECT_GT(from_sumo->step(cut_in, 0.2).accel, -1e-12) << name;
    EXPECT_LT(from_objects->step(cut_in, 0.2).accel, -1.0) << name;
    // The same numbers from either source when both report the same lead.
    Observation both = cut_in;
    both.leader = leaderOf(cut_in.objects[0]);
    EXPECT_EQ(from_sumo->step(both, 0.2).accel, from_objects->step(cut_in, 0.2).accel) << name;
  }
  EXPECT_THROW(makeController(registry, "paper_ego", "", "", ControllerParams({{"leader_from_objects", 0.5 + 1.0}}, "c")),
               ConfigError);
}

// A commanded set speed of 0 (an imported speed action to a stop) is a stop for every built-in
// that follows set speeds: braking while moving, a finite command at standstill (IDM's free-road
// term (v / v0)^delta is 0 / 0 there).
TEST(SetSpeed, ACommandedStopBrakesAndHoldsWithFiniteCommands) {
  auto registry = ControllerRegistry::withBuiltins();
  for (const auto& [name, description] : registry.available()) {
    auto controller = makeController(registry, name, "", "", ControllerParams({}, "c"));
    if (!controller->followsSetSpeed()) continue;
    for (const double speed : {8.0, 0.0}) {
      Observation stop = straightLane(speed, 0.0);
      stop.commandedSetSpeed = 0.0;
      const Command command = controller->step(stop, 0.2);
      EXPECT_TRUE(std::isfinite(command.accel) && std::isfinite(command.curvature)) << name << " at " << speed;
      if (speed > 0.0) {
        EXPECT_LT(command.accel, 0.0) << name;
      } else {
        EXPECT_LE(command.accel, 1e-12) << name;
      }
    }
  }
}

TEST(StepCost, TheWrappedControllerDrivesAndEachStepTakesTheExtraTime) {
  auto registry = ControllerRegistry::withBuiltins();
  const ControllerParams params({}, "controller");
  auto plain = makeController(registry, "paper_ego", "", "", params);
  auto slow = withStepCost(makeController(registry, "paper_ego", "", "", params), 0.02);
  const auto observation = straightLane(20.0, 0.3);
  const auto start = std::chrono::steady_clock::now();
  const Command slow_command = slow->step(observation, 0.1);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Command plain_command = plain->step(observation, 0.1);
  EXPECT_EQ(slow_command.accel, plain_command.accel);
  EXPECT_EQ(slow_command.curvature, plain_command.curvature);
  EXPECT_GE(elapsed, 0.02);  // it sleeps at least the cost (an upper bound would be a timing test)
  EXPECT_EQ(withStepCost(nullptr, 0.0), nullptr);  // no cost: the controller itself, unwrapped
}
