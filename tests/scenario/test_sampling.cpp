#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

using namespace vsd;
using namespace vsd::scenario;

namespace {
double input(const ConcreteScenario& concrete, const std::string& name) {
  return concrete.inputs[*concrete.logical->inputIndex(name)];
}
}  // namespace

TEST(Sampling, RespectsTheTableIncludingDependentRanges) {
  const auto logical = loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  double min_v = 1e9;
  double max_v = -1e9;
  for (std::uint64_t i = 0; i < 2000; ++i) {
    const auto c = sampleConcreteScenario(logical, 11, i);
    const double v = input(c, "v_ego");
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
    ASSERT_GE(v, 8.0);
    ASSERT_LE(v, 16.0);
    ASSERT_GE(input(c, "x_co"), -50.0 + v);
    ASSERT_LE(input(c, "x_co"), -50.0 + 2.0 * v);
    ASSERT_GE(input(c, "v_co"), v - 4.0);
    ASSERT_LE(input(c, "v_co"), v + 4.0);
    ASSERT_GE(input(c, "a_co"), -8.0);
    ASSERT_LE(input(c, "a_co"), -1.0);
    ASSERT_LE(std::abs(input(c, "a3")), 0.001);
    // Random variations of the paper: lane width 3.5 + U(-0.3, 0.3), centre noise U(-0.5, 0.5)
    // at each of the 25 points, heading noise U(-2.9, 2.9) deg per step of the Ego and of the Co.
    ASSERT_EQ(c.laneWidths.size(), 1u);
    ASSERT_GE(c.laneWidths[0], 3.2);
    ASSERT_LE(c.laneWidths[0], 3.8);
    ASSERT_EQ(c.centreNoise.size(), 25u);
    for (double n : c.centreNoise) ASSERT_LE(std::abs(n), 0.5);
    for (const auto* vehicle : {&c.ego, &c.others.at(0)}) {
      ASSERT_EQ(vehicle->headingNoise.size(), 25u);
      for (double n : vehicle->headingNoise) ASSERT_LE(std::abs(n), 2.9 * 3.14159265358979323846 / 180.0 + 1e-15);
    }
    ASSERT_NE(c.ego.headingNoise, c.others[0].headingNoise);  // independent draws
    ASSERT_EQ(c.ego.x, -50.0);
  }
  // Uniform sampling covers the range.
  EXPECT_LT(min_v, 8.1);
  EXPECT_GT(max_v, 15.9);
}

TEST(Sampling, IsAPureFunctionOfSeedAndIndex) {
  const auto logical = loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const auto a = sampleConcreteScenario(logical, 5, 42);
  const auto b = sampleConcreteScenario(logical, 5, 42);
  EXPECT_EQ(a.inputs, b.inputs);
  EXPECT_EQ(a.centreNoise, b.centreNoise);
  EXPECT_EQ(a.others[0].scriptedSpeed, b.others[0].scriptedSpeed);
  EXPECT_EQ(a.others[0].headingNoise, b.others[0].headingNoise);
  EXPECT_NE(sampleConcreteScenario(logical, 5, 43).inputs, a.inputs);
  EXPECT_NE(sampleConcreteScenario(logical, 6, 42).inputs, a.inputs);
}

TEST(Sampling, CoSpeedProfileFollowsItsParametersWithinTheNoise) {
  const auto logical = loadLogicalScenario(test::scenarioFile("acc.yaml"));
  for (std::uint64_t i = 0; i < 200; ++i) {
    const auto c = sampleConcreteScenario(logical, 3, i);
    const double v = input(c, "v_co");
    const double t_v = input(c, "t_v_co");
    const double a = input(c, "a_co");
    const double t_a = input(c, "t_a_co");
    const auto& speeds = c.others[0].scriptedSpeed;
    ASSERT_EQ(speeds.size(), 26u);
    for (std::size_t k = 0; k < speeds.size(); ++k) {
      const double t = 0.2 * static_cast<double>(k);
      const double nominal = std::max(0.0, v + a * std::clamp(t - t_v, 0.0, t_a));
      ASSERT_NEAR(speeds[k], nominal, 0.1 + 1e-12) << "sample " << i << " t " << t;
      ASSERT_GE(speeds[k], 0.0);
    }
  }
}

TEST(Sampling, ScriptedSpeedNeverReverses) {
  EXPECT_DOUBLE_EQ(scriptedSpeedAt(10.0, {{1.0, 0.0}, {3.0, -8.0}}, 0.5), 10.0);
  EXPECT_DOUBLE_EQ(scriptedSpeedAt(10.0, {{1.0, 0.0}, {3.0, -8.0}}, 1.5), 6.0);
  EXPECT_DOUBLE_EQ(scriptedSpeedAt(10.0, {{1.0, 0.0}, {3.0, -8.0}}, 3.0), 0.0);
  EXPECT_DOUBLE_EQ(scriptedSpeedAt(10.0, {{1.0, 0.0}, {3.0, -8.0}, {2.0, 5.0}}, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(scriptedSpeedAt(10.0, {{1.0, 2.0}}, 4.0), 12.0);
}

TEST(Sampling, BoundsThatCrossAtSampleTimeAreAConfigError) {
  const auto logical = parseLogicalScenario(R"(
name: crossed
inputs:
  - {name: v, min: 8, max: 16}
  - {name: w, min: v + 4, max: v - 4}
road: {}
vehicles: {ego: {x: -50, speed: v, controller: {name: paper_ego}}}
)", "crossed.yaml");
  try {
    sampleConcreteScenario(logical, 1, 0);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("inputs[1]"), std::string::npos) << message;
    EXPECT_NE(message.find("min 'v + 4'"), std::string::npos) << message;
  }
}
