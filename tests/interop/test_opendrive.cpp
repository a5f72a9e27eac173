// OpenDRIVE export: the road read back, and through SUMO's netconvert (a real consumer).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/interop/opendrive.hpp"
#include "vsd/interop/roundtrip.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

using namespace vsd;
using namespace vsd::interop;
using ::testing::HasSubstr;

namespace {

scenario::ConcreteScenario sample(const std::shared_ptr<const scenario::LogicalScenario>& logical, std::uint64_t index) {
  return scenario::sampleConcreteScenario(logical, 7, index);
}

std::shared_ptr<const scenario::LogicalScenario> threeLaneAccLk() {
  return scenario::parseLogicalScenario(test::scenarioVariant("acc_lk.yaml", "lanes: 1", "lanes: 3"),
                                        test::scenarioFile("acc_lk_3_lanes.yaml"));
}

std::string roadWith(const std::string& geometry, const std::string& lanes) {
  return R"(<?xml version="1.0"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="hand-written"/>
  <road id="7" junction="-1" length="100">
    <planView>
)" + geometry + R"(
    </planView>
    <lanes>
      <laneOffset s="0" a="1.75" b="0" c="0" d="0"/>
      <laneSection s="0">
        <center><lane id="0" type="none"/></center>
        <right>
)" + lanes + R"(
        </right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
)";
}

const std::string kLine = R"(<geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry>)";
const std::string kLane = R"(<lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>)";

}  // namespace

TEST(OpenDrive, ExportedRoadReadsBackExactly) {
  TemporaryDirectory work("vsd-od");
  for (const auto& logical : {scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml")), threeLaneAccLk()}) {
    const auto concrete = sample(logical, 4);
    const auto road = road::buildRoadGeometry(concrete);
    writeOpenDrive(road, "s4", work.path() / "s4.xodr");
    const auto read = readOpenDrive(work.path() / "s4.xodr");
    EXPECT_EQ(read.id, "1");
    ASSERT_EQ(read.geometry.centre.size(), road.centre.size());
    for (std::size_t i = 0; i < road.centre.size(); ++i) {
      EXPECT_NEAR((read.geometry.centre[i] - road.centre[i]).norm(), 0.0, 1e-9) << "point " << i;
    }
    EXPECT_EQ(read.geometry.lanes, road.lanes);
    EXPECT_EQ(read.geometry.laneWidths, road.laneWidths);
    EXPECT_DOUBLE_EQ(read.geometry.speedLimit, road.speedLimit);
  }
}

// Lanes of different widths: OpenDRIVE numbers them from the reference line (-1 the leftmost).
TEST(OpenDrive, LanesOfDifferentWidthsReadBackInTheirPlaces) {
  TemporaryDirectory work("vsd-od");
  auto road = road::buildRoadGeometry(sample(threeLaneAccLk(), 4));
  road.laneWidths = {3.65, 3.5, 3.9};
  writeOpenDrive(road, "s4", work.path() / "s4.xodr");
  const auto read = readOpenDrive(work.path() / "s4.xodr");
  EXPECT_EQ(read.geometry.laneWidths, road.laneWidths);
  EXPECT_NEAR(read.geometry.laneOffset(0), -(3.65 + 3.5 + 3.9) / 2 + 3.65 / 2, 1e-12);
  EXPECT_NEAR(read.geometry.laneOffset(2), (3.65 + 3.5 + 3.9) / 2 - 3.9 / 2, 1e-12);
}

TEST(OpenDrive, RoadCoordinatesInvertOnLaneCentres) {
  const auto logical = threeLaneAccLk();
  const auto road = road::buildRoadGeometry(sample(logical, 2));
  for (int lane = 0; lane < road.lanes; ++lane) {
    const auto start = road::startPoseOnLane(road, lane, -20.0, "v");
    const auto coordinate = toRoadCoordinate(road, start.position);
    EXPECT_NEAR(coordinate.t, road.laneOffset(lane), 1e-6);
    EXPECT_NEAR((fromRoadCoordinate(road, coordinate) - start.position).norm(), 0.0, 1e-9);
  }
}

// Issue 16: the exported .xodr, imported by netconvert, gives lane centres within 5 cm
// of the network vsd-sumo generated for the same scenario (benchmark: 200 scenarios).
TEST(OpenDrive, NetconvertImportMatchesTheGeneratedNetwork) {
  TemporaryDirectory work("vsd-od-netconvert");
  for (const auto& logical : {scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml")), threeLaneAccLk()}) {
    std::vector<scenario::ConcreteScenario> scenarios;
    for (std::uint64_t index = 0; index < 4; ++index) scenarios.push_back(sample(logical, index));
    const auto deviations = netconvertRoundTrip(scenarios, work.path());
    ASSERT_EQ(deviations.size(), scenarios.size());
    for (const auto& deviation : deviations) {
      EXPECT_LE(deviation.maxDeviation, 0.05) << logical->name << " sample " << deviation.sample;
    }
  }
}

TEST(OpenDrive, ArcsAreSampledOntoTheCircle) {
  TemporaryDirectory work("vsd-od-arc");
  const auto file = test::writeFile(
      work.path() / "arc.xodr",
      roadWith(R"(<geometry s="0" x="0" y="0" hdg="0" length="31.41592653589793"><arc curvature="0.05"/></geometry>)", kLane));
  const auto road = readOpenDrive(file).geometry;
  for (const auto& point : road.centre) EXPECT_NEAR((point - Vec2(0.0, 20.0)).norm(), 20.0, 1e-9);
  EXPECT_NEAR((road.centre.back() - Vec2(20.0, 20.0)).norm(), 0.0, 1e-9);  // a quarter circle
  EXPECT_EQ(road.lanes, 1);
}

TEST(OpenDrive, ElementsOutsideTheSubsetAreNamedWithTheirLine) {
  TemporaryDirectory work("vsd-od-bad");
  const auto spiral = test::writeFile(
      work.path() / "spiral.xodr",
      roadWith(R"(<geometry s="0" x="0" y="0" hdg="0" length="100"><spiral curvStart="0" curvEnd="0.01"/></geometry>)", kLane));
  try {
    readOpenDrive(spiral);
    FAIL() << "a spiral was accepted";
  } catch (const ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr("spiral.xodr:6:"));
    EXPECT_THAT(error.what(), HasSubstr("element <spiral> is outside the supported subset"));
  }
  const auto left = test::writeFile(work.path() / "left.xodr",
                                    roadWith(kLine, kLane + R"(</right><left><lane id="1" type="driving"/></left><right>)"));
  EXPECT_THROW(readOpenDrive(left), ConfigError);
  const auto varying = test::writeFile(
      work.path() / "varying.xodr",
      roadWith(kLine, R"(<lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0.01" c="0" d="0"/></lane>)"));
  try {
    readOpenDrive(varying);
    FAIL() << "a varying width was accepted";
  } catch (const ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr("varying.xodr:13: <width>: b=\"0.01\""));
  }
  const auto broken = test::writeFile(work.path() / "broken.xodr", "<OpenDRIVE><header revMajor=\"1\"></OpenDRIVE>");
  EXPECT_THROW(readOpenDrive(broken), ConfigError);
}

TEST(OpenDrive, AFileNetconvertRejectsIsOneLineNamingIt) {
  TemporaryDirectory work("vsd-od-reject");
  // Well-formed XML, but the geometry has no length: netconvert refuses it.
  const auto file = test::writeFile(work.path() / "rejected.xodr",
                                    roadWith(R"(<geometry s="0" x="0" y="0" hdg="0"><line/></geometry>)", kLane));
  try {
    netconvertLanes(file, "7", work.path());
    FAIL() << "netconvert accepted a geometry without length";
  } catch (const SumoError& error) {
    EXPECT_THAT(error.what(), HasSubstr("netconvert rejects " + file.string()));
    EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos);
  }
}
