#include <gtest/gtest.h>

#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/metrics/metrics.hpp"

using namespace vsd;
using namespace vsd::metrics;

namespace {

/// Ego at constant speed along +x from x = 0; leader `gap0` m (bumper to bumper)
/// ahead at `leader_speed`; both 5 m long.
Trace following(double ego_speed, double leader_speed, double gap0, int instants = 26, double dt = 0.2) {
  Trace trace;
  trace.step = dt;
  VehicleTrack ego;
  ego.role = VehicleRole::Ego;
  VehicleTrack leader;
  for (int k = 0; k < instants; ++k) {
    const double t = k * dt;
    ego.states.push_back({ego_speed * t, 0.0, 0.0, ego_speed, 0.0});
    leader.states.push_back({gap0 + 5.0 + leader_speed * t, 0.0, 0.0, leader_speed, 0.0});
    ego.valid.push_back(1);
    leader.valid.push_back(1);
  }
  trace.vehicles = {ego, leader};
  return trace;
}

}  // namespace

TEST(Metrics, DistanceTimeToCollisionAndHeadwayOnAClosingPair) {
  // Ego 15 m/s closes on a 10 m/s leader 30 m ahead: after 5 s the gap is 5 m.
  const Trace trace = following(15.0, 10.0, 30.0);
  EXPECT_NEAR(dMin(trace), 5.0, 1e-9);
  EXPECT_NEAR(ttcMin(trace), 5.0 / 5.0, 1e-9);   // gap 5 m at 5 m/s closing speed
  EXPECT_NEAR(thwMin(trace), 5.0 / 15.0, 1e-9);  // gap / v_ego
}

TEST(Metrics, TimeToCollisionIsInfiniteWhenNeverClosingIn) {
  const Trace trace = following(10.0, 12.0, 20.0);
  EXPECT_TRUE(std::isinf(ttcMin(trace)));
  EXPECT_NEAR(dMin(trace), 20.0, 1e-9);
  EXPECT_NEAR(thwMin(trace), 2.0, 1e-9);
}

TEST(Metrics, VehiclesBehindTheEgoAreNotLeaders) {
  Trace trace = following(10.0, 10.0, 20.0);
  for (auto& state : trace.vehicles[1].states) state.x -= 50.0;  // centre now 25 m behind
  EXPECT_TRUE(std::isinf(thwMin(trace)));
  EXPECT_TRUE(std::isinf(ttcMin(trace)));
  EXPECT_NEAR(dMin(trace), 25.0 - 5.0, 1e-9);
}

TEST(Metrics, EgoOnlyMetrics) {
  VehicleTrack ego;
  const double speeds[] = {10.0, 9.0, 7.0, 7.5};
  const double ys[] = {0.0, 0.4, 1.2, -0.3};
  for (int k = 0; k < 4; ++k) {
    ego.states.push_back({2.0 * k, ys[k], 0.0, speeds[k], 0.0});
    ego.valid.push_back(1);
  }
  fillAccelerationFromSpeed(ego, 0.2);
  EXPECT_NEAR(aMin(ego), -10.0, 1e-9);  // (7 - 9) / 0.2
  EXPECT_NEAR(pLatMax(ego), 1.2, 1e-12);
  EXPECT_NEAR(laneOffsetMax(ego, {{-10.0, 0.0}, {10.0, 0.0}}), 1.2, 1e-12);
  EXPECT_NEAR(laneOffsetMax(ego, {{-10.0, 1.0}, {10.0, 1.0}}), 1.3, 1e-12);
}

TEST(Metrics, InvalidInstantsAreIgnored) {
  Trace trace = following(15.0, 10.0, 30.0);
  trace.vehicles[1].valid[25] = 0;  // the leader vanished at the last instant
  EXPECT_NEAR(dMin(trace), 30.0 - 5.0 * 4.8, 1e-9);
}

TEST(MetricSet, DefaultsDependOnOtherVehiclesAndNamesAreChecked) {
  EXPECT_EQ(MetricSet({}, false, "w").names(), (std::vector<std::string>{"a_min", "p_lat_max", "lane_offset_max"}));
  EXPECT_EQ(MetricSet({}, true, "w").names().size(), 6u);
  try {
    MetricSet({"a_min", "dmin"}, true, "acc.yaml: metrics");
    FAIL();
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("unknown metric 'dmin'"), std::string::npos);
  }
  EXPECT_THROW(MetricSet({"d_min"}, false, "lk.yaml: metrics"), ConfigError);
  const Trace trace = following(15.0, 10.0, 30.0);
  const auto values = MetricSet({"d_min", "ttc_min"}, true, "w").evaluate(trace, {});
  EXPECT_NEAR(values[0], 5.0, 1e-9);
  EXPECT_NEAR(values[1], 1.0, 1e-9);
}
