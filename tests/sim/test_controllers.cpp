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

std::string errorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
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
  const auto message = errorOf([&] { registry.create("paper_eggo"); });
  EXPECT_NE(message.find("unknown controller 'paper_eggo'"), std::string::npos) << message;
  EXPECT_NE(message.find("idm, paper_ego"), std::string::npos) << message;
}

TEST(ControllerParams, OutOfRangeAndUnknownParametersAreNamed) {
  auto registry = ControllerRegistry::withBuiltins();
  const auto range = errorOf([&] {
    makeController(registry, "paper_ego", "", "", ControllerParams({{"time_gap", -2.0}}, "acc.yaml:40: controller"));
  });
  EXPECT_NE(range.find("params.time_gap: got -2"), std::string::npos) << range;
  EXPECT_NE(range.find("acc.yaml:40"), std::string::npos) << range;
  const auto unknown = errorOf([&] {
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
  // A leader closer than the 3 s gap: brakes.
  Observation close = straightLane(12.0, 0.0);
  close.leader = Observation::Leader{15.0, 12.0, 0.0};
  EXPECT_LT(controller->step(close, 0.2).accel, 0.0);
}

TEST(ControllerPlugin, PluginParameterErrorsReachTheUser) {
  auto registry = ControllerRegistry::withBuiltins();
  const auto message = errorOf([&] {
    makeController(registry, "cautious_ego", test::cautiousEgoPlugin(), "", ControllerParams({{"gain", 1.0}}, "c"));
  });
  EXPECT_NE(message.find("unknown parameter 'gain'"), std::string::npos) << message;
}

TEST(ControllerPlugin, MissingBrokenAndForeignLibrariesAreRejected) {
  TemporaryDirectory dir;
  auto registry = ControllerRegistry::withBuiltins();
  EXPECT_NE(errorOf([&] { registry.loadLibrary(dir.path() / "nope.so"); }).find("does not exist"), std::string::npos);
  const auto broken = test::writeFile(dir.path() / "broken.so", "this is not an ELF file");
  EXPECT_NE(errorOf([&] { registry.loadLibrary(broken); }).find("cannot be loaded"), std::string::npos);
  const auto foreign = errorOf([&] { registry.loadLibrary("/usr/lib/x86_64-linux-gnu/libyaml-cpp.so"); });
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
