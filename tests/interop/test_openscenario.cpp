// OpenSCENARIO export and import: the concrete scenario read back, and re-simulated by
// `run` with the same metrics as the original run (issue 16).

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <regex>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/interop/opendrive.hpp"
#include "vsd/interop/openscenario.hpp"
#include "vsd/interop/roundtrip.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

using namespace vsd;
using namespace vsd::interop;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

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

namespace {

/// `text` with the first match of `pattern` replaced (regex syntax).
std::string edited(const std::string& text, const std::string& pattern, const std::string& replacement) {
  return std::regex_replace(text, std::regex(pattern), replacement, std::regex_constants::format_first_only);
}

std::string property(const std::string& name, const std::string& value) {
  return "name=\"" + name + "\" value=\"" + value + "\"";
}

}  // namespace

// Issue 29: an imported file carries data, not commands, and its numbers are checked as
// the YAML's are — each refusal one line naming the file, the field and the value.
TEST(OpenScenario, HostileFilesAreRefusedInOneLineBeforeAnyWork) {
  TemporaryDirectory work("vsd-osc-hostile");
  const auto logical = load("acc.yaml");
  const auto files = exportConcreteScenario(scenario::sampleConcreteScenario(logical, 1, 0), work.path(), "acc0", header());
  const std::string text = readTextFile(files.xosc);
  const std::string seed = R"(name="vsd-sumo\.seed" value="[^"]*")";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {edited(text, R"(name="vsd-sumo\.sumo\.options" value="\[\]")",
              property("vsd-sumo.sumo.options", "[&quot;--fcd-output&quot;,&quot;/tmp/x.xml&quot;]")),
       "vsd-sumo.sumo.options[0]: got '--fcd-output', expected an option a scenario file may pass to SUMO"},
      {edited(text, R"(name="vsd-sumo\.sumo\.netconvert_options" value="\[\]")",
              property("vsd-sumo.sumo.netconvert_options", "[&quot;--plain-output-prefix&quot;,&quot;/tmp/p&quot;]")),
       "vsd-sumo.sumo.netconvert_options[0]: got '--plain-output-prefix'"},
      {edited(text, seed, property("vsd-sumo.seed", "abc")), "vsd-sumo.seed: got 'abc', expected a whole number"},
      {edited(text, seed, property("vsd-sumo.seed", "")), "vsd-sumo.seed: got '', expected a whole number 0 .. 18446744073709551615 (empty)"},
      {edited(text, seed, property("vsd-sumo.seed", "nan")), "(NaN is not a number)"},
      {edited(text, seed, property("vsd-sumo.seed", "18446744073709551616")), "(out of range)"},
      {edited(text, seed, property("vsd-sumo.seed", "-1")), "vsd-sumo.seed: got '-1'"},
      {edited(text, seed, property("vsd-sumo.seed", "1.5")), "(a fraction)"},
      {edited(text, R"(name="vsd-sumo\.sample" value="[^"]*")", property("vsd-sumo.sample", "-1")),
       "vsd-sumo.sample: got '-1', expected a whole number 0 .. 1125899906842623"},
      {edited(text, R"(length="5")", "length=\"1e300\""), "<Dimensions>: length: got '1e300', expected a finite number in (0, 100]"},
      {edited(text, R"(maxSpeed="[^"]*")", "maxSpeed=\"nan\""), "<Performance>: maxSpeed: got 'nan'"},
      {edited(text, R"(maxDeceleration="[^"]*")", "maxDeceleration=\"-9\""), "<Performance>: maxDeceleration: got '-9'"},
      {edited(text, R"(name="vsd-sumo\.sumo\.collision_action" value="[^"]*")",
              property("vsd-sumo.sumo.collision_action", "explode")),
       "vsd-sumo.sumo.collision_action: got 'explode', expected one of none, warn, teleport, remove"},
      {edited(text, R"(name="vsd-sumo\.road\.x_range" value="[^"]*")", property("vsd-sumo.road.x_range", "55 -55")),
       "vsd-sumo.road.x_range: got '55 -55', expected x_min < x_max"},
      {edited(text, R"(name="vsd-sumo\.road\.extension" value="[^"]*")", property("vsd-sumo.road.extension", "30 1e9")),
       "vsd-sumo.road.extension (second number): got '1e9'"},
      {edited(text, R"(name="vsd-sumo\.step" value="[^"]*")", property("vsd-sumo.step", "1e-5")),
       "vsd-sumo.step: got '1e-5', expected a multiple of 0.001 s"},
      {edited(text, R"(<SimulationTimeCondition rule="greaterOrEqual" value="5" />)",
              "<SimulationTimeCondition rule=\"greaterOrEqual\" value=\"1e9\" />"),
       "got '1000000000', expected a whole multiple of the step (0.2 s), 1 .. 1000 steps"},
      {edited(text, R"(filepath="[^"]*")", "filepath=\"/dev/zero\""), "<LogicFile>: filepath: got '/dev/zero', expected a path inside"},
      {edited(text, R"(filepath="[^"]*")", "filepath=\"../acc0.xodr\""), "<LogicFile>: filepath: got '../acc0.xodr'"},
      {edited(text, R"(<Property name="time_gap")", "<Property name=\"vsd-sumo.library\" value=\"../../lib/libx.so\" /><Property name=\"time_gap\""),
       "vsd-sumo.library: got '../../lib/libx.so', expected a path inside"},
      // Issue 24's bad input: entity declarations (billion laughs, an external entity) are
      // refused, not read with the entity names left in the text.
      {edited(edited(text, R"(<OpenSCENARIO)",
                     "<!DOCTYPE OpenSCENARIO [ <!ENTITY a0 \"lol\"> <!ENTITY a1 \"&a0;&a0;&a0;&a0;&a0;&a0;&a0;&a0;&a0;&a0;\"> ]>"
                     "<OpenSCENARIO"),
              seed, property("vsd-sumo.seed", "&a1;")),
       "hostile.xosc:2: the document type declares entities (<!ENTITY ...>)"},
      {edited(text, R"(<OpenSCENARIO)", "<!DOCTYPE OpenSCENARIO [ <!ENTITY xxe SYSTEM \"file:///etc/passwd\"> ]><OpenSCENARIO"),
       "hostile.xosc:2: the document type declares entities"},
  };
  const fs::path folder = work.path() / "inner";
  fs::create_directories(folder);
  test::writeFile(folder / "acc0.xodr", readTextFile(files.xodr));
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto& [mutated, expected] = cases[i];
    ASSERT_NE(mutated, text) << "case " << i << " changed nothing: " << expected;
    const auto file = test::writeFile(folder / "hostile.xosc", mutated);
    try {
      importOpenScenario(file);
      ADD_FAILURE() << "case " << i << " was accepted: " << expected;
    } catch (const ConfigError& error) {
      EXPECT_THAT(error.what(), HasSubstr(expected)) << "case " << i;
      EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos);
    }
  }
}

// Issue 29: an OpenDRIVE road of absurd size is refused before any point is computed.
TEST(OpenDriveImport, GeometryIsBoundedBeforeWork) {
  TemporaryDirectory work("vsd-odr-huge");
  const auto logical = load("acc.yaml");
  const auto files = exportConcreteScenario(scenario::sampleConcreteScenario(logical, 1, 0), work.path(), "acc0", header());
  const std::string text = readTextFile(files.xodr);
  const auto last = text.rfind("<geometry ");
  const auto end = text.find("</geometry>", last) + std::string("</geometry>").size();
  const std::string geometry = text.substr(last, end - last);
  const auto with_last = [&](const std::string& replacement) {
    return text.substr(0, last) + replacement + text.substr(end);
  };
  const std::string arc = edited(geometry, "<line ?/>", "<arc curvature=\"0.001\" />");
  std::string many;  // short ones: the count is the bound that holds first
  const std::string short_geometry = edited(geometry, R"(length="[^"]*")", "length=\"0.1\"");
  for (int i = 0; i < 100'001; ++i) many += short_geometry;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {with_last(edited(arc, R"(length="[^"]*")", "length=\"1e9\"")), "length: got '1e9', expected a finite number in (0, 50000]"},
      {with_last(edited(arc, R"(length="[^"]*")", "length=\"49900\"")), "the road is longer than 50000 m here"},
      {with_last(edited(geometry, "<line ?/>", "<arc curvature=\"1e9\" />")), "curvature: got '1e9'"},
      {with_last(many), "more than 100000 geometries"},
  };
  for (const auto& [mutated, expected] : cases) {
    const auto file = test::writeFile(work.path() / "huge.xodr", mutated);
    try {
      readOpenDrive(file);
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const ConfigError& error) {
      EXPECT_THAT(error.what(), HasSubstr(expected));
    }
  }
}

// Issue 29: comparing netconvert's lanes with vsd-sumo's is n log n — a 50 km road with
// 100,000 points in each polyline (the quadratic way took minutes; the figures are in the
// report of the issue, not asserted here) — and exact.
TEST(OpenDriveImport, PolylineDeviationIsExactOnHugeRoads) {
  Polyline a;
  Polyline b;
  for (int i = 0; i <= 100'000; ++i) {
    const double s = 0.5 * i;
    a.emplace_back(s, 100.0 * std::sin(s / 1000.0));
    b.emplace_back(s + 0.25, 100.0 * std::sin((s + 0.25) / 1000.0) + (i == 50'000 ? 0.3 : 0.0));
  }
  EXPECT_NEAR(polylineDeviation(a, b), 0.3, 0.01);  // the one displaced vertex
  // Against the obvious definition on a small pair.
  Polyline c = {{0, 0}, {1, 0}, {2, 1}, {3, 1}};
  Polyline d = {{0, 0.5}, {1.5, 0.2}, {3, 2}};
  double worst = 0.0;
  for (const auto& p : c) worst = std::max(worst, (MeasuredPolyline(d).project(p).foot - p).norm());
  for (const auto& p : d) worst = std::max(worst, (MeasuredPolyline(c).project(p).foot - p).norm());
  EXPECT_DOUBLE_EQ(polylineDeviation(c, d), worst);
}
