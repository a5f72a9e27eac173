#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "vsd/core/error.hpp"
#include "vsd/metrics/metrics.hpp"

using namespace vsd;
using namespace vsd::metrics;

namespace {

/// Ego at constant speed along +x from x = 0; leader `gap0` m (bumper to bumper)
/// ahead at `leader_speed`; lengths as given (default: both 5 m).
Trace following(double ego_speed, double leader_speed, double gap0, double ego_length = 5.0,
                double leader_length = 5.0) {
  const int instants = 26;
  const double dt = 0.2;
  Trace trace;
  trace.step = dt;
  VehicleTrack ego;
  ego.role = VehicleRole::Ego;
  ego.length = ego_length;
  ego.width = 1.8;
  VehicleTrack leader;
  leader.length = leader_length;
  leader.width = 2.5;
  for (int k = 0; k < instants; ++k) {
    const double t = k * dt;
    ego.states.push_back({ego_speed * t, 0.0, 0.0, ego_speed, 0.0});
    leader.states.push_back({gap0 + 0.5 * (ego_length + leader_length) + leader_speed * t, 0.0, 0.0, leader_speed, 0.0});
    ego.valid.push_back(1);
    leader.valid.push_back(1);
  }
  trace.vehicles = {ego, leader};
  return trace;
}

double value(const std::string& name, const Trace& trace, const Polyline& lane = {}) {
  return metric(name, "test").compute({trace, lane});
}

}  // namespace

TEST(Metrics, DistanceTimeToCollisionAndHeadwayOnAClosingPair) {
  // Ego 15 m/s closes on a 10 m/s leader 30 m ahead: after 5 s the gap is 5 m.
  const Trace trace = following(15.0, 10.0, 30.0);
  EXPECT_NEAR(value("d_min", trace), 5.0, 1e-9);
  EXPECT_NEAR(value("ttc_min", trace), 5.0 / 5.0, 1e-9);   // gap 5 m at 5 m/s closing speed
  EXPECT_NEAR(value("thw_min", trace), 5.0 / 15.0, 1e-9);  // gap / v_ego
}

TEST(Metrics, GapsUseEachVehiclesOwnLength) {
  // A 12 m truck ahead: the same bumper gaps as with a car, whatever the lengths.
  const Trace truck = following(15.0, 10.0, 30.0, /*ego_length=*/4.5, /*leader_length=*/12.0);
  EXPECT_NEAR(value("d_min", truck), 5.0, 1e-9);
  EXPECT_NEAR(value("ttc_min", truck), 1.0, 1e-9);
  // Assuming a 5 m leader for the truck would overstate the gap by 3.5 m.
  Trace wrong = truck;
  wrong.vehicles[1].length = 5.0;
  EXPECT_NEAR(value("d_min", wrong), 5.0 + 3.5, 1e-9);
}

TEST(Metrics, TimeToCollisionIsInfiniteWhenNeverClosingIn) {
  const Trace trace = following(10.0, 12.0, 20.0);
  EXPECT_TRUE(std::isinf(value("ttc_min", trace)));
  EXPECT_NEAR(value("d_min", trace), 20.0, 1e-9);
  EXPECT_NEAR(value("thw_min", trace), 2.0, 1e-9);
}

TEST(Metrics, VehiclesBehindTheEgoAreNotLeaders) {
  Trace trace = following(10.0, 10.0, 20.0);
  for (auto& state : trace.vehicles[1].states) state.x -= 50.0;  // centre now 25 m behind
  EXPECT_TRUE(std::isinf(value("thw_min", trace)));
  EXPECT_TRUE(std::isinf(value("ttc_min", trace)));
  EXPECT_NEAR(value("d_min", trace), 25.0 - 5.0, 1e-9);
}

TEST(Metrics, EgoAccelerationAndScenarioFramePosition) {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  const double speeds[] = {10.0, 9.0, 7.0, 7.5};
  const double ys[] = {0.0, 0.4, 1.2, -0.3};
  for (int k = 0; k < 4; ++k) {
    ego.states.push_back({2.0 * k, 100.0 + ys[k], 0.0, speeds[k], 0.0});
    ego.valid.push_back(1);
  }
  fillAccelerationFromSpeed(ego, 0.2);
  trace.vehicles = {ego};
  EXPECT_NEAR(value("a_min", trace), -10.0, 1e-9);  // (7 - 9) / 0.2
  EXPECT_NEAR(value("y_max", trace), 101.2, 1e-12);
}

TEST(Metrics, LateralMetricsAreRelativeToTheEgosLane) {
  // The lane runs 100 m up in the scenario frame; the Ego weaves around it.
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  const double offsets[] = {0.0, 0.4, -1.3, 0.2};
  for (int k = 0; k < 4; ++k) {
    ego.states.push_back({2.0 * k, 100.0 + offsets[k], 0.0, 10.0, 0.0});
    ego.valid.push_back(1);
  }
  trace.vehicles = {ego};
  const Polyline lane = {{-10.0, 100.0}, {20.0, 100.0}};
  EXPECT_NEAR(value("p_lat_max", trace, lane), 0.4, 1e-12);        // signed, left positive
  EXPECT_NEAR(value("lane_offset_max", trace, lane), 1.3, 1e-12);  // unsigned
  // Driving the lane the other way round flips the sign of the offsets.
  const Polyline reversed = {{20.0, 100.0}, {-10.0, 100.0}};
  EXPECT_NEAR(value("p_lat_max", trace, reversed), 1.3, 1e-12);
  // Without a lane they cannot be computed.
  EXPECT_TRUE(std::isnan(value("p_lat_max", trace)));
  EXPECT_TRUE(std::isnan(value("lane_offset_max", trace)));
}

// Gaps between vehicles are clearances between oriented footprints: a car side by side
// in the next lane is not a collision, one ahead in the lane keeps its bumper gap, and
// the bumper gap to vehicles in the Ego's lane is its own metric (d_lon_min).
TEST(Metrics, GapsComeFromOrientedFootprintsAndTheLaneGapIsItsOwnMetric) {
  Trace trace = following(15.0, 15.0, 20.0);  // leader 20 m ahead, same speed
  VehicleTrack beside = trace.vehicles[1];     // a car in the next lane, 1 m ahead of the Ego
  beside.width = 1.8;
  for (std::size_t k = 0; k < beside.states.size(); ++k) {
    beside.states[k].x = trace.vehicles[0].states[k].x + 1.0;
    beside.states[k].y = 3.5;
  }
  trace.vehicles.push_back(beside);
  EXPECT_NEAR(value("d_min", trace), 3.5 - 0.5 * (1.8 + 1.8), 1e-9);  // 1.7 m, no collision
  EXPECT_NEAR(value("d_lon_min", trace), 20.0, 1e-9);                 // the leader's bumper gap
  // The same car overlapping the Ego by 0.3 m sideways: the overlap depth.
  for (auto& state : trace.vehicles[2].states) state.y = 1.5;
  EXPECT_NEAR(value("d_min", trace), -0.3, 1e-9);
  EXPECT_NEAR(value("d_lon_min", trace), -4.0, 1e-9);  // now in the Ego's lane: 1 m - 5 m
}

TEST(Metrics, LaneGapFollowsACurvedLane) {
  // A lane curving left with radius 40 m; Ego at arc 0, leader at arc 30 m, both centred.
  const double radius = 40.0;
  Polyline lane;
  for (int i = -10; i <= 100; ++i) {
    const double angle = i * 0.01;
    lane.emplace_back(radius * std::sin(angle), radius * (1.0 - std::cos(angle)));
  }
  const auto at_arc = [&](double arc) {
    const double angle = arc / radius;
    return VehicleState{radius * std::sin(angle), radius * (1.0 - std::cos(angle)), angle, 10.0, 0.0};
  };
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.length = 5.0;
  ego.width = 1.8;
  VehicleTrack leader = ego;
  ego.states = {at_arc(0.0)};
  leader.states = {at_arc(30.0)};
  ego.valid = leader.valid = {1};
  trace.vehicles = {ego, leader};
  // 11 m to the side in the Ego's frame, but in its lane: 30 m along it minus 5 m.
  EXPECT_NEAR(value("d_lon_min", trace, lane), 25.0, 0.05);
}

// On maps the Ego's lane is the one it is in at each instant: midway between the
// nearest boundaries left and right that run along its heading.
TEST(Metrics, LaneOffsetOnMapsIsMeasuredInTheLaneTheEgoIsIn) {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.width = 1.8;
  const double ys[] = {0.0, 0.4, 1.6, 1.9, 3.4};  // drifts left, changes into the next lane
  for (int k = 0; k < 5; ++k) {
    ego.states.push_back({10.0 * k, ys[k], 0.0, 10.0, 0.0});
    ego.valid.push_back(1);
  }
  trace.vehicles = {ego};
  // Two lanes along +x (boundaries at -1.75, 1.75, 5.25) and a crossing road's boundaries.
  const std::vector<Polyline> boundaries = {{{-20, -1.75}, {80, -1.75}}, {{-20, 1.75}, {80, 1.75}},
                                            {{-20, 1.75}, {80, 1.75}},   {{-20, 5.25}, {80, 5.25}},
                                            {{18, -30}, {18, 30}},       {{22, -30}, {22, 30}}};
  const Polyline starting_lane = {{-20, 0.0}, {80, 0.0}};
  const MetricContext context{trace, starting_lane, &boundaries};
  // Largest: 1.6 m from lane 0's centre just before the boundary (then 1.6 from lane 1's).
  EXPECT_NEAR(metric("lane_offset_max", "test").compute(context), 1.6, 1e-9);
  // A source without the lane along the whole path measures per instant ...
  const Availability map{/*otherVehicles=*/false, /*egoLane=*/false, /*scenarioFrame=*/false};
  EXPECT_NEAR(MetricSet({"lane_offset_max"}, map, "w").evaluate(context)[0], 1.6, 1e-9);
  // ... one with it, against the starting lane (the lane change shows as 3.4 m).
  const Availability generated{/*otherVehicles=*/false, /*egoLane=*/true, /*scenarioFrame=*/true};
  EXPECT_NEAR(MetricSet({"lane_offset_max"}, generated, "w").evaluate(context)[0], 3.4, 1e-9);
  // Off every lane (beyond the boundaries' ends): not computable.
  for (auto& state : trace.vehicles[0].states) state.x += 500.0;
  EXPECT_TRUE(std::isnan(metric("lane_offset_max", "test").compute(context)));
}

TEST(Metrics, InvalidInstantsAreIgnored) {
  Trace trace = following(15.0, 10.0, 30.0);
  trace.vehicles[1].valid[25] = 0;  // the leader vanished at the last instant
  EXPECT_NEAR(value("d_min", trace), 30.0 - 5.0 * 4.8, 1e-9);
}

TEST(MetricRegistry, EveryEntryIsCompleteAndUnique) {
  std::set<std::string> names;
  for (const auto& definition : registry()) {
    EXPECT_TRUE(names.insert(definition.name).second) << definition.name << " registered twice";
    EXPECT_FALSE(definition.unit.empty()) << definition.name;
    EXPECT_FALSE(definition.definition.empty()) << definition.name;
    EXPECT_FALSE(definition.frame.empty()) << definition.name;
    EXPECT_TRUE(static_cast<bool>(definition.compute)) << definition.name;
  }
  EXPECT_EQ(metricNames().size(), registry().size());
  EXPECT_EQ(findMetric("no_such_metric"), nullptr);
  try {
    metric("dmin", "acc.yaml: metrics");
    FAIL();
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("unknown metric 'dmin' (known: a_min, d_min"), std::string::npos)
        << error.what();
  }
}

TEST(MetricSet, DefaultsFollowWhatTheSourceProvides) {
  const Availability ego_alone{/*otherVehicles=*/false, /*egoLane=*/true, /*scenarioFrame=*/true};
  const Availability generated{/*otherVehicles=*/true, /*egoLane=*/true, /*scenarioFrame=*/true};
  const Availability map{/*otherVehicles=*/true, /*egoLane=*/false, /*scenarioFrame=*/false};
  EXPECT_EQ(MetricSet({}, ego_alone, "w").names(),
            (std::vector<std::string>{"a_min", "p_lat_max", "y_max", "lane_offset_max", "decel_max", "jerk_max"}));
  EXPECT_EQ(MetricSet({}, generated, "w").names(), metricNames());
  EXPECT_EQ(MetricSet({}, map, "w").names(),
            (std::vector<std::string>{"a_min", "d_min", "d_lon_min", "ttc_min", "thw_min", "lane_offset_max", "pet_min",
                                      "drac_max", "decel_max", "jerk_max"}));
  EXPECT_THROW(MetricSet({"y_max"}, map, "--metrics"), ConfigError);
  EXPECT_THROW(MetricSet({"d_min"}, ego_alone, "lk.yaml: metrics"), ConfigError);
  EXPECT_THROW(MetricSet({"p_lat_max"}, map, "--metrics"), ConfigError);
  EXPECT_THROW(MetricSet({"a_min", "a_min"}, map, "--metrics"), ConfigError);
  const Trace trace = following(15.0, 10.0, 30.0);
  const auto values = MetricSet({"d_min", "ttc_min"}, generated, "w").evaluate({trace, {}});
  EXPECT_NEAR(values[0], 5.0, 1e-9);
  EXPECT_NEAR(values[1], 1.0, 1e-9);
}

TEST(MetricSet, CollisionRuleComesFromTheRegistry) {
  const Availability generated{true, true, true};
  const MetricSet with_gap({"a_min", "d_min"}, generated, "w");
  EXPECT_EQ(with_gap.collisionRule(), "d_min <= 0");
  EXPECT_TRUE(with_gap.collision({-3.0, -0.1}));
  EXPECT_TRUE(with_gap.collision({-3.0, 0.0}));
  EXPECT_FALSE(with_gap.collision({-3.0, 0.2}));
  const MetricSet without_gap({"a_min", "ttc_min"}, generated, "w");
  EXPECT_EQ(without_gap.collisionRule(), "");
  EXPECT_FALSE(without_gap.collision({-3.0, 0.0}));
}

namespace {

/// The Ego at 10 m/s along y = 0; another car 25 m ahead (centres) at 5 m/s that moves from
/// the next lane (y = 3.5) into the Ego's between t = 1 s and t = 3 s.
Trace cutIn() {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.role = VehicleRole::Ego;
  ego.length = 5.0;
  ego.width = 1.8;
  VehicleTrack other;
  other.length = 5.0;
  other.width = 1.8;
  for (int k = 0; k <= 25; ++k) {
    const double t = 0.2 * k;
    const double y = 3.5 * (1.0 - std::clamp((t - 1.0) / 2.0, 0.0, 1.0));
    ego.states.push_back({10.0 * t, 0.0, 0.0, 10.0, 0.0});
    other.states.push_back({25.0 + 5.0 * t, y, 0.0, 5.0, 0.0});
    ego.valid.push_back(1);
    other.valid.push_back(1);
  }
  trace.vehicles = {ego, other};
  return trace;
}

}  // namespace

// In path from the instant it reaches into the Ego's corridor (|y| < 1.8 m, from t = 2.0 s):
// the in-path TTC is the gap then over the closing speed, not the one of the whole run.
TEST(Metrics, InPathTimeToCollisionFollowsACutIn) {
  const Trace trace = cutIn();
  const Polyline lane = {{-50.0, 0.0}, {200.0, 0.0}};
  // First instant in path: t = 2.0 s (y = 1.75 m); gap 25 + 10 - 20 - 5 = 10 m at 5 m/s closing,
  // shrinking to 25 + 25 - 50 - 5 = -5 (collision) at t = 5 s: the minimum is 0.
  EXPECT_NEAR(value("ttc_inpath_min", trace, lane), 0.0, 1e-9);
  Trace early = trace;
  for (auto* track : {&early.vehicles[0], &early.vehicles[1]}) {
    track->states.resize(11);  // up to t = 2.0 s
    track->valid.resize(11);
  }
  EXPECT_NEAR(value("ttc_inpath_min", early, lane), 10.0 / 5.0, 1e-9);
  EXPECT_NEAR(value("thw_inpath_min", early, lane), 10.0 / 10.0, 1e-9);
  // Before it enters the path there is no in-path object at all.
  for (auto* track : {&early.vehicles[0], &early.vehicles[1]}) {
    track->states.resize(10);
    track->valid.resize(10);
  }
  EXPECT_TRUE(std::isinf(value("ttc_inpath_min", early, lane)));
}

TEST(Metrics, LateralClearanceCountsRoadUsersBesideTheEgo) {
  Trace trace = following(10.0, 10.0, 0.0);
  for (auto& state : trace.vehicles[1].states) {
    state.x -= 5.0;  // beside the Ego: centres level
    state.y = 2.5;
  }
  const Polyline lane = {{-50.0, 0.0}, {200.0, 0.0}};
  EXPECT_NEAR(value("lat_clearance_min", trace, lane), 2.5 - 0.9 - 1.25, 1e-9);  // leader 2.5 m wide
  EXPECT_TRUE(std::isinf(value("lat_clearance_min", following(10.0, 10.0, 20.0), lane)));  // never beside
}

TEST(Metrics, EgoDecelerationAndJerk) {
  Trace trace = following(10.0, 10.0, 20.0);
  auto& ego = trace.vehicles[0];
  for (std::size_t k = 0; k < ego.states.size(); ++k) ego.states[k].accel = k >= 10 ? -4.0 : 0.0;
  EXPECT_NEAR(value("decel_max", trace), 4.0, 1e-12);
  EXPECT_NEAR(value("jerk_max", trace), 4.0 / 0.2, 1e-9);
}

// d_min visits instants nearest first and stops where no footprint can come closer: on
// random traces (overlaps, crossings, several road users, vehicles turned every way) it is
// exactly the minimum of the footprint gaps over every instant and road user.
TEST(Metrics, MinimumGapIsTheSmallestFootprintGapOfAllInstants) {
  std::mt19937_64 random(20261126);
  std::uniform_real_distribution<double> place(-30.0, 30.0);
  std::uniform_real_distribution<double> turn(-3.2, 3.2);
  std::uniform_real_distribution<double> size(0.5, 12.0);
  for (int round = 0; round < 200; ++round) {
    Trace trace;
    trace.step = 0.2;
    const int users = 2 + round % 3;
    for (int v = 0; v < users; ++v) {
      VehicleTrack track;
      track.role = v == 0 ? VehicleRole::Ego : VehicleRole::Other;
      track.length = size(random);
      track.width = std::min(track.length, size(random) / 3.0);
      for (int k = 0; k < 26; ++k) {
        track.states.push_back({place(random), place(random) / 3.0, turn(random), 10.0, 0.0});
        track.valid.push_back(k % 7 == 3 && v == 1 ? 0 : 1);
      }
      trace.vehicles.push_back(track);
    }
    double expected = std::numeric_limits<double>::infinity();
    const VehicleTrack& ego = trace.vehicles[0];
    for (std::size_t v = 1; v < trace.vehicles.size(); ++v) {
      const VehicleTrack& other = trace.vehicles[v];
      for (std::size_t k = 0; k < ego.states.size(); ++k) {
        if (!ego.validAt(k) || !other.validAt(k)) continue;
        const auto& e = ego.states[k];
        const auto& o = other.states[k];
        expected = std::min(expected, footprintGap({e.position(), e.heading, ego.length, ego.width},
                                                   {o.position(), o.heading, other.length, other.width}));
      }
    }
    EXPECT_EQ(value("d_min", trace), expected) << "round " << round;
  }
}
