#include <gtest/gtest.h>

#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/sim/object_list.hpp"

using namespace vsd;
using namespace vsd::sim;

namespace {

// A straight lane along +x, 3.5 m wide, and a car-sized Ego on its centre line at x = 0.
const MeasuredPolyline kLane({{-200.0, 0.0}, {0.0, 0.0}, {200.0, 0.0}});
constexpr double kLaneWidth = 3.5;
const Footprint kEgo{{0.0, 0.0}, 0.0, 5.0, 1.8};

RoadUserState car(int id, double x, double y, double heading = 0.0, double speed = 10.0) {
  return {id, RoadUserType::Car, {x, y, heading, speed, -1.0}, 5.0, 1.8};
}

std::vector<int> seen(const std::vector<RoadUserState>& others, const ObjectSensor& sensor = {}) {
  std::vector<int> ids;
  for (const auto& object : observeObjects(kLane, kLaneWidth, kEgo, others, sensor)) ids.push_back(object.id);
  return ids;
}

}  // namespace

// The defaults are UN R157's detection ranges: 46 m ahead of the front bumper (7.1.1), the
// full width of the neighbouring lanes (7.1.2), nothing required behind.
TEST(ObjectList, DefaultCoverageIsTheRegulationsDetectionRange) {
  // Bumper gaps 45 m and 47 m ahead in the Ego's lane: only the first is seen.
  EXPECT_EQ(seen({car(1, 50.0, 0.0), car(2, 52.0, 0.0)}), (std::vector<int>{1}));
  // Behind (gap 1 m) is not covered; alongside in either neighbouring lane is.
  EXPECT_EQ(seen({car(1, -6.0, 0.0), car(2, 1.0, 3.5), car(3, -2.0, -3.5)}), (std::vector<int>{2, 3}));
  // A car hugging the far edge of the next lane is covered, one two lanes over is not.
  EXPECT_EQ(seen({car(1, 20.0, 4.35), car(2, 20.0, 7.0)}), (std::vector<int>{1}));
}

TEST(ObjectList, ScenarioSetsRangesAndFieldOfView) {
  ObjectSensor sensor;
  sensor.forwardRange = 100.0;
  sensor.rearRange = 30.0;
  sensor.lateralRange = 10.0;
  EXPECT_EQ(seen({car(1, 100.0, 0.0), car(2, -30.0, 0.0), car(3, 20.0, 7.0)}, sensor), (std::vector<int>{1, 2, 3}));
  // A 60 degree forward sensor: a car 20 m ahead in the next lane (10 degrees off) is seen,
  // one beside the Ego (90 degrees) is not.
  sensor.fieldOfView = kPi / 3.0;
  EXPECT_EQ(seen({car(1, 20.0, 3.5), car(2, 1.0, 3.5)}, sensor), (std::vector<int>{1}));
}

TEST(ObjectList, EntriesCarryStateSizeAndTheSharedPathRelation) {
  const auto others = std::vector<RoadUserState>{car(4, 30.0, 1.75, 0.3, 12.0)};
  const auto objects = observeObjects(kLane, kLaneWidth, kEgo, others, {});
  ASSERT_EQ(objects.size(), 1u);
  const auto& object = objects[0];
  EXPECT_EQ(object.id, 4);
  EXPECT_EQ(object.type, RoadUserType::Car);
  EXPECT_EQ(object.state.accel, -1.0);
  const auto expected = relateToPath(kLane, kLaneWidth, kEgo, {{30.0, 1.75}, 0.3, 5.0, 1.8});
  EXPECT_EQ(object.relation.lateralGap, expected.lateralGap);
  EXPECT_EQ(object.relation.longitudinalGap, expected.longitudinalGap);
  EXPECT_TRUE(object.relation.inPath);  // its right side reaches into the Ego's corridor
  EXPECT_EQ(object.relation.relativeLane, 1);  // though its centre is still in the left lane
  EXPECT_NEAR(object.longitudinalSpeed(), 12.0 * std::cos(0.3), 1e-12);
  EXPECT_NEAR(object.lateralSpeed(), 12.0 * std::sin(0.3), 1e-12);
}

// A cut-in is in the Ego's path as soon as it reaches into the corridor the Ego sweeps -
// before SUMO would move it to the Ego's lane (its centre crossing the lane marking).
TEST(ObjectList, NearestInPathFindsACutInAsItEntersThePath) {
  const std::vector<RoadUserState> before{car(1, 40.0, 0.0), car(2, 20.0, 1.85)};
  const auto far_objects = observeObjects(kLane, kLaneWidth, kEgo, before, {});
  ASSERT_NE(nearestInPath(far_objects), nullptr);
  EXPECT_EQ(nearestInPath(far_objects)->id, 1);  // the cut-in's side is still 5 cm outside the path
  const std::vector<RoadUserState> entering{car(1, 40.0, 0.0), car(2, 20.0, 1.78)};
  const auto objects = observeObjects(kLane, kLaneWidth, kEgo, entering, {});
  ASSERT_NE(nearestInPath(objects), nullptr);
  EXPECT_EQ(nearestInPath(objects)->id, 2);
  EXPECT_EQ(nearestInPath(objects)->relation.relativeLane, 1);  // its centre is still in the left lane
  EXPECT_EQ(nearestInPath(observeObjects(kLane, kLaneWidth, kEgo, {car(3, 20.0, 3.5)}, {})), nullptr);
}

TEST(ObjectList, SensorValuesOutOfRangeAreNamed) {
  auto message = [](const ObjectSensor& sensor) {
    try {
      sensor.validate("cut_in.yaml:14: ego.sensor");
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  ObjectSensor sensor;
  EXPECT_EQ(message(sensor), "");
  sensor.forwardRange = -1.0;
  EXPECT_EQ(message(sensor), "cut_in.yaml:14: ego.sensor.forward_range: got -1, expected a distance >= 0 m");
  sensor = {};
  sensor.fieldOfView = 7.0;
  EXPECT_NE(message(sensor).find("ego.sensor.field_of_view: got 7, expected an angle in (0, 2 pi] rad"),
            std::string::npos);
  sensor = {};
  sensor.lateralRange = std::nan("");
  EXPECT_NE(message(sensor).find("ego.sensor.lateral_range: got nan"), std::string::npos);
}
