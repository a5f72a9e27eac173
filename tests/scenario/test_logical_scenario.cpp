#include <gtest/gtest.h>

#include <regex>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/scenario/logical_scenario.hpp"

using namespace vsd;
using namespace vsd::scenario;

namespace {

struct Row {
  const char* name;
  double min_at_lo;  // bound evaluated with v_ego = 8 (dependent rows) or constant
  double max_at_lo;
};

double evalWith(const LogicalScenario& scenario, const Expression& expression, double v_ego) {
  std::vector<double> values(scenario.inputs.size(), 0.0);
  if (auto index = scenario.inputIndex("v_ego")) values[*index] = v_ego;
  return expression.evaluate(values);
}

void expectInputs(const LogicalScenario& scenario, const std::vector<Row>& rows) {
  ASSERT_EQ(scenario.inputs.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& input = scenario.inputs[i];
    EXPECT_EQ(input.name, rows[i].name);
    EXPECT_EQ(input.distribution.kind, Distribution::Kind::Uniform) << input.name;
    EXPECT_DOUBLE_EQ(evalWith(scenario, input.distribution.min, 8.0), rows[i].min_at_lo) << input.name;
    EXPECT_DOUBLE_EQ(evalWith(scenario, input.distribution.max, 8.0), rows[i].max_at_lo) << input.name;
  }
}

std::string errorOf(const std::string& yaml) {
  try {
    parseLogicalScenario(yaml, "bad.yaml");
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

}  // namespace

// Table I of the paper, dependent bounds evaluated at v_Ego = 8 m/s.
TEST(LogicalScenario, AccLkReproducesThePaperTable) {
  const auto scenario = loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  EXPECT_EQ(scenario->name, "acc_lk");
  expectInputs(*scenario, {{"a0", -1, 1}, {"a1", -0.1, 0.1}, {"a2", -0.01, 0.01}, {"a3", -0.001, 0.001},
                           {"v_ego", 8, 16}, {"x_co", -42, -34}, {"v_co", 4, 12}, {"t_v_co", 0, 3},
                           {"a_co", -8, -1}, {"t_a_co", 1, 3}});
  EXPECT_DOUBLE_EQ(scenario->step, 0.2);
  EXPECT_DOUBLE_EQ(scenario->duration, 5.0);
  EXPECT_EQ(scenario->steps(), 25);
  EXPECT_EQ(scenario->road.points, 25);
  EXPECT_DOUBLE_EQ(scenario->road.xMin, -55.0);
  EXPECT_DOUBLE_EQ(scenario->road.xMax, 55.0);
  EXPECT_DOUBLE_EQ(scenario->road.centreNoise.min.evaluate({}), -0.5);
  EXPECT_DOUBLE_EQ(scenario->road.centreNoise.max.evaluate({}), 0.5);
  EXPECT_DOUBLE_EQ(scenario->road.laneWidth.evaluate({}), 3.5);
  EXPECT_DOUBLE_EQ(scenario->road.laneWidthNoise.max.evaluate({}), 0.3);
  EXPECT_NEAR(scenario->ego.headingNoise.max.evaluate({}) * scenario->ego.headingNoise.unitScale, 2.9 * 3.14159265358979323846 / 180.0,
              1e-15);
  ASSERT_EQ(scenario->others.size(), 1u);
  EXPECT_EQ(scenario->others[0].id, "co");
  EXPECT_EQ(scenario->others[0].speedProfile.phases.size(), 2u);
  EXPECT_DOUBLE_EQ(scenario->others[0].speedNoise.max.evaluate({}), 0.1);
  EXPECT_EQ(scenario->ego.controller.name, "paper_ego");
}

TEST(LogicalScenario, AccHasAStraightRoadAndLkHasNoCo) {
  const auto acc = loadLogicalScenario(test::scenarioFile("acc.yaml"));
  expectInputs(*acc, {{"v_ego", 8, 16}, {"x_co", -42, -34}, {"v_co", 4, 12}, {"t_v_co", 0, 3}, {"a_co", -8, -1},
                      {"t_a_co", 1, 3}});
  EXPECT_TRUE(acc->road.centre.isConstant());
  EXPECT_DOUBLE_EQ(acc->road.centre.evaluate({}), 0.0);
  EXPECT_EQ(acc->others.size(), 1u);

  const auto lk = loadLogicalScenario(test::scenarioFile("lk.yaml"));
  expectInputs(*lk, {{"a0", -1, 1}, {"a1", -0.1, 0.1}, {"a2", -0.01, 0.01}, {"a3", -0.001, 0.001}, {"v_ego", 8, 16}});
  EXPECT_TRUE(lk->others.empty());
}

TEST(LogicalScenario, MalformedYamlNamesFileAndLine) {
  const auto message = errorOf("name: x\ninputs: [ {name: a, min: 1\n");
  EXPECT_NE(message.find("bad.yaml:"), std::string::npos) << message;
  EXPECT_NE(message.find("malformed YAML"), std::string::npos) << message;
}

TEST(LogicalScenario, UnknownKeysAreRejectedWithTheAllowedOnes) {
  const std::string yaml = test::scenarioVariant("acc.yaml", "  lanes: 1\n", "  lanes: 1\n  lane_widht: 3\n");
  const auto message = errorOf(yaml);
  EXPECT_NE(message.find("road.lane_widht"), std::string::npos) << message;
  EXPECT_NE(message.find("allowed:"), std::string::npos) << message;
  EXPECT_TRUE(std::regex_search(message, std::regex("bad\\.yaml:[0-9]+:"))) << message;
}

TEST(LogicalScenario, MinGreaterThanMaxIsRejected) {
  const std::string yaml = test::scenarioVariant("acc.yaml", "min: 0,           max: 3", "min: 5,           max: 3");
  const auto message = errorOf(yaml);
  EXPECT_NE(message.find("inputs[3]"), std::string::npos) << message;
  EXPECT_NE(message.find("min 5 > max 3"), std::string::npos) << message;
}

TEST(LogicalScenario, ExpressionWithUnknownInputIsRejected) {
  const std::string yaml = test::scenarioVariant("acc.yaml", "max: -50 + 2*v_ego", "max: -50 + 2*v_eg");
  const auto message = errorOf(yaml);
  EXPECT_NE(message.find("inputs[1].max"), std::string::npos) << message;
  EXPECT_NE(message.find("'v_eg'"), std::string::npos) << message;
}

TEST(LogicalScenario, BoundsMayOnlyUseEarlierInputs) {
  // v_co is defined after x_co: sampling order would make this ambiguous.
  const std::string yaml = test::scenarioVariant("acc.yaml", "max: -50 + 2*v_ego", "max: -50 + 2*v_co");
  EXPECT_NE(errorOf(yaml).find("'v_co'"), std::string::npos);
}

TEST(LogicalScenario, NegativeDurationsAreRejected) {
  EXPECT_NE(errorOf(test::scenarioVariant("acc.yaml", "duration: 5.0", "duration: -5.0")).find("time.duration"),
            std::string::npos);
  EXPECT_NE(errorOf(test::scenarioVariant("acc.yaml", "step: 0.2", "step: 0")).find("time.step"), std::string::npos);
  const auto phase = errorOf(test::scenarioVariant("acc.yaml", "{duration: t_v_co, accel: 0}", "{duration: -1, accel: 0}"));
  EXPECT_NE(phase.find("phases[0].duration"), std::string::npos) << phase;
  EXPECT_NE(phase.find("'-1'"), std::string::npos) << phase;
}

TEST(LogicalScenario, MissingEgoIsRejected) {
  const auto message = errorOf("name: x\nroad: {}\nvehicles:\n  others: []\n");
  EXPECT_NE(message.find("vehicles.ego"), std::string::npos) << message;
}

TEST(LogicalScenario, NewFunctionalScenariosNeedNoCode) {
  // Other ranges and distributions, two other vehicles, two lanes, a longer duration.
  const auto scenario = parseLogicalScenario(R"(
name: cut_through
time: {step: 0.1, duration: 8}
inputs:
  - {name: v_ego, distribution: normal, mean: 20, std: 2, min: 15, max: 25}
  - {name: gap, choices: [10, 20, 30]}
  - {name: lead_speed, min: v_ego - 5, max: v_ego}
road: {lanes: 2, centre: "0.001*x^2", lane_width: 3.25}
vehicles:
  ego: {x: -40, lane: 0, speed: v_ego, controller: {name: idm, params: {set_speed: v_ego + 2}}}
  others:
    - {id: lead, x: -40 + gap, lane: 0, speed_profile: {initial: lead_speed}}
    - {id: left, x: -45, lane: 1, length: 12, speed_profile: {initial: 15, phases: [{duration: 2, accel: 1}]}}
)", "cut_through.yaml");
  EXPECT_EQ(scenario->steps(), 80);
  EXPECT_EQ(scenario->inputs[0].distribution.kind, Distribution::Kind::Normal);
  EXPECT_EQ(scenario->inputs[1].distribution.kind, Distribution::Kind::Choice);
  EXPECT_EQ(scenario->road.lanes, 2);
  EXPECT_EQ(scenario->others.size(), 2u);
  EXPECT_DOUBLE_EQ(scenario->others[1].length, 12.0);
}

TEST(LogicalScenario, LaneIndexMustExist) {
  const auto message = errorOf(test::scenarioVariant("acc.yaml", "      x: x_co\n", "      x: x_co\n      lane: 1\n"));
  EXPECT_NE(message.find("vehicles.others[0].lane"), std::string::npos) << message;
}
