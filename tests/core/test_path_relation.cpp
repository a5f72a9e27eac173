#include <gtest/gtest.h>

#include <cmath>

#include "vsd/core/path_relation.hpp"
#include "vsd/core/road_user.hpp"

using namespace vsd;

namespace {

// A straight lane along +x and a car-sized Ego on its centre line at x = 0.
const MeasuredPolyline kStraightLane({{-100.0, 0.0}, {0.0, 0.0}, {100.0, 0.0}});
constexpr double kLaneWidth = 3.5;
const Footprint kEgo{{0.0, 0.0}, 0.0, 5.0, 1.8};

Footprint car(double x, double y, double heading = 0.0) { return {{x, y}, heading, 5.0, 1.8}; }

}  // namespace

TEST(PathRelation, LeaderInTheEgoLaneIsInPathWithItsBumperGap) {
  const auto relation = relateToPath(kStraightLane, kLaneWidth, kEgo, car(30.0, 0.2));
  EXPECT_TRUE(relation.inPath);
  EXPECT_NEAR(relation.longitudinalDistance, 30.0, 1e-12);
  EXPECT_NEAR(relation.longitudinalGap, 25.0, 1e-12);  // 30 m minus two half lengths
  EXPECT_EQ(relation.relativeLane, 0);
  EXPECT_NEAR(relation.lateralGap, 0.2 - 1.8, 1e-12);
}

TEST(PathRelation, VehicleInTheNextLaneIsBesideThePathUntilItReachesIntoIt) {
  // Centred in the left lane: 3.5 m across, 1.7 m of clearance, not in the path.
  const auto beside = relateToPath(kStraightLane, kLaneWidth, kEgo, car(20.0, 3.5));
  EXPECT_FALSE(beside.inPath);
  EXPECT_EQ(beside.relativeLane, 1);
  EXPECT_NEAR(beside.lateralGap, 1.7, 1e-12);
  // Half-way through a cut-in it still belongs to the left lane but reaches into the path.
  const auto cutting_in = relateToPath(kStraightLane, kLaneWidth, kEgo, car(20.0, 1.6));
  EXPECT_EQ(cutting_in.relativeLane, 0);
  EXPECT_TRUE(cutting_in.inPath);
  const auto entering = relateToPath(kStraightLane, kLaneWidth, kEgo, car(20.0, 1.75));
  EXPECT_EQ(entering.relativeLane, 1);  // its centre is still in the left lane ...
  EXPECT_TRUE(entering.inPath);         // ... but its right side is inside the Ego's corridor
  const auto right = relateToPath(kStraightLane, kLaneWidth, kEgo, car(20.0, -3.5));
  EXPECT_EQ(right.relativeLane, -1);
  EXPECT_FALSE(right.inPath);
}

TEST(PathRelation, VehiclesBehindOrAlongsideAreNotInPath) {
  const auto behind = relateToPath(kStraightLane, kLaneWidth, kEgo, car(-20.0, 0.0));
  EXPECT_FALSE(behind.inPath);
  EXPECT_NEAR(behind.longitudinalDistance, -20.0, 1e-12);
  EXPECT_NEAR(behind.longitudinalGap, 15.0, 1e-12);
  const auto alongside = relateToPath(kStraightLane, kLaneWidth, kEgo, car(2.0, 3.5));
  EXPECT_LT(alongside.longitudinalGap, 0.0);  // s ranges overlap
  EXPECT_NEAR(alongside.lateralGap, 1.7, 1e-12);
}

TEST(PathRelation, ExtentsFollowTheObjectsHeadingRelativeToTheLane) {
  // A pedestrian crossing the lane (heading +y): 0.7 m along the lane, 0.5 m across it.
  const auto& kind = roadUserKind(RoadUserType::Pedestrian);
  const Footprint walker{{15.0, -2.0}, kPi / 2.0, kind.length, kind.width};
  const auto relation = relateToPath(kStraightLane, kLaneWidth, kEgo, walker);
  EXPECT_NEAR(relation.longitudinalGap, 15.0 - 2.5 - 0.5 * kind.width, 1e-12);
  EXPECT_NEAR(relation.lateralGap, 2.0 - 0.9 - 0.5 * kind.length, 1e-12);
  EXPECT_NEAR(relation.relativeHeading, kPi / 2.0, 1e-12);
  EXPECT_FALSE(relation.inPath);
  const Footprint on_the_lane{{15.0, -1.0}, kPi / 2.0, kind.length, kind.width};
  EXPECT_TRUE(relateToPath(kStraightLane, kLaneWidth, kEgo, on_the_lane).inPath);
}

TEST(PathRelation, DistancesAreMeasuredAlongACurvedLane) {
  // A quarter circle of radius 100 m, turning left; the Ego at its start, a car 50 m of arc on.
  Polyline arc;
  for (int i = 0; i <= 900; ++i) {
    const double angle = (kPi / 2.0) * i / 900.0;
    arc.emplace_back(100.0 * std::sin(angle), 100.0 - 100.0 * std::cos(angle));
  }
  const MeasuredPolyline lane(arc);
  const double angle = 50.0 / 100.0;
  const Footprint ahead{{100.0 * std::sin(angle), 100.0 - 100.0 * std::cos(angle)}, angle, 5.0, 1.8};
  const auto relation = relateToPath(lane, kLaneWidth, kEgo, ahead);
  EXPECT_NEAR(relation.longitudinalDistance, 50.0, 1e-2);  // arc, not chord (47.9 m)
  EXPECT_TRUE(relation.inPath);
  EXPECT_NEAR(relation.lateralDistance, 0.0, 1e-3);
}

TEST(PathRelation, PositionsBeyondTheLinesEndsAreMeasuredAlongTheEndSegments) {
  const MeasuredPolyline short_lane({{0.0, 0.0}, {10.0, 0.0}});
  const auto beyond = projectExtended(short_lane, {25.0, 1.0});
  EXPECT_NEAR(beyond.arcLength, 25.0, 1e-12);
  EXPECT_NEAR(beyond.lateralOffset, 1.0, 1e-12);
  const auto before = projectExtended(short_lane, {-5.0, -2.0});
  EXPECT_NEAR(before.arcLength, -5.0, 1e-12);
  EXPECT_NEAR(before.lateralOffset, -2.0, 1e-12);
  const auto inside = projectExtended(short_lane, {4.0, 3.0});
  EXPECT_NEAR(inside.arcLength, 4.0, 1e-12);
  EXPECT_NEAR(inside.lateralOffset, 3.0, 1e-12);
}

TEST(RoadUserKinds, EveryKindHasANameAPositiveSizeAndIsFoundByName) {
  for (const auto& kind : roadUserKinds()) {
    EXPECT_EQ(&roadUserKind(kind.type), &kind);
    EXPECT_GT(kind.length, 0.0);
    EXPECT_GT(kind.width, 0.0);
    EXPECT_EQ(findRoadUserType(kind.name), kind.type);
  }
  EXPECT_FALSE(findRoadUserType("tank").has_value());
  EXPECT_EQ(roadUserTypeList(), "car, van, truck, bus, motorbike, pedestrian, stationary_object, bicycle");
  // The paper's vehicles: every default of a car is the paper's 5.0 x 1.8 m.
  EXPECT_EQ(roadUserKind(RoadUserType::Car).length, 5.0);
  EXPECT_EQ(roadUserKind(RoadUserType::Car).width, 1.8);
}
