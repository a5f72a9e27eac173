#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/road/network.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/sim/sumo_session.hpp"

#include <libsumo/libsumo.h>

#include <map>

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
  EXPECT_EQ(road.laneWidths, concrete.laneWidths);
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
  road.laneWidths.assign(static_cast<std::size_t>(road.lanes), 3.0);
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
    EXPECT_NEAR(lane.width, roads[i].laneWidthOf(0), 0.01);
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
  road.laneWidths.assign(static_cast<std::size_t>(road.lanes), kDefaultLaneWidth);
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

// --- the direct .net.xml writer against netconvert -------------------------------------

namespace {

/// What SUMO loaded from a network: everything the simulation uses of our roads.
struct LoadedNet {
  struct Lane {
    std::vector<Vec2> shape;
    double width = 0.0;
    double length = 0.0;
    double speed = 0.0;
    std::size_t links = 0;
  };
  struct Junction {
    Vec2 position;
    std::vector<Vec2> shape;
  };
  std::map<std::string, std::vector<std::string>> edgeLanes;
  std::map<std::string, Lane> lanes;
  std::map<std::string, Junction> junctions;
};

std::vector<Vec2> toPoints(const libsumo::TraCIPositionVector& shape) {
  std::vector<Vec2> points;
  for (const auto& p : shape.value) points.emplace_back(p.x, p.y);
  return points;
}

LoadedNet loadWithSumo(const std::filesystem::path& net) {
  sim::SumoSession session({"--net-file", net.string()});
  LoadedNet loaded;
  for (const auto& lane : libsumo::Lane::getIDList()) {
    loaded.edgeLanes[libsumo::Lane::getEdgeID(lane)].push_back(lane);
    loaded.lanes[lane] = {toPoints(libsumo::Lane::getShape(lane)), libsumo::Lane::getWidth(lane),
                          libsumo::Lane::getLength(lane), libsumo::Lane::getMaxSpeed(lane),
                          libsumo::Lane::getLinks(lane).size()};
  }
  for (const auto& junction : libsumo::Junction::getIDList()) {
    const auto position = libsumo::Junction::getPosition(junction);
    loaded.junctions[junction] = {Vec2(position.x, position.y), toPoints(libsumo::Junction::getShape(junction))};
  }
  return loaded;
}

void expectSamePoints(const std::vector<Vec2>& direct, const std::vector<Vec2>& reference, const std::string& what) {
  ASSERT_EQ(direct.size(), reference.size()) << what;
  for (std::size_t k = 0; k < direct.size(); ++k) {
    EXPECT_LE((direct[k] - reference[k]).norm(), 0.01) << what << " point " << k;
  }
}

/// Roads that exercise every rule of netconvert's lane shapes: a dense stretch (points
/// closer than 0.1 m are dropped), almost straight kinks (moved along the chord), sharp
/// bends (moved to the intersection of the offset segments), 1 to 3 lanes.
std::vector<RoadGeometry> awkwardRoads() {
  std::vector<RoadGeometry> roads;
  RoadGeometry dense;
  dense.lanes = 3;
  dense.laneWidths.assign(static_cast<std::size_t>(dense.lanes), 3.2);
  for (int i = 0; i <= 40; ++i) dense.centre.emplace_back(-100.0 + 0.06 * i, 0.01 * i);
  dense.centre.emplace_back(0.0, 16.0);
  dense.centre.emplace_back(0.03, 16.005);  // the last point closer than 0.1 m to its predecessor
  roads.push_back(dense);
  RoadGeometry single;  // one lane: its shape is the edge's, whatever the bends
  single.laneWidths.assign(static_cast<std::size_t>(single.lanes), kDefaultLaneWidth);
  single.centre = {{-100, 0}, {-99.95, 0.01}, {-99.9, 0.3}, {-60, 40}, {-59, 40}, {0, -10}, {0.05, -10.02}};
  roads.push_back(single);
  RoadGeometry kinks;
  kinks.lanes = 2;
  kinks.laneWidths.assign(static_cast<std::size_t>(kinks.lanes), 3.75);
  kinks.centre = {{-200, 0}, {-100, 0.05}, {-50, 0.06}, {0, 20}, {10, 21}, {60, 90}, {200, 95}};
  roads.push_back(kinks);
  return roads;
}

}  // namespace

TEST(DirectNetwork, SumoLoadsTheSameLanesAsNetconvertBuildsForTheSameRoads) {
  TemporaryDirectory dir;
  NetworkBuilder builder;
  std::uint64_t index = 0;
  std::size_t lanes = 0;
  std::vector<Vec2> offsets;
  auto add = [&](const RoadGeometry& road, const BatchLayout& layout) {
    builder.add(index, road, layout.offsetFor(index));
    offsets.push_back(layout.offsetFor(index));
    lanes += static_cast<std::size_t>(road.lanes);
    ++index;
  };
  for (const std::string file : {"acc.yaml", "lk.yaml", "acc_lk.yaml"}) {
    const auto logical = scenario::loadLogicalScenario(test::scenarioFile(file));
    const BatchLayout layout(BatchLayout::cellSizeFor(logical->road));
    for (int i = 0; i < 40; ++i) {
      auto road = buildRoadGeometry(scenario::sampleConcreteScenario(logical, 7, index));
      road.lanes = 1 + i % 3;  // noisy bends moved sideways, too
      road.laneWidths.assign(static_cast<std::size_t>(road.lanes), road.laneWidths.front());
      add(road, layout);
    }
  }
  for (const auto& road : awkwardRoads()) add(road, BatchLayout(1000.0));
  ASSERT_TRUE(builder.directlyWritable());

  builder.writePlainXml(dir.path() / "reference");
  const auto reference = loadWithSumo(PendingNetwork::start(dir.path() / "reference", {}).wait());
  const auto direct = loadWithSumo(builder.writeSumoNet(dir.path() / "direct"));

  ASSERT_EQ(direct.edgeLanes, reference.edgeLanes);  // same edges, same lanes in the same order
  ASSERT_EQ(direct.lanes.size(), lanes);
  for (const auto& [id, lane] : reference.lanes) {
    const auto& mine = direct.lanes.at(id);
    // SUMO gets straight runs without their inner points: what it loads lies on netconvert's lanes.
    expectSamePoints({mine.shape.front(), mine.shape.back()}, {lane.shape.front(), lane.shape.back()}, "lane " + id);
    const MeasuredPolyline netconvert_lane(lane.shape);
    for (const Vec2& point : mine.shape) EXPECT_LT(std::abs(netconvert_lane.project(point).lateralOffset), 0.01) << id;
    EXPECT_DOUBLE_EQ(mine.width, lane.width) << id;
    EXPECT_DOUBLE_EQ(mine.length, lane.length) << id;
    EXPECT_DOUBLE_EQ(mine.speed, lane.speed) << id;
    EXPECT_EQ(mine.links, lane.links) << id;
  }
  // vsd-sumo measures its lanes on the full detail: netconvert's points, widths.
  for (std::uint64_t i = 0; i < index; ++i) {
    for (const auto& lane : builder.lanesAsLoaded(i)) {
      const auto& built = reference.lanes.at(lane.id);
      std::vector<Vec2> in_net;
      for (const Vec2& point : lane.centre) in_net.push_back(point + offsets[i]);
      expectSamePoints(in_net, built.shape, "full-detail lane " + lane.id);
      EXPECT_DOUBLE_EQ(lane.width, built.width) << lane.id;
    }
  }
  ASSERT_EQ(direct.junctions.size(), reference.junctions.size());
  for (const auto& [id, junction] : reference.junctions) {
    const auto& mine = direct.junctions.at(id);
    EXPECT_LE((mine.position - junction.position).norm(), 0.01) << id;
    expectSamePoints(mine.shape, junction.shape, "junction " + id);
  }
}

TEST(DirectNetwork, RoadsWhoseLanesFoldAtABendAreLeftToNetconvert) {
  // A 3-lane road turning at a point 0.12 m after the previous one: the right lane's
  // mitre (~0.1 m) is longer than half that segment; netconvert then cuts the lane at
  // the junction, which the direct writer does not reproduce.
  RoadGeometry road;
  road.lanes = 3;
  road.laneWidths.assign(static_cast<std::size_t>(road.lanes), 3.2);
  road.centre = {{-100, 0}, {-2.4, 0.4}, {-2.28, 0.42}, {0, 5}};
  NetworkBuilder folding;
  folding.add(0, road, {1000, 1000});
  EXPECT_FALSE(folding.directlyWritable());
  road.lanes = 1;  // the centre lane alone never folds
  road.laneWidths.resize(1);
  NetworkBuilder single;
  single.add(0, road, {1000, 1000});
  EXPECT_TRUE(single.directlyWritable());
  // Lanes of different widths (esmini's e6mini: 3.65, 3.5, 3.9 m) go to netconvert too.
  road.lanes = 3;
  road.laneWidths = {3.65, 3.5, 3.9};
  road.centre = {{-100, 0}, {0, 0}, {100, 0}};
  NetworkBuilder widths;
  widths.add(0, road, {0, 0});
  EXPECT_FALSE(widths.directlyWritable());
}

// netconvert puts lanes of different widths where the road's geometry has them (on a bend too).
TEST(DirectNetwork, NetconvertPlacesLanesOfDifferentWidthsWhereTheRoadHasThem) {
  TemporaryDirectory dir;
  RoadGeometry road;
  road.lanes = 3;
  road.laneWidths = {3.65, 3.5, 3.9};
  for (int i = 0; i <= 40; ++i) {
    const double angle = 0.005 * i;  // 200 m radius
    road.centre.emplace_back(200.0 * std::sin(angle) - 100.0, 200.0 * (1.0 - std::cos(angle)));
  }
  NetworkBuilder builder;
  builder.add(0, road, {0, 0});
  builder.writePlainXml(dir.path() / "widths");
  const auto loaded = loadWithSumo(PendingNetwork::start(dir.path() / "widths", {}).wait());
  for (int lane = 0; lane < road.lanes; ++lane) {
    const auto& built = loaded.lanes.at(edgeIdFor(0) + "_" + std::to_string(lane));
    EXPECT_NEAR(built.width, road.laneWidthOf(lane), 1e-9);
    const MeasuredPolyline centre(road.laneCentre(lane));
    for (const Vec2& point : built.shape) EXPECT_LT(std::abs(centre.project(point).lateralOffset), 0.02) << lane;
  }
}

namespace {
std::string polylineRoad(const std::string& centre_line, const std::string& extra = "") {
  return "name: bend\nroad: {shape: polyline, centre_line: " + centre_line + ", lanes: 2" + extra +
         "}\nvehicles:\n  ego: {s: 20, lane: 0, speed: 10, controller: {name: idm}}\n";
}
std::string polylineError(const std::string& centre_line, const std::string& extra = "") {
  try {
    scenario::parseLogicalScenario(polylineRoad(centre_line, extra), "bend.yaml");
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}
}  // namespace

TEST(RoadGeometry, APolylineRoadIsItsPointsWithStraightExtensionsAndAFittingCell) {
  const auto logical = scenario::parseLogicalScenario(polylineRoad("[[0, 0], [100, 0], [200, 50], [300, 50]]"), "bend.yaml");
  const auto road = buildRoadGeometry(scenario::sampleConcreteScenario(logical, 1, 0));
  ASSERT_EQ(road.regionEnd - road.regionBegin, 4u);
  EXPECT_TRUE(road.centre[road.regionBegin + 2].isApprox(Vec2(200.0, 50.0)));
  // Extensions (30 m before, 150 m after by default) along the first and the last segment.
  EXPECT_TRUE(road.centre.front().isApprox(Vec2(-30.0, 0.0), 1e-12));
  EXPECT_TRUE(road.centre.back().isApprox(Vec2(450.0, 50.0), 1e-12));
  EXPECT_EQ(regionXRange(*logical, {}), std::make_pair(0.0, 300.0));
  EXPECT_TRUE(BatchLayout(BatchLayout::cellSizeFor(logical->road)).fits(road));
}

TEST(RoadGeometry, PolylineRoadsThatScenesCannotClipByXAreRefused) {
  EXPECT_NE(polylineError("[[0, 0]]").find("road.centre_line: a polyline road needs 'centre_line'"), std::string::npos);
  // Turning back: the second segment heads 2.36 rad from +x.
  EXPECT_NE(polylineError("[[0, 0], [100, 0], [90, 10]]").find("road.centre_line[2]"), std::string::npos);
  EXPECT_NE(polylineError("[[0, 0], [100, 0], [90, 10]]").find("at most 1.4 rad"), std::string::npos);
  EXPECT_NE(polylineError("[[0, 0], [0, 0]]").find("at least 1 mm"), std::string::npos);
  EXPECT_NE(polylineError("[[0, 0], [10, 0]]", ", length: 10").find("road.length: belongs to another road shape"),
            std::string::npos);
  EXPECT_NE(polylineError("[[0, 0], [x, 0]]").find("road.centre_line[1][0]"), std::string::npos);
}
