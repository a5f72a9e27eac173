#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <regex>

#include "extension/steady_brake_controller.hpp"
#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/road/network.hpp"
#include "vsd/sim/batch_simulation.hpp"
#include "vsd/sim/builtin_controllers.hpp"
#include "vsd/sim/ego_driver.hpp"
#include "vsd/sim/scripted_vehicle.hpp"

using namespace vsd;
using namespace vsd::sim;

namespace {

/// Samples, builds and simulates `count` scenarios of a logical scenario in one net.
struct Batch {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  std::vector<scenario::ConcreteScenario> scenarios;
  std::vector<road::RoadGeometry> roads;
  road::BatchLayout layout{1000.0};
  std::vector<SimulatedScenario> results;

  Batch(const std::shared_ptr<const scenario::LogicalScenario>& scenario, std::size_t count,
        const std::filesystem::path& dir, ControllerRegistry registry = ControllerRegistry::withBuiltins(),
        std::filesystem::path fcd = {}, double lateral_resolution = 0.0)
      : logical(scenario), layout(road::BatchLayout::cellSizeFor(scenario->road)) {
    road::NetworkBuilder builder;
    for (std::uint64_t i = 0; i < count; ++i) {
      scenarios.push_back(scenario::sampleConcreteScenario(logical, 1, i));
      roads.push_back(road::buildRoadGeometry(scenarios.back()));
      builder.add(i, roads.back(), layout.offsetFor(i));
    }
    builder.writePlainXml(dir / "net");
    const auto net = road::PendingNetwork::start(dir / "net", {}).wait();
    std::vector<ScenarioRun> runs;
    for (std::size_t i = 0; i < count; ++i) runs.push_back({&scenarios[i], &roads[i], layout.offsetFor(i)});
    BatchOptions options;
    options.step = logical->step;
    options.steps = logical->steps();
    options.fcdOutput = fcd;
    options.lateralResolution = lateral_resolution;
    results = simulateBatch(net, runs, registry, options);
  }
};

}  // namespace

TEST(BatchSimulation, EgoAndCoStartWhereTheScenarioSays) {
  TemporaryDirectory dir;
  const Batch batch(scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml")), 10, dir.path());
  for (std::size_t i = 0; i < 10; ++i) {
    const auto& result = batch.results[i];
    ASSERT_TRUE(result.ok()) << result.failure;
    const auto& concrete = batch.scenarios[i];
    const auto& ego = result.trace.vehicles[0].states[0];
    const auto& co = result.trace.vehicles[1].states[0];
    const auto lane_point = pointAtX(batch.roads[i].centre, -50.0);
    ASSERT_TRUE(lane_point.has_value());
    EXPECT_NEAR(ego.x, -50.0, 1e-9);
    EXPECT_NEAR(ego.y, lane_point->y(), 1e-9);  // on the lane centre
    EXPECT_NEAR(ego.speed, concrete.ego.speed, 1e-12);
    // The Co starts like the Ego: its centre on the lane centre at x_co, heading along the lane.
    const double x_co = concrete.inputs[*concrete.logical->inputIndex("x_co")];
    EXPECT_NEAR(co.x, x_co, 1e-9);
    EXPECT_NEAR(co.y, pointAtX(batch.roads[i].centre, x_co)->y(), 1e-9);
    EXPECT_NEAR(co.speed, concrete.others[0].scriptedSpeed[0], 1e-12);
    ASSERT_EQ(result.lanes.size(), 1u);
    EXPECT_NEAR(result.lanes[0].width, concrete.laneWidths.at(0), 0.01);
    for (std::size_t k = 0; k < result.trace.instants(); ++k) {
      ASSERT_TRUE(result.trace.vehicles[0].validAt(k));
      ASSERT_TRUE(result.trace.vehicles[1].validAt(k));
      // The Co drives at its scripted speed.
      EXPECT_NEAR(result.trace.vehicles[1].states[k].speed, concrete.others[0].scriptedSpeed[k], 1e-9);
    }
  }
}

TEST(BatchSimulation, SumoSeesTheEgoWhereTheControllerPutIt) {
  TemporaryDirectory dir;
  const auto fcd = dir.path() / "fcd.xml";
  const Batch batch(scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml")), 3, dir.path(),
                    ControllerRegistry::withBuiltins(), fcd);
  // FCD reports SUMO's front-bumper position of every vehicle at every step.
  const std::string xml = readTextFile(fcd);
  const std::regex pattern(
      R"re(<timestep time="([0-9.]+)">|<vehicle id="s([0-9]+)\.(ego|co)" x="([-0-9.]+)" y="([-0-9.]+)" angle="([-0-9.]+)")re");
  double time = 0.0;
  int compared = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), pattern); it != std::sregex_iterator(); ++it) {
    const auto& match = *it;
    if (match[1].matched) {
      time = std::stod(match[1]);
      continue;
    }
    const auto index = std::stoul(match[2]);
    // FCD time T holds instant k = T / 0.2.
    const auto k = static_cast<std::size_t>(std::lround(time / 0.2));
    const std::size_t vehicle = match[3] == "ego" ? 0 : 1;
    const auto& state = batch.results[index].trace.vehicles[vehicle].states[k];
    const Vec2 front = state.position() + 2.5 * headingVector(state.heading) + batch.layout.offsetFor(index);
    EXPECT_NEAR(std::stod(match[4]), front.x(), 0.011) << "sample " << index << " t " << time << " " << match[3];
    EXPECT_NEAR(std::stod(match[5]), front.y(), 0.011) << "sample " << index << " t " << time << " " << match[3];
    EXPECT_NEAR(headingFromSumoAngle(std::stod(match[6])), state.heading, 0.01);
    ++compared;
  }
  EXPECT_EQ(compared, 3 * 26 * 2);  // the Ego and the Co, where the trace says, at every instant
}

// The paper varies the orientation of Ego *and* Co (U(-2.9 deg, 2.9 deg)); the Co keeps its
// lane like the Ego, so it no longer traces the lane centre exactly.
TEST(BatchSimulation, TheCoKeepsItsLaneWithThePapersOrientationNoise) {
  TemporaryDirectory dir;
  const Batch batch(scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml")), 10, dir.path());
  double largest_deviation = 0.0;
  for (std::size_t i = 0; i < 10; ++i) {
    const auto& result = batch.results[i];
    ASSERT_TRUE(result.ok()) << result.failure;
    const MeasuredPolyline lane(result.lanes[0].centre);
    const auto& co = result.trace.vehicles[1];
    for (const auto& state : co.states) {
      const auto projection = lane.project(state.position());
      largest_deviation = std::max(largest_deviation, std::abs(wrapAngle(state.heading - projection.heading)));
      // The whole body inside the lane.
      EXPECT_LT(std::abs(projection.lateralOffset) + 0.5 * co.width, 0.5 * result.lanes[0].width) << "sample " << i;
    }
  }
  EXPECT_GT(largest_deviation, 1.0 * kPi / 180.0);
  // Bounded: lane keeping corrects the disturbance (slowly when the Co crawls after braking,
  // where a step's turn is small: a few disturbances in a row then add up).
  EXPECT_LT(largest_deviation, 20.0 * kPi / 180.0);
}

// Vehicles inside their lane are matched to it in SUMO (keepRoute 1), vehicles near or past
// its edge placed exactly (keepRoute 3); with FCD output every vehicle is placed exactly.
// Both must give the same simulation, also when vehicles leave the road.
TEST(BatchSimulation, MatchingVehiclesToTheirLanesChangesNothingSumoComputes) {
  std::string text = test::scenarioVariant("acc_lk.yaml", "lanes: 1", "lanes: 3");
  const std::string noise = "heading_noise_deg: {min: -2.9, max: 2.9}";
  for (auto at = text.find(noise); at != std::string::npos; at = text.find(noise)) {
    text.replace(at, noise.size(), "heading_noise_deg: {min: -45, max: 45}");
  }
  const auto logical = scenario::parseLogicalScenario(text, test::scenarioFile("acc_lk_wild.yaml"));
  const std::size_t count = 40;
  TemporaryDirectory matched_dir;
  TemporaryDirectory exact_dir;
  const Batch matched(logical, count, matched_dir.path());
  const Batch exact(logical, count, exact_dir.path(), ControllerRegistry::withBuiltins(), exact_dir.path() / "fcd.xml");
  std::size_t off_lane = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const auto& a = matched.results[i];
    const auto& b = exact.results[i];
    EXPECT_EQ(a.failure, b.failure) << "sample " << i;
    ASSERT_EQ(a.trace.vehicles.size(), b.trace.vehicles.size());
    for (std::size_t v = 0; v < a.trace.vehicles.size(); ++v) {
      const auto& track = a.trace.vehicles[v];
      ASSERT_EQ(track.valid, b.trace.vehicles[v].valid) << "sample " << i;
      for (std::size_t k = 0; k < track.states.size(); ++k) {
        const auto& x = track.states[k];
        const auto& y = b.trace.vehicles[v].states[k];
        ASSERT_TRUE(x.x == y.x && x.y == y.y && x.heading == y.heading && x.speed == y.speed && x.accel == y.accel)
            << "sample " << i << " vehicle " << v << " instant " << k;
        double nearest = std::numeric_limits<double>::infinity();
        for (const auto& lane : a.lanes) {
          nearest = std::min(nearest, std::abs(MeasuredPolyline(lane.centre).project(x.position()).lateralOffset));
        }
        if (track.valid[k] && nearest > 0.5 * (a.lanes[0].width + track.width)) ++off_lane;
      }
    }
  }
  EXPECT_GT(off_lane, 0u);  // the exact placement's case happened
}

// keepRoute asks first the lane that matched the vehicle placed before: its answer must not
// depend on what was placed before (a fresh SumoPlacement has no history).
TEST(BatchSimulation, PlacementDoesNotDependOnTheVehiclesPlacedBefore) {
  std::vector<LaneGeometry> lanes;
  for (int lane = 0; lane < 3; ++lane) {
    Polyline centre;
    for (int i = 0; i <= 40; ++i) centre.emplace_back(10.0 * i, 3.5 * lane + 0.002 * i * i);
    lanes.push_back({"e_" + std::to_string(lane), centre, 3.5});
  }
  const SumoPlacement placement(lanes);
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> along(-20.0, 420.0);
  std::uniform_real_distribution<double> across(-6.0, 13.0);
  int matched = 0;
  int exact = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec2 front(along(rng), across(rng));
    const double width = i % 2 == 0 ? 1.8 : 2.5;
    const int route = placement.keepRoute(front, width);
    EXPECT_EQ(route, SumoPlacement(lanes).keepRoute(front, width)) << i;
    (route == 1 ? matched : exact)++;
  }
  EXPECT_GT(matched, 500);
  EXPECT_GT(exact, 100);
}

TEST(BatchSimulation, AVehicleReachingTheEndOfItsRoadFailsOnlyItsScenario) {
  TemporaryDirectory dir;
  // No lead-out: a fast Co reaches the end of its road and is taken out.
  auto logical = scenario::parseLogicalScenario(
      test::shortRoadScenario(),
      test::scenarioFile("acc.yaml"));
  const Batch batch(logical, 40, dir.path());
  int failed = 0;
  for (std::size_t i = 0; i < batch.results.size(); ++i) {
    const auto& result = batch.results[i];
    const auto& co = result.trace.vehicles[1];
    if (result.ok()) {
      for (std::size_t k = 0; k < co.states.size(); ++k) ASSERT_TRUE(co.validAt(k));
      continue;
    }
    ++failed;
    EXPECT_NE(result.failure.find("vehicle 'co' reached the end of its road"), std::string::npos) << result.failure;
    EXPECT_FALSE(co.validAt(co.states.size() - 1));
  }
  EXPECT_GT(failed, 0);
  EXPECT_LT(failed, 40);
}

// A vehicle driving against the road (on the left lane, facing back) is simulated where the
// stepper plans it, SUMO holds it on its lane moving back along it, and it leaves the road at
// the road's start: its front (s = 180 - 2.5 m from the lead-in's start) gets there after 8.875 s.
TEST(BatchSimulation, AVehicleDrivingAgainstTheRoadIsSimulatedAsPlannedAndLeavesAtTheRoadsStart) {
  const auto scenario_of = [](double duration) {
    return scenario::parseLogicalScenario(fmt::format(R"(
name: oncoming
time: {{step: 0.2, duration: {}}}
road: {{shape: arc, curvature: 0, length: 200, lanes: 2, extension: {{before: 30, after: 150}}}}
vehicles:
  ego: {{s: 20, lane: 0, speed: 10, controller: {{name: idm, params: {{set_speed: 10}}}}}}
  others:
    - {{id: oncoming, s: 150, lane: 1, length: 5, direction: against, speed: 20}}
)",
                                                      duration),
                                          "oncoming.yaml");
  };
  TemporaryDirectory dir;
  const Batch batch(scenario_of(6.0), 1, dir.path(), ControllerRegistry::withBuiltins(), dir.path() / "fcd.xml");
  const auto& result = batch.results[0];
  ASSERT_TRUE(result.ok()) << result.failure;
  const auto planned = plannedPaths(batch.scenarios[0], batch.roads[0]);
  const auto& track = result.trace.vehicles[1];
  for (std::size_t k = 0; k < track.states.size(); ++k) {
    EXPECT_EQ(track.states[k].x, planned[0][k].x) << k;
    EXPECT_EQ(track.states[k].heading, planned[0][k].heading) << k;
  }
  EXPECT_NEAR(track.states.back().x, 150.0 - 20.0 * 6.0, 1e-9);
  // SUMO's picture: on lane 1 of the road's edge, 20 m further back along it every second.
  const std::string fcd = readTextFile(dir.path() / "fcd.xml");
  const std::regex at_one(R"re(time="1.00">[\s\S]*?id="s0.oncoming"[^>]*pos="([0-9.]+)" lane="s0_1")re");
  const std::regex at_two(R"re(time="2.00">[\s\S]*?id="s0.oncoming"[^>]*pos="([0-9.]+)" lane="s0_1")re");
  std::smatch one;
  std::smatch two;
  ASSERT_TRUE(std::regex_search(fcd, one, at_one));
  ASSERT_TRUE(std::regex_search(fcd, two, at_two));
  EXPECT_NEAR(std::stod(one[1]) - std::stod(two[1]), 20.0, 0.01);

  TemporaryDirectory long_dir;
  const Batch longer(scenario_of(10.0), 1, long_dir.path());
  EXPECT_NE(longer.results[0].failure.find("vehicle 'oncoming' reached the end of its road"), std::string::npos)
      << longer.results[0].failure;
  const auto& left = longer.results[0].trace.vehicles[1];
  EXPECT_TRUE(left.validAt(44));    // 8.8 s
  EXPECT_FALSE(left.validAt(45));   // 9.0 s
}

namespace {
/// Runs `body` in a forked child, so that a crash in libsumo takes down only the child; returns its wait status.
int inChild(const std::function<void()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    try {
      body();
    } catch (const std::exception& error) {
      std::fprintf(stderr, "%s\n", error.what());
      ::_exit(2);
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

std::string describeStatus(int status) {
  if (WIFSIGNALED(status)) return fmt::format("killed by signal {}", WTERMSIG(status));
  return fmt::format("exit code {}", WEXITSTATUS(status));
}
}  // namespace

// SUMO's network has only the lanes: a pedestrian standing on the shoulder is beyond all of them. Placed there
// before SUMO had inserted it, SUMO 1.15 inserted it with no lane and crashed writing its FCD (which names every
// vehicle's lane) in the first step, sublane model or not. It runs, and SUMO's FCD has it where it is at every
// instant: standing on the shoulder, then walking across the road from t = 1 s (back onto the lanes).
TEST(BatchSimulation, ARoadUserStartingBeyondTheLanesIsInSumosFcdWhereItIs) {
  const auto logical = scenario::parseLogicalScenario(R"(
name: shoulder
time: {step: 0.2, duration: 4}
road: {shape: arc, curvature: 0, length: 300, lanes: 2, lane_width: 3.5, shoulders: {right: 2.5}}
vehicles:
  ego: {s: 20, lane: 0, speed: 10, controller: {name: idm, params: {set_speed: 10}}}
  others:
    - {id: walker, type: pedestrian, length: 0.4, width: 0.6, s: 100, lane: 0, offset: -3, heading_deg: 90,
       actions: [{trigger: {time: 1}, cross: {speed: 1.5, to_offset: 3.5}}]}
)",
                                                      "shoulder.yaml");
  const auto concrete = scenario::sampleConcreteScenario(logical, 1, 0);
  const auto walker = plannedPaths(concrete, road::buildRoadGeometry(concrete))[0];
  const Vec2 offset = road::BatchLayout(road::BatchLayout::cellSizeFor(logical->road)).offsetFor(0);
  const std::regex record(R"re(<timestep time="([0-9.]+)">|<vehicle id="s0\.walker" x="([-0-9.]+)" y="([-0-9.]+)")re");
  for (const double lateral_resolution : {0.0, 1.75}) {
    TemporaryDirectory dir;
    const auto fcd = dir.path() / "fcd.xml";
    const int status = inChild([&] {
      const Batch batch(logical, 1, dir.path(), ControllerRegistry::withBuiltins(), fcd, lateral_resolution);
      if (!batch.results[0].ok()) throw Error(batch.results[0].failure);
    });
    const bool completed = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    EXPECT_TRUE(completed) << "lateral resolution " << lateral_resolution << ": the simulation "
                           << describeStatus(status);
    if (!completed) continue;
    const std::string xml = readTextFile(fcd);
    std::size_t k = 0;
    std::size_t seen = 0;
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), record); it != std::sregex_iterator(); ++it) {
      if ((*it)[1].matched) {
        k = static_cast<std::size_t>(std::lround(std::stod((*it)[1]) / 0.2));  // FCD time T holds instant T / 0.2
        continue;
      }
      const Vec2 front = walker[k].position() + 0.2 * headingVector(walker[k].heading) + offset;
      EXPECT_NEAR(std::stod((*it)[2]), front.x(), 0.011) << "instant " << k << ", resolution " << lateral_resolution;
      EXPECT_NEAR(std::stod((*it)[3]), front.y(), 0.011) << "instant " << k << ", resolution " << lateral_resolution;
      ++seen;
    }
    EXPECT_EQ(seen, walker.size()) << "lateral resolution " << lateral_resolution;  // at every instant, from t = 0
  }
}

namespace {
/// A controller that gives up after 1 s, to check per-scenario failure handling.
class FailingController final : public EgoController {
 public:
  void init(const ControllerParams& params) override { params.rejectUnknown("failing"); }
  void reset() override {}
  Command step(const Observation& observation, double) override {
    if (observation.time >= 1.0) throw Error("sensor fusion lost track");
    return {};
  }
};
}  // namespace

namespace {
/// Keeps its speed and heading and records SUMO's leader at every step it is asked.
class LeaderRecorder final : public EgoController {
 public:
  explicit LeaderRecorder(std::vector<std::pair<double, Observation::Leader>>* seen) : seen_(seen) {}
  void init(const ControllerParams& params) override { params.rejectUnknown("leader_recorder"); }
  void reset() override {}
  Command step(const Observation& observation, double) override {
    if (observation.leader) seen_->emplace_back(observation.time, *observation.leader);
    return {};
  }

 private:
  std::vector<std::pair<double, Observation::Leader>>* seen_;
};
}  // namespace

// An oncoming vehicle on the Ego's lane is SUMO's leader with its real bumper gap and its speed
// towards the Ego: centres 130 m apart (both 5 m long), closing at 10 + 20 m/s.
TEST(BatchSimulation, AnOncomingLeaderClosesInAtItsSpeedAgainstTheLane) {
  std::vector<std::pair<double, Observation::Leader>> seen;
  auto registry = ControllerRegistry::withBuiltins();
  registry.add("leader_recorder", "records SUMO's leader", [&seen] { return std::make_unique<LeaderRecorder>(&seen); });
  const auto logical = scenario::parseLogicalScenario(R"(
name: head_on
time: {step: 0.2, duration: 3}
road: {shape: arc, curvature: 0, length: 300, lanes: 2}
vehicles:
  ego: {s: 20, lane: 0, length: 5, speed: 10, controller: {name: leader_recorder}}
  others:
    - {id: oncoming, s: 150, lane: 0, length: 5, direction: against, speed: 20}
)",
                                                      "head_on.yaml");
  TemporaryDirectory dir;
  const Batch batch(logical, 1, dir.path(), registry);
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  ASSERT_GE(seen.size(), 10u);
  for (const auto& [time, leader] : seen) {
    EXPECT_NEAR(leader.gap, 125.0 - 30.0 * time, 0.05) << time;
    EXPECT_NEAR(leader.speed, -20.0, 1e-9) << time;
  }
}

TEST(BatchSimulation, AFailingControllerFailsItsScenarioWithTheReason) {
  TemporaryDirectory dir;
  auto registry = ControllerRegistry::withBuiltins();
  registry.add("failing", "fails at t = 1 s", [] { return std::make_unique<FailingController>(); });
  auto logical = scenario::parseLogicalScenario(
      test::scenarioVariant("acc.yaml", "name: paper_ego\n      params: {time_gap: 2.0, set_speed: v_ego}",
                            "name: failing"),
      test::scenarioFile("acc.yaml"));
  const Batch batch(logical, 2, dir.path(), registry);
  for (const auto& result : batch.results) {
    EXPECT_NE(result.failure.find("Ego controller failed at t = 1.0 s: sensor fusion lost track"), std::string::npos)
        << result.failure;
    EXPECT_TRUE(result.trace.vehicles[0].validAt(5));
    EXPECT_FALSE(result.trace.vehicles[0].validAt(6));
  }
}

// docs/design.md "Adding a controller": the controller's own file plus one registry line,
// then a scenario names it and the simulation drives the Ego with it.
TEST(BatchSimulation, AControllerAddedFromItsOwnFileDrivesTheEgo) {
  TemporaryDirectory dir;
  auto registry = ControllerRegistry::withBuiltins();
  test::registerSteadyBrake(registry);  // the one line a newcomer writes
  auto logical = scenario::parseLogicalScenario(
      test::scenarioVariant("acc.yaml", "name: paper_ego\n      params: {time_gap: 2.0, set_speed: v_ego}",
                            "name: steady_brake\n      params: {decel: 1.5}"),
      test::scenarioFile("acc.yaml"));
  const Batch batch(logical, 2, dir.path(), registry);
  for (std::size_t i = 0; i < batch.results.size(); ++i) {
    const auto& result = batch.results[i];
    ASSERT_TRUE(result.ok()) << result.failure;
    const auto& ego = result.trace.vehicles[0];
    for (std::size_t k = 0; k < result.trace.instants(); ++k) {
      const double expected = std::max(0.0, batch.scenarios[i].ego.speed - 1.5 * logical->step * static_cast<double>(k));
      EXPECT_NEAR(ego.states[k].speed, expected, 1e-9) << "scenario " << i << " step " << k;
    }
  }
}

// Triggers on motion in the simulation, with the real Ego (idm at its set speed of 10 m/s on a
// free road): a speed trigger of a scripted vehicle and an `any` of the Ego's travelled
// distance and a time start their actions where the numbers say (step 0.2 s).
TEST(BatchSimulation, MotionTriggersFireWhereTheNumbersSay) {
  TemporaryDirectory dir;
  const auto logical = scenario::parseLogicalScenario(R"(
name: motion_triggers
time: {step: 0.2, duration: 6.0}
road: {shape: arc, curvature: 0, length: 300, lanes: 3, lane_width: 3.5}
vehicles:
  ego: {s: 30, lane: 1, speed: 10, controller: {name: idm, params: {set_speed: 10}}}
  others:
    - {id: fast, s: 100, lane: 2, length: 5, speed_profile: {initial: 20, phases: [{duration: 10, accel: 1}]},
       actions: [{trigger: {speed_at_least: 25}, stop: {decel: 5, shape: linear}}]}
    - {id: side, s: 60, lane: 0, length: 5, speed: 10,
       actions: [{trigger: {any: [{travelled: 24, of: ego}, {time: 5}]}, speed: {target: 15, shape: step}}]}
)",
                                                      "motion_triggers.yaml");
  const Batch batch(logical, 1, dir.path());
  const auto& result = batch.results.at(0);
  ASSERT_TRUE(result.ok()) << result.failure;
  // 20 m/s + 1 m/s^2: 25 m/s at t = 5 s, braking at 5 m/s^2 from there.
  const auto& fast = result.trace.vehicles.at(1).states;
  EXPECT_NEAR(fast.at(25).speed, 25.0, 1e-9);
  EXPECT_NEAR(fast.at(26).speed, 24.0, 1e-9);
  // The Ego at 10 m/s has travelled 24 m at 2.4 s: the step to 15 m/s is there at the next instant.
  const auto& ego = result.trace.vehicles.at(0).states;
  EXPECT_NEAR(ego.at(12).speed, 10.0, 1e-6);
  const auto& side = result.trace.vehicles.at(2).states;
  EXPECT_NEAR(side.at(12).speed, 10.0, 1e-9);
  EXPECT_NEAR(side.at(13).speed, 15.0, 1e-9);
}

// A set_speed action reaches the Ego's controller at its start: the ALKS-like system cruises
// at 20 m/s until t = 1 s, then its cruise law a = 0.5 1/s * (10 - v) (no lead; within its
// 6 m/s^2) takes the speed down by 10 % of the difference per 0.2 s step: 10 + 10 * 0.9^n.
// controller.active_from: before it the controller is not asked and the Ego keeps its initial
// speed on its lane (OpenSCENARIO's scripted phase before ActivateControllerAction). By hand:
// steady_brake (-1 m/s^2) from t = 2 s: 20 m/s up to instant 10, then 0.2 m/s less per step; the
// alks's set speed of 10 m/s (commanded at t = 1 s) from t = 3 s: 10 + 10 * 0.9^(k - 15) after
// instant 15 (its cruise law, as in TheEgoFollowsTheSetSpeedItsActionsCommand).
TEST(BatchSimulation, TheControllerDrivesFromItsActivationTime) {
  TemporaryDirectory dir;
  ControllerRegistry registry = ControllerRegistry::withBuiltins();
  test::registerSteadyBrake(registry);
  const auto run = [&](const std::string& ego) {
    const std::string yaml = R"(
name: activation
time: {step: 0.2, duration: 8}
road: {shape: arc, length: 400, lanes: 2, lane_width: 3.5}
vehicles:
  ego: )" + ego + "\n";
    const Batch batch(scenario::parseLogicalScenario(yaml, "activation.yaml"), 1, dir.path(), registry);
    EXPECT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
    return batch.results[0].trace.vehicles[0];
  };
  const auto braking = run("{s: 20, lane: 0, speed: 20, controller: {name: steady_brake, params: {decel: 1}, "
                           "active_from: 2}}");
  for (std::size_t k = 0; k < braking.states.size(); ++k) {
    const double expected = k <= 10 ? 20.0 : 20.0 - 0.2 * static_cast<double>(k - 10);
    EXPECT_NEAR(braking.states[k].speed, expected, 1e-9) << "instant " << k;
    EXPECT_NEAR(braking.states[k].y, braking.states[0].y, 1e-9) << "instant " << k;
  }
  const auto cruising = run("{s: 20, lane: 0, speed: 20, controller: {name: alks, params: {set_speed: 20}, "
                            "active_from: 3}, actions: [{trigger: {time: 1}, set_speed: {target: 10}}]}");
  for (std::size_t k = 0; k < cruising.states.size(); ++k) {
    const double expected = k <= 15 ? 20.0 : 10.0 + 10.0 * std::pow(0.9, static_cast<double>(k - 15));
    EXPECT_NEAR(cruising.states[k].speed, expected, 1e-6) << "instant " << k;
  }
}

// The Ego's controller actions hand it to another controller from their start: by hand,
// steady_brake at 1 m/s^2 from 20 m/s (0.2 m/s less per 0.2 s step), at 3 m/s^2 from t = 2 s
// (instant 10, 18 m/s), at 1 m/s^2 again from t = 4 s (instant 20, 12 m/s).
TEST(BatchSimulation, TheEgosControllerActionsHandItToAnotherController) {
  TemporaryDirectory dir;
  ControllerRegistry registry = ControllerRegistry::withBuiltins();
  test::registerSteadyBrake(registry);
  const std::string yaml = R"(
name: handover
time: {step: 0.2, duration: 6}
road: {shape: arc, length: 400, lanes: 2, lane_width: 3.5}
vehicles:
  ego: {s: 20, lane: 0, speed: 20, controller: {name: steady_brake, params: {decel: 1}},
        actions: [{trigger: {time: 2}, controller: {name: steady_brake, params: {decel: 3}}},
                  {trigger: {time: 4}, controller: {name: steady_brake, params: {decel: 1}}}]}
)";
  const Batch batch(scenario::parseLogicalScenario(yaml, "handover.yaml"), 1, dir.path(), registry);
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  const auto& ego = batch.results[0].trace.vehicles[0];
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    const double t = 0.2 * static_cast<double>(k);
    const double expected = t <= 2.0 + 1e-9 ? 20.0 - t : t <= 4.0 + 1e-9 ? 18.0 - 3.0 * (t - 2.0) : 12.0 - (t - 4.0);
    EXPECT_NEAR(ego.states[k].speed, expected, 1e-9) << "instant " << k;
  }
  // A hand-over activates: before its own active_from (4 s), the Ego is braked from 2 s at 3 m/s^2.
  std::string early = yaml;
  early.replace(early.find("params: {decel: 1}},"), std::string("params: {decel: 1}},").size(),
                "params: {decel: 1}, active_from: 4},");
  const Batch activated(scenario::parseLogicalScenario(early, "handover.yaml"), 1, dir.path(), registry);
  ASSERT_TRUE(activated.results[0].ok()) << activated.results[0].failure;
  const auto& held = activated.results[0].trace.vehicles[0];
  for (std::size_t k = 0; k <= 20; ++k) {
    const double t = 0.2 * static_cast<double>(k);
    EXPECT_NEAR(held.states[k].speed, t <= 2.0 + 1e-9 ? 20.0 : 20.0 - 3.0 * (t - 2.0), 1e-9) << "instant " << k;
  }
}

namespace {

/// The Ego (idm at its set speed, 20 m/s, from s = 30 m on lane 0) on a straight road of 3
/// lanes of 3.5 m (lane centres at y = -3.5, 0, 3.5) with `actions` (and `others`), simulated.
Batch egoOnThreeLanes(const TemporaryDirectory& dir, const std::string& name, double duration,
                      const std::string& actions, const std::string& others = "") {
  const std::string yaml = fmt::format(R"(
name: {}
time: {{step: 0.2, duration: {}}}
road: {{shape: arc, curvature: 0, length: 500, lanes: 3, lane_width: 3.5}}
vehicles:
  ego: {{s: 30, lane: 0, speed: 20, controller: {{name: idm, params: {{set_speed: 20}}}}, actions: {}}}
{})",
                                       name, duration, actions, others.empty() ? "" : "  others:\n" + others);
  return Batch(scenario::parseLogicalScenario(yaml, name + ".yaml"), 1, dir.path());
}

}  // namespace

// The Ego's lane_change and lateral_offset actions move the lane its controller keeps (idm:
// pure pursuit on the observed lane): it follows each move with its own lag and settles on the
// target (egoOnThreeLanes: lane centres at y = -3.5, 0, 3.5).
TEST(BatchSimulation, TheEgosLateralActionsMoveTheLaneItsControllerKeeps) {
  TemporaryDirectory dir;
  const Batch batch = egoOnThreeLanes(dir, "ego_lateral", 18, R"([
      {id: left, trigger: {time: 1}, lane_change: {lanes: 1, duration: 3}},
      {id: over, trigger: {time: 8}, lane_change: {lane: 2, shape: step}},
      {trigger: {time: 13}, lateral_offset: {offset: -0.5, duration: 1}}])");
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  const auto& ego = batch.results[0].trace.vehicles[0].states;
  const auto y_at = [&](double t) { return ego.at(static_cast<std::size_t>(std::lround(t / 0.2))).y; };
  EXPECT_NEAR(y_at(1.0), -3.5, 1e-9);   // its own lane until the first move starts
  EXPECT_GT(y_at(4.0), -2.0);           // following the move (which ends at 4 s) ...
  EXPECT_LT(y_at(4.0), 0.0);            // ... a little behind it
  EXPECT_NEAR(y_at(7.8), 0.0, 0.05);    // settled on lane 1
  EXPECT_NEAR(y_at(8.0), 0.0, 0.05);    // a step moves the lane at once (8 s), the Ego its own way:
  EXPECT_GT(y_at(8.4), 1.0);            // steering hard for the lane that jumped
  EXPECT_NEAR(y_at(10.4), 3.5, 0.05);   // on lane 2
  EXPECT_NEAR(y_at(18.0), 3.0, 0.05);   // 0.5 m right of its centre
  for (std::size_t k = 1; k < ego.size(); ++k) {
    if (k > 40 && k <= 52) continue;  // the step's answer, 8 .. 10.4 s
    EXPECT_LT(std::abs(ego[k].y - ego[k - 1].y), 0.2 * 2.5) << "instant " << k;  // < 2.5 m/s sideways
  }
}

// A teleport of the Ego moves it at once; its controller drives on from there (idm at its set
// speed: 20 m/s throughout). By hand, on a straight road of 3 lanes of 3.5 m (centres at y =
// -3.5, 0, 3.5): it starts at s = 30 m; at 2.1 s (42 m on) it lands at s = 10 m, 0.5 m left of
// lane 1's centre, so at 2.2 s it is 2 m further; the lane change under way ends and it keeps
// its landing place across the road. Travelled: 42 m before, 18 m after the jump: 60 m at 3.0 s,
// when its set speed drops to 10 m/s (it brakes from then on, not before).
TEST(BatchSimulation, AnEgoTeleportMovesItAtOnceAndItsControllerDrivesOnFromThere) {
  TemporaryDirectory dir;
  const Batch batch = egoOnThreeLanes(dir, "ego_teleport", 6, R"([
      {trigger: {time: 0.5}, lane_change: {lane: 2, duration: 4}},
      {id: back, trigger: {time: 2.1}, teleport: {s: 10, lane: 1, offset: 0.5}},
      {trigger: {travelled: 60}, set_speed: {target: 10}}])");
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  const auto& ego = batch.results[0].trace.vehicles[0].states;
  const double x0 = ego.at(0).x;
  EXPECT_GT(ego.at(10).x - x0, 39.9);  // 40 m, less what the lane change turned it
  EXPECT_NEAR(ego.at(11).x - x0, -18.0, 1e-6);
  for (std::size_t k = 11; k <= 15; ++k) {
    EXPECT_NEAR(ego.at(k).y, 0.5, 1e-6) << "instant " << k;
    EXPECT_NEAR(ego.at(k).heading, 0.0, 1e-9) << "instant " << k;
    EXPECT_NEAR(ego.at(k).speed, 20.0, 1e-9) << "instant " << k;
  }
  EXPECT_NEAR(ego.at(20).y, 0.5, 1e-3);  // the lane change under way ended at the teleport
  EXPECT_LT(ego.at(17).speed, 20.0 - 1e-3);  // braking once it has travelled 60 m (3.0 s)
  // Relative to a slower car two lanes left (10 m/s, at s = 130 m at 1 s): at 1 s it lands 25 m
  // behind it in its lane, and its controller sees it as its leader from the step that lands it
  // (it brakes in that step already: SUMO has it in that lane at once).
  const Batch relative = egoOnThreeLanes(dir, "ego_teleport_behind", 2,
                                         "[{trigger: {time: 1}, teleport: {from: slow, ds: -25, lanes: 0}}]",
                                         "    - {id: slow, s: 120, lane: 2, speed: 10}\n");
  ASSERT_TRUE(relative.results[0].ok()) << relative.results[0].failure;
  const auto& follower = relative.results[0].trace.vehicles[0].states;
  EXPECT_NEAR(follower.at(4).speed, 20.0, 1e-9);
  EXPECT_LT(follower.at(5).speed, 20.0 - 1e-3);
  EXPECT_NEAR(follower.at(5).y, 3.5, 1e-6);
  EXPECT_NEAR(follower.at(5).x - follower.at(0).x, 75.0, 0.5);  // less what it braked in the last step
}

// A controller action may hand over one domain: the other stays with its controller. By hand,
// steady_brake at 1 m/s^2 from 20 m/s; from t = 2 s keep_lane drives the speed (18 m/s held)
// while steady_brake keeps steering; from t = 3 s a steady_brake at 2 m/s^2 steers only (the
// speed stays 18 m/s); from t = 4 s steady_brake at 3 m/s^2 drives the speed again.
TEST(BatchSimulation, AControllerActionHandsOverTheDomainsItNames) {
  TemporaryDirectory dir;
  ControllerRegistry registry = ControllerRegistry::withBuiltins();
  test::registerSteadyBrake(registry);
  const std::string yaml = R"(
name: domains
time: {step: 0.2, duration: 6}
road: {shape: arc, length: 400, lanes: 2, lane_width: 3.5}
vehicles:
  ego: {s: 20, lane: 0, speed: 20, controller: {name: steady_brake, params: {decel: 1}},
        actions: [{trigger: {time: 2}, controller: {name: keep_lane, domains: longitudinal}},
                  {trigger: {time: 3}, controller: {name: steady_brake, params: {decel: 2}, domains: lateral}},
                  {trigger: {time: 4}, controller: {name: steady_brake, params: {decel: 3}, domains: longitudinal}}]}
)";
  const Batch batch(scenario::parseLogicalScenario(yaml, "domains.yaml"), 1, dir.path(), registry);
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  const auto& ego = batch.results[0].trace.vehicles[0];
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    const double t = 0.2 * static_cast<double>(k);
    const double expected = t <= 2.0 + 1e-9 ? 20.0 - t : t <= 4.0 + 1e-9 ? 18.0 : 18.0 - 3.0 * (t - 4.0);
    EXPECT_NEAR(ego.states[k].speed, expected, 1e-9) << "instant " << k;
  }
  const auto bad = [](const std::string& domains) {
    return test::configErrorOf([&] {
      scenario::parseLogicalScenario(
          "name: d\ntime: {step: 0.2, duration: 2}\nroad: {shape: arc, length: 200, lanes: 2, lane_width: 3.5}\n"
          "vehicles:\n  ego: {s: 20, lane: 0, speed: 20, controller: {name: idm},\n"
          "        actions: [{trigger: {time: 1}, controller: {name: idm, domains: " + domains + "}}]}\n",
          "d.yaml");
    });
  };
  const std::string refused = bad("steering");
  EXPECT_NE(refused.find("domains: got 'steering', expected both, longitudinal or lateral"), std::string::npos)
      << refused;
}

TEST(BatchSimulation, TheEgoFollowsTheSetSpeedItsActionsCommand) {
  TemporaryDirectory dir;
  const std::string yaml = R"(
name: set_speed
time: {step: 0.2, duration: 8}
road: {shape: arc, length: 400, lanes: 2, lane_width: 3.5}
vehicles:
  ego: {s: 20, lane: 0, speed: 20, controller: {name: CONTROLLER, params: {PARAMS}},
        actions: [{trigger: {time: 1}, set_speed: {target: 10}}]}
)";
  const auto variant = [&](const std::string& controller, const std::string& params) {
    return std::regex_replace(std::regex_replace(yaml, std::regex("CONTROLLER"), controller), std::regex("PARAMS"),
                              params);
  };
  const Batch batch(scenario::parseLogicalScenario(variant("alks", "set_speed: 20"), "set_speed.yaml"), 1,
                    dir.path());
  ASSERT_TRUE(batch.results[0].ok()) << batch.results[0].failure;
  const auto& ego = batch.results[0].trace.vehicles[0];
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    const double expected = k <= 5 ? 20.0 : 10.0 + 10.0 * std::pow(0.9, static_cast<double>(k - 5));
    EXPECT_NEAR(ego.states[k].speed, expected, 1e-6) << "instant " << k;
  }
  // A controller that takes no set speed is refused before anything runs.
  ControllerRegistry registry = ControllerRegistry::withBuiltins();
  test::registerSteadyBrake(registry);
  try {
    const Batch refused(scenario::parseLogicalScenario(variant("steady_brake", "decel: 1"), "set_speed.yaml"), 1,
                        dir.path(), registry);
    FAIL() << "a set speed for a controller without one ran";
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("set_speed.yaml:"), std::string::npos) << message;
    EXPECT_NE(message.find("set_speed: 10: controller 'steady_brake' takes no set speed (allowed: alks"),
              std::string::npos)
        << message;
  }
}
