// Physics sanity of the co-simulation on runs with fixed seeds (issue: "Numbers").
#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/sim/builtin_controllers.hpp"

using namespace vsd;
using namespace vsd::pipeline;

namespace {

std::vector<ScenarioOutcome> simulate(const std::filesystem::path& scenario, std::uint64_t samples,
                                      std::shared_ptr<const scenario::LogicalScenario>* logical_out = nullptr) {
  RunOptions options;
  options.scenarioFile = scenario;
  options.samples = samples;
  options.seed = 2024;
  options.writeFiles = false;
  std::vector<ScenarioOutcome> outcomes;
  const auto logical = scenario::loadLogicalScenario(scenario);
  if (logical_out) *logical_out = logical;
  runScenarios(logical, options, [&](const ScenarioOutcome& outcome) { outcomes.push_back(outcome); });
  return outcomes;
}

double metric(const ScenarioOutcome& outcome, const std::shared_ptr<const scenario::LogicalScenario>& logical,
              const std::string& name) {
  const auto names = logical->metrics;
  const auto it = std::find(names.begin(), names.end(), name);
  return outcome.metrics.at(static_cast<std::size_t>(std::distance(names.begin(), it)));
}

/// Could the Ego have avoided the collision by braking at 9 m/s^2 from t = 0 (straight road)?
bool avoidableByFullBraking(const Trace& trace) {
  const auto& ego = trace.ego();
  const auto& co = trace.vehicles[1];
  const double v0 = ego.states[0].speed;
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    const double t = trace.step * static_cast<double>(k);
    const double travelled = t < v0 / 9.0 ? v0 * t - 4.5 * t * t : v0 * v0 / 18.0;
    const double gap = co.states[k].x - (ego.states[0].x + travelled) - 0.5 * (ego.length + co.length);
    if (gap <= 0.0) return false;
  }
  return true;
}

}  // namespace

TEST(Physics, AccEgoNeverCollidesUnlessUnavoidable) {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  const auto outcomes = simulate(test::scenarioFile("acc.yaml"), 1000, &logical);
  int collisions = 0;
  int unavoidable = 0;
  for (const auto& outcome : outcomes) {
    ASSERT_TRUE(outcome.ok()) << outcome.failure;
    if (metric(outcome, logical, "d_min") > 0.0) continue;
    ++collisions;
    if (!avoidableByFullBraking(outcome.trace)) ++unavoidable;
    EXPECT_FALSE(avoidableByFullBraking(outcome.trace)) << "avoidable collision in sample " << outcome.index;
  }
  RecordProperty("collisions", collisions);
  RecordProperty("unavoidable", unavoidable);
  std::printf("acc: %d collisions in 1000 samples, %d of them unavoidable\n", collisions, unavoidable);
}

TEST(Physics, TimeGapConvergesToTwoSecondsWhenTheCoHoldsItsSpeed) {
  TemporaryDirectory dir;
  const auto scenario = test::writeFile(dir.path() / "hold.yaml", R"(
name: acc_hold
time: {step: 0.2, duration: 30}
inputs:
  - {name: v_ego, min: 8, max: 16}
  - {name: x_co, min: -50 + v_ego, max: -50 + 2*v_ego}
  - {name: v_co, min: v_ego - 4, max: v_ego + 4}
road: {centre: 0, extension: {before: 30, after: 800}}
vehicles:
  ego: {x: -50, speed: v_ego, controller: {name: paper_ego, params: {time_gap: 2.0, set_speed: 30}}}
  others:
    - {id: co, x: x_co, speed_profile: {initial: v_co}}
)");
  const auto outcomes = simulate(scenario, 100);
  for (const auto& outcome : outcomes) {
    ASSERT_TRUE(outcome.ok()) << outcome.failure;
    const auto& ego = outcome.trace.ego();
    const auto& co = outcome.trace.vehicles[1];
    auto time_gap = [&](std::size_t k) {
      return (co.states[k].x - ego.states[k].x - 5.0) / ego.states[k].speed;
    };
    const double initial_error = std::abs(time_gap(0) - 2.0);
    const double after_10s = std::abs(time_gap(50) - 2.0);
    const double final_error = std::abs(time_gap(150) - 2.0);
    EXPECT_LT(after_10s, std::max(0.25 * initial_error, 0.1)) << "sample " << outcome.index;
    EXPECT_LT(final_error, 0.02) << "sample " << outcome.index;
  }
}

TEST(Physics, LkEgoStaysInItsLaneAndYMaxTracksTheRoad) {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  const auto outcomes = simulate(test::scenarioFile("lk.yaml"), 1000, &logical);
  double worst_margin = 1e9;
  std::vector<double> p_lat;
  std::vector<double> y_max;
  for (const auto& outcome : outcomes) {
    ASSERT_TRUE(outcome.ok()) << outcome.failure;
    const auto& lane = outcome.lanes.at(0);
    const auto& ego = outcome.trace.ego();
    // The whole vehicle stays inside the lane: |offset| + width / 2 <= lane width / 2.
    const double offset = metric(outcome, logical, "lane_offset_max");
    const double margin = 0.5 * lane.width - (offset + 0.5 * ego.width);
    worst_margin = std::min(worst_margin, margin);
    EXPECT_GT(margin, 0.0) << "sample " << outcome.index << " offset " << offset;
    // p_lat_max is relative to the lane: within its offsets, whatever the road does.
    const double p_lat_max = metric(outcome, logical, "p_lat_max");
    EXPECT_LE(p_lat_max, offset + 1e-12) << "sample " << outcome.index;
    EXPECT_GE(p_lat_max, -offset - 1e-12) << "sample " << outcome.index;
    p_lat.push_back(p_lat_max);
    // y_max follows the road's own highest point over the stretch the Ego drove.
    double road_max = -1e9;
    const double x_end = ego.states.back().x;
    for (const auto& point : lane.centre) {
      if (point.x() >= -50.0 && point.x() <= x_end) road_max = std::max(road_max, point.y());
    }
    for (double x : {-50.0, x_end}) road_max = std::max(road_max, pointAtX(lane.centre, x)->y());
    y_max.push_back(metric(outcome, logical, "y_max"));
    EXPECT_NEAR(y_max.back(), road_max, 0.5 * lane.width) << "sample " << outcome.index;
  }
  std::printf("lk: smallest margin between the Ego's body and its lane boundary: %.2f m\n", worst_margin);
  // The paper's p_lat_max is a lateral position on the road: its spread is tenths of a metre,
  // where the scenario-frame maximum follows the sampled cubic over tens of metres.
  auto spread = [](const std::vector<double>& values) {
    double mean = 0.0;
    for (double v : values) mean += v / static_cast<double>(values.size());
    double variance = 0.0;
    for (double v : values) variance += (v - mean) * (v - mean) / static_cast<double>(values.size() - 1);
    return std::sqrt(variance);
  };
  std::printf("lk: std of p_lat_max %.3f m, of y_max %.1f m\n", spread(p_lat), spread(y_max));
  EXPECT_LT(spread(p_lat), 0.3);
  EXPECT_GT(spread(y_max), 10.0);
}

TEST(Physics, CoSpeedProfileMatchesItsParameters) {
  std::shared_ptr<const scenario::LogicalScenario> logical;
  const auto outcomes = simulate(test::scenarioFile("acc_lk.yaml"), 300, &logical);
  const auto index = [&](const char* name) { return *logical->inputIndex(name); };
  for (const auto& outcome : outcomes) {
    ASSERT_TRUE(outcome.ok()) << outcome.failure;
    const double v = outcome.inputs[index("v_co")];
    const double t_v = outcome.inputs[index("t_v_co")];
    const double a = outcome.inputs[index("a_co")];
    const double t_a = outcome.inputs[index("t_a_co")];
    const auto& co = outcome.trace.vehicles[1];
    for (std::size_t k = 0; k < co.states.size(); ++k) {
      const double t = 0.2 * static_cast<double>(k);
      const double nominal = std::max(0.0, v + a * std::clamp(t - t_v, 0.0, t_a));
      ASSERT_NEAR(co.states[k].speed, nominal, 0.1 + 1e-6) << "sample " << outcome.index << " t " << t;
    }
  }
}
