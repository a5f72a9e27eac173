#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/road/network.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/sim/sumo_session.hpp"

using namespace vsd;
using namespace vsd::road;

namespace {
scenario::ConcreteScenario sample(const std::string& file, std::uint64_t index) {
  return scenario::sampleConcreteScenario(scenario::loadLogicalScenario(test::scenarioFile(file)), 1, index);
}
}  // namespace

TEST(RoadGeometry, LanePointsFollowThePolynomialPlusNoise) {
  const auto concrete = sample("acc_lk.yaml", 3);
  const auto road = buildRoadGeometry(concrete);
  ASSERT_EQ(road.regionEnd - road.regionBegin, 25u);
  const auto& in = concrete.inputs;  // a0..a3 first
  for (std::size_t i = 0; i < 25; ++i) {
    const Vec2 p = road.centre[road.regionBegin + i];
    const double x = -55.0 + 110.0 / 24.0 * static_cast<double>(i);
    EXPECT_NEAR(p.x(), x, 1e-9);
    const double polynomial = in[0] + in[1] * x + in[2] * x * x + in[3] * x * x * x;
    EXPECT_NEAR(p.y(), polynomial + concrete.centreNoise[i], 1e-9);
  }
  EXPECT_DOUBLE_EQ(road.laneWidth, concrete.laneWidth);
}

TEST(RoadGeometry, ExtensionsAreStraightAlongTheEndTangents) {
  const auto concrete = sample("acc.yaml", 0);  // straight road: tangents along +x
  const auto road = buildRoadGeometry(concrete);
  const Vec2 first = road.centre[road.regionBegin];
  const Vec2 last = road.centre[road.regionEnd - 1];
  EXPECT_TRUE(road.centre.front().isApprox(first - Vec2(30.0, 0.0), 1e-9));
  EXPECT_TRUE(road.centre.back().isApprox(last + Vec2(150.0, 0.0), 1e-9));
}

TEST(RoadGeometry, LanesSpreadAroundTheCentreWithLaneZeroRightmost) {
  RoadGeometry road;
  road.centre = {{0, 0}, {100, 0}};
  road.lanes = 3;
  road.laneWidth = 3.0;
  EXPECT_DOUBLE_EQ(road.laneOffset(0), -3.0);
  EXPECT_DOUBLE_EQ(road.laneOffset(1), 0.0);
  EXPECT_DOUBLE_EQ(road.laneOffset(2), 3.0);
  const auto start = startPoseOnLane(road, 2, 40.0, "v");
  EXPECT_TRUE(start.position.isApprox(Vec2(40.0, 3.0)));
  EXPECT_THROW(startPoseOnLane(road, 0, 200.0, "v"), ConfigError);
}

TEST(BatchLayout, OffsetsDependOnlyOnTheSampleIndexAndNeverCollideWithinABatch) {
  const BatchLayout layout(1000.0);
  EXPECT_TRUE(layout.offsetFor(17).isApprox(layout.offsetFor(17 + BatchLayout::kMaxBatch)));
  std::set<std::pair<double, double>> cells;
  for (std::uint64_t i = 5000; i < 5000 + BatchLayout::kMaxBatch; ++i) {
    const Vec2 offset = layout.offsetFor(i);
    EXPECT_GT(offset.minCoeff(), 0.0);
    cells.emplace(offset.x(), offset.y());
  }
  EXPECT_EQ(cells.size(), BatchLayout::kMaxBatch);
}

TEST(BatchLayout, CellSizeCoversTheRoadAndItsExtensions) {
  scenario::RoadSpec spec;
  EXPECT_DOUBLE_EQ(BatchLayout::cellSizeFor(spec), 1000.0);
  spec.extensionAfter = 800.0;
  EXPECT_GE(BatchLayout::cellSizeFor(spec), 2.0 * (55.0 + 800.0));
  const auto concrete = sample("acc_lk.yaml", 0);
  EXPECT_TRUE(BatchLayout(1000.0).fits(buildRoadGeometry(concrete)));
  RoadGeometry huge;
  huge.centre = {{-600, 0}, {600, 0}};
  EXPECT_FALSE(BatchLayout(1000.0).fits(huge));
}

TEST(Network, SumoBuildsExactlyTheGeneratedLanesForManyScenariosInOneNet) {
  TemporaryDirectory dir;
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc_lk.yaml"));
  const BatchLayout layout(BatchLayout::cellSizeFor(logical->road));
  NetworkBuilder builder;
  std::vector<RoadGeometry> roads;
  for (std::uint64_t i = 0; i < 20; ++i) {
    roads.push_back(buildRoadGeometry(scenario::sampleConcreteScenario(logical, 1, i)));
    builder.add(i, roads.back(), layout.offsetFor(i));
  }
  builder.writePlainXml(dir.path() / "net");
  const auto net = PendingNetwork::start(dir.path() / "net", {}).wait();
  ASSERT_TRUE(std::filesystem::exists(net));
  sim::SumoSession session({"--net-file", net.string()});
  for (std::uint64_t i = 0; i < 20; ++i) {
    const auto lane = sim::fetchLane(edgeIdFor(i) + "_0", layout.offsetFor(i));
    EXPECT_NEAR(lane.width, roads[i].laneWidth, 0.01);
    // Every generated point is in SUMO's lane shape, at netconvert's 0.01 m precision.
    ASSERT_EQ(lane.centre.size(), roads[i].centre.size());
    for (std::size_t k = 0; k < lane.centre.size(); ++k) {
      EXPECT_NEAR(lane.centre[k].x(), roads[i].centre[k].x(), 0.006);
      EXPECT_NEAR(lane.centre[k].y(), roads[i].centre[k].y(), 0.006);
    }
  }
}

TEST(Network, NetconvertFailureNamesTheInputAndTheReason) {
  TemporaryDirectory dir;
  NetworkBuilder builder;
  RoadGeometry road;
  road.centre = {{0, 0}, {100, 0}};
  builder.add(0, road, {1000, 1000});
  builder.writePlainXml(dir.path() / "net");
  try {
    PendingNetwork::start(dir.path() / "net", {"--no-such-option"}).wait();
    FAIL() << "expected SumoError";
  } catch (const SumoError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("netconvert failed"), std::string::npos) << message;
    EXPECT_NE(message.find((dir.path() / "net").string()), std::string::npos) << message;
    EXPECT_NE(message.find("no-such-option"), std::string::npos) << message;
  }
}
