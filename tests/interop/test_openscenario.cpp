// OpenSCENARIO export and import: the concrete scenario read back, and re-simulated by
// `run` with the same metrics as the original run (issue 16).

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/interop/openscenario.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

using namespace vsd;
using namespace vsd::interop;
using ::testing::HasSubstr;

namespace {

std::shared_ptr<const scenario::LogicalScenario> load(const std::string& name) {
  return scenario::loadLogicalScenario(test::scenarioFile(name));
}

ExportHeader header() { return {"2024-01-01T00:00:00", ""}; }

/// A hand-written <ScenarioObject> opening with a 4.6 m car whose box centre is `center_x` ahead of its reference point.
std::string vehicleXml(const std::string& name, double center_x) {
  return fmt::format(R"(    <ScenarioObject name="{}">
      <Vehicle name="car" vehicleCategory="car">
        <BoundingBox><Center x="{}" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox>
        <Performance maxSpeed="70" maxAcceleration="4" maxDeceleration="9"/>
        <Axles>
          <FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.7" positionX="2.8" positionZ="0.3"/>
          <RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.7" positionX="0" positionZ="0.3"/>
        </Axles>
        <Properties/>
      </Vehicle>
)",
                     name, center_x);
}

/// Outcomes of a run without files, by sample index.
std::map<std::uint64_t, pipeline::ScenarioOutcome> simulate(const std::shared_ptr<const scenario::LogicalScenario>& logical,
                                                            std::uint64_t samples, std::uint64_t seed,
                                                            pipeline::ScenarioSource source = {}) {
  pipeline::RunOptions options;
  options.samples = samples;
  options.seed = seed;
  options.writeFiles = false;
  options.source = std::move(source);
  std::map<std::uint64_t, pipeline::ScenarioOutcome> outcomes;
  pipeline::runScenarios(logical, options, [&](const pipeline::ScenarioOutcome& outcome) {
    outcomes.emplace(outcome.index, outcome);
  });
  return outcomes;
}

}  // namespace

TEST(OpenScenario, ExportedConcreteScenarioReadsBackExactly) {
  TemporaryDirectory work("vsd-osc");
  const auto logical = load("acc_lk.yaml");
  const auto original = scenario::sampleConcreteScenario(logical, 5, 11);
  const auto files = exportConcreteScenario(original, work.path(), "acc_lk_000011", header());
  EXPECT_EQ(files.xodr.filename(), "acc_lk_000011.xodr");
  const auto imported = importOpenScenario(files.xosc);
  const auto& copy = imported.concrete;
  EXPECT_EQ(imported.logical->name, "acc_lk");
  EXPECT_DOUBLE_EQ(imported.logical->step, logical->step);
  EXPECT_DOUBLE_EQ(imported.logical->duration, logical->duration);
  EXPECT_EQ(imported.logical->inputNames(), logical->inputNames());
  EXPECT_EQ(copy.inputs, original.inputs);
  EXPECT_EQ(copy.seed, 5u);
  EXPECT_EQ(copy.index, 11u);
  EXPECT_EQ(copy.ego.headingNoise, original.ego.headingNoise);
  EXPECT_EQ(copy.controllerParams, original.controllerParams);
  EXPECT_EQ(imported.logical->ego.controller.name, "paper_ego");
  EXPECT_NEAR(copy.ego.x, original.ego.x, 1e-9);
  EXPECT_EQ(copy.ego.speed, original.ego.speed);
  EXPECT_EQ(copy.ego.length, original.ego.length);
  ASSERT_EQ(copy.others.size(), 1u);
  EXPECT_NEAR(copy.others[0].x, original.others[0].x, 1e-9);
  EXPECT_EQ(copy.others[0].scriptedSpeed, original.others[0].scriptedSpeed);
  EXPECT_EQ(copy.others[0].headingNoise, original.others[0].headingNoise);  // the Co's disturbance travels too
  EXPECT_EQ(imported.logical->metrics, logical->metrics);
  ASSERT_EQ(imported.logical->criteria.size(), 1u);
  EXPECT_EQ(imported.logical->criteria[0].expression, "d_min < 2");
  EXPECT_EQ(imported.road.centre.size(), road::buildRoadGeometry(original).centre.size());
}

// Issue 16: `.xosc` round trip — metrics equal within 1 cm / 0.01 m/s^2 / 0.01 s on 50
// scenarios of each functional scenario.
TEST(OpenScenario, ReSimulatedExportsReproduceTheOriginalMetrics) {
  TemporaryDirectory work("vsd-osc-roundtrip");
  constexpr std::uint64_t kSamples = 50;
  for (const char* name : {"acc.yaml", "lk.yaml", "acc_lk.yaml"}) {
    const auto logical = load(name);
    const auto original = simulate(logical, kSamples, 3);
    std::vector<ImportedScenario> imported;
    for (std::uint64_t index = 0; index < kSamples; ++index) {
      const auto concrete = scenario::sampleConcreteScenario(logical, 3, index);
      const auto files = exportConcreteScenario(concrete, work.path(), logical->name + std::to_string(index), header());
      imported.push_back(importOpenScenario(files.xosc));
    }
    const auto again = simulate(imported.front().logical, kSamples, 0, [&](std::uint64_t index) {
      return pipeline::ScenarioWithRoad{imported[index].concrete, imported[index].road};
    });
    ASSERT_EQ(again.size(), original.size());
    for (const auto& [index, outcome] : original) {
      const auto& copy = again.at(index);
      ASSERT_EQ(copy.failure, outcome.failure) << name << " sample " << index;
      ASSERT_EQ(copy.metrics.size(), outcome.metrics.size());
      for (std::size_t m = 0; m < outcome.metrics.size(); ++m) {
        const double a = outcome.metrics[m];
        const double b = copy.metrics[m];
        if (std::isnan(a) || std::isinf(a)) {
          EXPECT_EQ(std::isnan(a), std::isnan(b));
          EXPECT_EQ(std::isinf(a), std::isinf(b));
          continue;
        }
        EXPECT_NEAR(b, a, 0.01) << name << " sample " << index << " metric " << m;
      }
    }
  }
}

TEST(OpenScenario, AHandWrittenScenarioWithinTheSubsetRuns) {
  TemporaryDirectory work("vsd-osc-hand");
  test::writeFile(work.path() / "straight.xodr", R"(<?xml version="1.0"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="straight"/>
  <road id="r1" junction="-1" length="400">
    <planView><geometry s="0" x="-100" y="0" hdg="0" length="400"><line/></geometry></planView>
    <lanes>
      <laneOffset s="0" a="3.5" b="0" c="0" d="0"/>
      <laneSection s="0">
        <center><lane id="0" type="none"/></center>
        <right>
          <lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/><roadMark sOffset="0" type="broken" color="white"/></lane>
          <lane id="-2" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        </right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
)");
  const auto xosc = test::writeFile(work.path() / "cut.xosc", R"(<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader author="me" date="2024-01-01T00:00:00" description="brake test" revMajor="1" revMinor="1"/>
  <ParameterDeclarations>
    <ParameterDeclaration name="LeadSpeed" parameterType="double" value="15"/>
  </ParameterDeclarations>
  <CatalogLocations/>
  <RoadNetwork><LogicFile filepath="straight.xodr"/></RoadNetwork>
  <Entities>
)" + vehicleXml("Ego", 1.4) +
                                        R"(      <ObjectController><Controller name="idm"><Properties><Property name="time_gap" value="1.8"/></Properties></Controller></ObjectController>
    </ScenarioObject>
)" + vehicleXml("Lead", 0.0) + R"(    </ScenarioObject>
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
        <Private entityRef="Ego">
          <PrivateAction><TeleportAction><Position><LanePosition roadId="r1" laneId="-2" s="20" offset="0"/></Position></TeleportAction></PrivateAction>
          <PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="15"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
        </Private>
        <Private entityRef="Lead">
          <PrivateAction><TeleportAction><Position><WorldPosition x="-40" y="-1.75" h="0"/></Position></TeleportAction></PrivateAction>
          <PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="$LeadSpeed"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
        </Private>
      </Actions>
    </Init>
    <Story name="s">
      <Act name="a">
        <ManeuverGroup maximumExecutionCount="1" name="g">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="Lead"/></Actors>
          <Maneuver name="m">
            <Event name="brake" priority="overwrite">
              <Action name="brake"><PrivateAction><LongitudinalAction><SpeedAction>
                <SpeedActionDynamics dynamicsShape="linear" value="5" dynamicsDimension="rate"/>
                <SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget>
              </SpeedAction></LongitudinalAction></PrivateAction></Action>
              <StartTrigger><ConditionGroup><Condition name="t" delay="0" conditionEdge="rising">
                <ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition>
              </Condition></ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup><Condition name="start" delay="0" conditionEdge="none">
          <ByValueCondition><SimulationTimeCondition value="0" rule="greaterThan"/></ByValueCondition>
        </Condition></ConditionGroup></StartTrigger>
      </Act>
    </Story>
    <StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="none">
      <ByValueCondition><SimulationTimeCondition value="6" rule="greaterThan"/></ByValueCondition>
    </Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
)");
  try {
    importOpenScenario(xosc);
    FAIL() << "a file without a step was accepted without --step";
  } catch (const ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr("pass --step"));
  }
  ImportOptions options;
  options.step = 0.1;
  const auto imported = importOpenScenario(xosc, options);
  const auto& concrete = imported.concrete;
  EXPECT_EQ(imported.logical->steps(), 61);  // greaterThan 6 s: the first instant after 6 s
  EXPECT_EQ(imported.logical->ego.controller.name, "idm");
  EXPECT_EQ(concrete.ego.id, "Ego");
  EXPECT_EQ(concrete.ego.lane, 0);                       // OpenDRIVE lane -2 of 2 = the rightmost
  EXPECT_NEAR(concrete.ego.x, -100.0 + 20.0 + 1.4, 1e-9);  // reference point 1.4 m behind the box centre
  ASSERT_EQ(concrete.others.size(), 1u);
  EXPECT_EQ(concrete.others[0].lane, 0);  // y = -1.75: the centre of the right lane, ahead of the Ego
  EXPECT_NEAR(concrete.others[0].x, -40.0, 1e-9);
  const auto& speed = concrete.others[0].scriptedSpeed;
  ASSERT_EQ(speed.size(), 62u);
  // Brakes at 5 m/s^2 from the first instant after 1 s (t = 1.1 s) until 5 m/s (t = 3.1 s).
  EXPECT_DOUBLE_EQ(speed[0], 15.0);
  EXPECT_DOUBLE_EQ(speed[11], 15.0);
  EXPECT_NEAR(speed[12], 14.5, 1e-9);
  EXPECT_NEAR(speed[21], 10.0, 1e-9);
  EXPECT_NEAR(speed[31], 5.0, 1e-9);
  EXPECT_NEAR(speed[61], 5.0, 1e-9);
  EXPECT_EQ(imported.logical->inputNames(), std::vector<std::string>{"LeadSpeed"});
  const auto outcomes = simulate(imported.logical, 1, 0, [&](std::uint64_t) {
    return pipeline::ScenarioWithRoad{imported.concrete, imported.road};
  });
  ASSERT_TRUE(outcomes.at(0).ok()) << outcomes.at(0).failure;
  EXPECT_GT(outcomes.at(0).trace.ego().states.back().x, outcomes.at(0).trace.ego().states.front().x + 30.0);
}

TEST(OpenScenario, ElementsOutsideTheSubsetAreRefusedWithTheirLine) {
  TemporaryDirectory work("vsd-osc-bad");
  const auto logical = load("acc.yaml");
  const auto files = exportConcreteScenario(scenario::sampleConcreteScenario(logical, 1, 0), work.path(), "acc0", header());
  std::string text = readTextFile(files.xosc);
  const auto at = text.find("<Story ");
  ASSERT_NE(at, std::string::npos);
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  text.insert(at, "<Story name=\"weather\"><Act name=\"a\"><ManeuverGroup maximumExecutionCount=\"1\" name=\"g\"><Actors "
                  "selectTriggeringEntities=\"false\"/><CatalogReference catalogName=\"x\" entryName=\"y\"/>"
                  "</ManeuverGroup><StartTrigger><ConditionGroup><Condition name=\"c\" delay=\"0\" conditionEdge=\"none\">"
                  "<ByValueCondition><SimulationTimeCondition value=\"0\" rule=\"greaterThan\"/></ByValueCondition>"
                  "</Condition></ConditionGroup></StartTrigger></Act></Story>\n");
  const auto bad = test::writeFile(work.path() / "bad.xosc", text);
  test::writeFile(work.path() / "acc0.xodr", readTextFile(files.xodr));
  try {
    importOpenScenario(bad);
    FAIL() << "a CatalogReference in a ManeuverGroup was accepted";
  } catch (const ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr(fmt::format("bad.xosc:{}: element <CatalogReference> is outside the supported subset", line)));
    EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos);
  }
}
