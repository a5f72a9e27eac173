// PET, DRAC and the lane-relative TTC / headway / gap (SSM's conventions) on
// constructed traces whose values follow by hand.

#include <gtest/gtest.h>

#include <cmath>

#include "vsd/metrics/metrics.hpp"

using namespace vsd;
using namespace vsd::metrics;

namespace {

constexpr double kStep = 0.2;

VehicleTrack track(double length, double width, std::size_t instants) {
  VehicleTrack result;
  result.length = length;
  result.width = width;
  result.states.resize(instants);
  result.valid.assign(instants, 1);
  return result;
}

/// A vehicle moving at constant speed from `start` along `heading`.
VehicleTrack straight(const Vec2& start, double heading, double speed, std::size_t instants) {
  VehicleTrack result = track(5.0, 1.8, instants);
  for (std::size_t k = 0; k < instants; ++k) {
    const Vec2 p = start + speed * kStep * static_cast<double>(k) * headingVector(heading);
    result.states[k] = {p.x(), p.y(), heading, speed, 0.0};
  }
  return result;
}

double evaluate(const std::string& name, const Trace& trace, const Polyline& lane) {
  const MetricSet set({name}, {true, true, true}, "test");
  return set.evaluate({trace, lane})[0];
}

}  // namespace

TEST(CriticalityMetrics, FollowingOnAStraightLane) {
  Trace trace;
  trace.step = kStep;
  trace.vehicles = {straight({0.0, 0.0}, 0.0, 10.0, 1), straight({20.0, 0.0}, 0.0, 6.0, 1)};
  const Polyline lane = {{-50.0, 0.0}, {200.0, 0.0}};
  // Bumpers 15 m apart, closing at 4 m/s.
  EXPECT_NEAR(evaluate("gap_min_lane", trace, lane), 15.0, 1e-12);
  EXPECT_NEAR(evaluate("ttc_min_lane", trace, lane), 15.0 / 4.0, 1e-12);
  EXPECT_NEAR(evaluate("thw_min_lane", trace, lane), 1.5, 1e-12);
  EXPECT_NEAR(evaluate("drac_max_lane", trace, lane), 16.0 / 30.0, 1e-12);
  EXPECT_NEAR(evaluate("drac_max", trace, lane), 16.0 / 30.0, 1e-12);
  EXPECT_TRUE(std::isinf(evaluate("pet_min", trace, lane)));  // following: no crossing

  // A vehicle on the neighbouring lane (3.5 m to the left) is nobody's leader on the Ego's lane.
  trace.vehicles[1] = straight({20.0, 3.5}, 0.0, 6.0, 1);
  EXPECT_TRUE(std::isinf(evaluate("gap_min_lane", trace, lane)));
  EXPECT_TRUE(std::isinf(evaluate("ttc_min_lane", trace, lane)));
  EXPECT_EQ(evaluate("drac_max_lane", trace, lane), 0.0);

  // A faster leader: never closing.
  trace.vehicles[1] = straight({20.0, 0.0}, 0.0, 12.0, 1);
  EXPECT_TRUE(std::isinf(evaluate("ttc_min_lane", trace, lane)));
  EXPECT_EQ(evaluate("drac_max", trace, lane), 0.0);
}

TEST(CriticalityMetrics, AnOncomingVehicleOnTheEgosLaneClosesInWithBothSpeeds) {
  Trace trace;
  trace.step = kStep;
  // Centres 30 m apart, the other heading back along the lane at 6 m/s: its front (at 27.5 m)
  // faces the Ego's (at 2.5 m), 25 m apart, closing at 16 m/s.
  trace.vehicles = {straight({0.0, 0.0}, 0.0, 10.0, 1), straight({30.0, 0.0}, kPi, 6.0, 1)};
  const Polyline lane = {{-50.0, 0.0}, {200.0, 0.0}};
  EXPECT_NEAR(evaluate("gap_min_lane", trace, lane), 25.0, 1e-12);
  EXPECT_NEAR(evaluate("ttc_min_lane", trace, lane), 25.0 / 16.0, 1e-12);
  EXPECT_NEAR(evaluate("thw_min_lane", trace, lane), 2.5, 1e-12);
  EXPECT_NEAR(evaluate("drac_max_lane", trace, lane), 256.0 / 50.0, 1e-12);
  // Standing, it is an obstacle as one facing along the lane would be.
  trace.vehicles[1] = straight({30.0, 0.0}, kPi, 0.0, 1);
  EXPECT_NEAR(evaluate("ttc_min_lane", trace, lane), 2.5, 1e-12);
}

TEST(CriticalityMetrics, LaneGapFollowsTheArcWhereTheStraightGapTakesTheChord) {
  // Both on a circle of radius 50 m, fronts 20 m of arc apart.
  const double radius = 50.0;
  Polyline lane;
  for (int i = 0; i <= 720; ++i) {
    const double angle = -kPi / 2.0 + kPi * i / 720.0;
    lane.emplace_back(radius * std::cos(angle), radius * std::sin(angle) + radius);
  }
  auto on_circle = [&](double arc, double speed) {
    // The centre 2.5 m of arc behind the front; heading along the tangent at the centre.
    const double angle = -kPi / 2.0 + (arc - 2.5) / radius;
    VehicleTrack vehicle = track(5.0, 1.8, 1);
    const Vec2 centre(radius * std::cos(angle), radius * std::sin(angle) + radius);
    vehicle.states[0] = {centre.x(), centre.y(), angle + kPi / 2.0, speed, 0.0};
    return vehicle;
  };
  Trace trace;
  trace.step = kStep;
  trace.vehicles = {on_circle(10.0, 10.0), on_circle(30.0, 5.0)};
  // Front points sit slightly off the arc (the bumper is on the tangent), so allow a few mm.
  EXPECT_NEAR(evaluate("gap_min_lane", trace, lane), 15.0, 0.01);
  EXPECT_NEAR(evaluate("ttc_min_lane", trace, lane), 3.0, 0.01);
  EXPECT_LT(evaluate("d_min", trace, lane), evaluate("gap_min_lane", trace, lane) - 0.05);  // the chord is shorter
}

TEST(CriticalityMetrics, PostEncroachmentTimeOfAPerpendicularCrossing) {
  // Ego along +x through the origin at t = 2 s, the other along +y through it at t = 3 s,
  // both 10 m/s, 5 m long, 1.8 m wide: the Ego's rear leaves the other's strip
  // (0.9 m + 2.5 m past the crossing) at 2.34 s, the other's front enters the Ego's
  // strip (0.9 m before) at 3 - 0.34 = 2.66 s.
  constexpr std::size_t kInstants = 31;
  Trace trace;
  trace.step = kStep;
  trace.vehicles = {straight({-20.0, 0.0}, 0.0, 10.0, kInstants), straight({0.0, -30.0}, kPi / 2.0, 10.0, kInstants)};
  const Polyline no_lane;
  const MetricSet pet({"pet_min"}, {true, false, false}, "test");
  EXPECT_NEAR(pet.evaluate({trace, no_lane})[0], 0.32, 1e-9);

  // Both inside the conflict area at once: 0.
  trace.vehicles[1] = straight({0.0, -22.0}, kPi / 2.0, 10.0, kInstants);
  EXPECT_EQ(pet.evaluate({trace, no_lane})[0], 0.0);

  // The other never reaches the crossing within the recording: no PET.
  trace.vehicles[1] = straight({0.0, -300.0}, kPi / 2.0, 10.0, kInstants);
  EXPECT_TRUE(std::isinf(pet.evaluate({trace, no_lane})[0]));
}
