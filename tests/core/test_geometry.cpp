#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "vsd/core/geometry.hpp"
#include "vsd/core/trace.hpp"

using namespace vsd;

TEST(Geometry, WrapAngleStaysInHalfOpenInterval) {
  EXPECT_NEAR(wrapAngle(3.0 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(2.0 * kPi + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(wrapAngle(-0.25), -0.25, 1e-12);
}

TEST(Geometry, SumoAngleConversionRoundTripsAndMatchesConventions) {
  // SUMO: 0 deg = north (+y), 90 deg = east (+x), clockwise.
  EXPECT_NEAR(headingFromSumoAngle(90.0), 0.0, 1e-12);
  EXPECT_NEAR(headingFromSumoAngle(0.0), kPi / 2.0, 1e-12);
  EXPECT_NEAR(headingFromSumoAngle(180.0), -kPi / 2.0, 1e-12);
  for (double heading : {-3.0, -1.0, 0.0, 0.5, 2.9}) {
    EXPECT_NEAR(headingFromSumoAngle(sumoAngleFromHeading(heading)), heading, 1e-12);
    const double angle = sumoAngleFromHeading(heading);
    EXPECT_GE(angle, 0.0);
    EXPECT_LT(angle, 360.0);
  }
}

TEST(Geometry, ProjectionGivesArcLengthAndSignedOffset) {
  const MeasuredPolyline line({{0, 0}, {10, 0}, {10, 10}});
  EXPECT_DOUBLE_EQ(line.length(), 20.0);
  auto left = line.project({4, 1.5});
  EXPECT_NEAR(left.arcLength, 4.0, 1e-12);
  EXPECT_NEAR(left.lateralOffset, 1.5, 1e-12);  // left of travel direction is positive
  EXPECT_NEAR(left.heading, 0.0, 1e-12);
  auto right = line.project({11, 5});
  EXPECT_NEAR(right.arcLength, 15.0, 1e-12);
  EXPECT_NEAR(right.lateralOffset, -1.0, 1e-12);
  EXPECT_NEAR(right.heading, kPi / 2.0, 1e-12);
}

TEST(Geometry, PointAtExtendsEndSegmentsLinearly) {
  const MeasuredPolyline line({{0, 0}, {10, 0}, {10, 10}});
  EXPECT_TRUE(line.pointAt(5).isApprox(Vec2(5, 0)));
  EXPECT_TRUE(line.pointAt(12).isApprox(Vec2(10, 2)));
  EXPECT_TRUE(line.pointAt(25).isApprox(Vec2(10, 15)));
  EXPECT_TRUE(line.pointAt(-3).isApprox(Vec2(-3, 0)));
  EXPECT_NEAR(line.headingAt(12), kPi / 2.0, 1e-12);
}

TEST(Geometry, OffsetPolylineKeepsDistanceFromBothSegments) {
  // A 45 degree left turn: every offset segment runs parallel to its original at
  // exactly the offset, on the inner (left) and the outer (right) side alike.
  const Polyline line = {{0, 0}, {10, 0}, {20, 10}};
  for (double offset : {2.0, -1.5}) {
    const Polyline moved = offsetPolyline(line, offset);
    ASSERT_EQ(moved.size(), 3u);
    for (std::size_t seg = 0; seg + 1 < line.size(); ++seg) {
      for (const Vec2& p : {moved[seg], moved[seg + 1]}) {
        const Vec2 direction = (line[seg + 1] - line[seg]).normalized();
        const Vec2 relative = p - line[seg];
        EXPECT_NEAR(direction.x() * relative.y() - direction.y() * relative.x(), offset, 1e-9);
      }
    }
  }
  EXPECT_TRUE(offsetPolyline(line, 2.0)[0].isApprox(Vec2(0, 2)));
}

TEST(Geometry, ClipToXRangeInterpolatesBorders) {
  const Polyline line = {{-70, 0}, {-50, 2}, {0, 2}, {60, 8}};
  const Polyline clipped = clipToXRange(line, -55, 55);
  ASSERT_EQ(clipped.size(), 4u);
  EXPECT_TRUE(clipped.front().isApprox(Vec2(-55, 1.5)));
  EXPECT_TRUE(clipped.back().isApprox(Vec2(55, 7.5)));
  const auto at = pointAtX(line, -60);
  ASSERT_TRUE(at.has_value());
  EXPECT_NEAR(at->y(), 1.0, 1e-12);
  EXPECT_FALSE(pointAtX(line, 100).has_value());
}

// The footprint gap against a brute-force reference: for rectangles apart, the
// smallest distance between densely sampled boundary points; for overlapping ones,
// the smallest translation that separates them over 1440 directions
// (h_A(d) + h_B(-d), h = support function).
TEST(Geometry, FootprintGapMatchesABruteForceReference) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> position(-6.0, 6.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> size(0.5, 12.0);
  const auto boundary = [](const Footprint& f) {
    std::vector<Vec2> points;
    const Vec2 u = headingVector(f.heading);
    const Vec2 n = headingVector(f.heading + 0.5 * kPi);
    for (int i = 0; i <= 100; ++i) {
      const double s = -0.5 + i / 100.0;
      points.push_back(f.centre + s * f.length * u + 0.5 * f.width * n);
      points.push_back(f.centre + s * f.length * u - 0.5 * f.width * n);
      points.push_back(f.centre + 0.5 * f.length * u + s * f.width * n);
      points.push_back(f.centre - 0.5 * f.length * u + s * f.width * n);
    }
    return points;
  };
  int apart = 0;
  int overlapping = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Footprint a{Vec2(position(rng), position(rng)), angle(rng), size(rng), size(rng) / 3.0};
    const Footprint b{Vec2(position(rng), position(rng)), angle(rng), size(rng), size(rng) / 3.0};
    const double gap = footprintGap(a, b);
    const auto pa = boundary(a);
    const auto pb = boundary(b);
    double reference = std::numeric_limits<double>::infinity();
    for (int d = 0; d < 1440; ++d) {
      const Vec2 dir = headingVector(2.0 * kPi * d / 1440.0);
      double max_a = -std::numeric_limits<double>::infinity();
      double min_b = std::numeric_limits<double>::infinity();
      for (const auto& p : pa) max_a = std::max(max_a, p.dot(dir));
      for (const auto& p : pb) min_b = std::min(min_b, p.dot(dir));
      reference = std::min(reference, max_a - min_b);
    }
    if (reference > 0.0) {  // overlapping: the penetration depth
      ++overlapping;
      EXPECT_NEAR(gap, -reference, 0.03) << trial;  // 0.25° steps: up to 0.02 m on 12 m vehicles
    } else {
      ++apart;
      double distance = std::numeric_limits<double>::infinity();
      for (const auto& p : pa) {
        for (const auto& q : pb) distance = std::min(distance, (p - q).norm());
      }
      EXPECT_NEAR(gap, distance, 0.07) << trial;
    }
  }
  EXPECT_GT(apart, 50);
  EXPECT_GT(overlapping, 50);
  // Two cars side by side in neighbouring 3.5 m lanes: apart by the lane width minus the width.
  EXPECT_NEAR(footprintGap({Vec2(0, 0), 0.0, 5.0, 1.8}, {Vec2(1.0, 3.5), 0.0, 5.0, 1.8}), 1.7, 1e-12);
  // One behind the other in the same lane: the bumper gap.
  EXPECT_NEAR(footprintGap({Vec2(0, 0), 0.0, 5.0, 1.8}, {Vec2(12.0, 0.1), 0.0, 4.0, 1.8}), 7.5, 1e-12);
}

namespace {

/// project() as the plain scan over every segment it replaced (the reference).
PolylineProjection projectByScan(const Polyline& points, const Vec2& point) {
  std::vector<double> cumulative(points.size(), 0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    cumulative[i] = cumulative[i - 1] + (points[i] - points[i - 1]).norm();
  }
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::size_t best_segment = 0;
  std::size_t heading_segment = kNone;
  double best_fraction = 0.0;
  double best_distance_sq = std::numeric_limits<double>::infinity();
  for (std::size_t seg = 0; seg + 1 < points.size(); ++seg) {
    const Vec2 start = points[seg];
    const Vec2 delta = points[seg + 1] - start;
    const double length_sq = delta.squaredNorm();
    double fraction = 0.0;
    if (length_sq > 0.0) fraction = std::clamp((point - start).dot(delta) / length_sq, 0.0, 1.0);
    const double distance_sq = (point - (start + fraction * delta)).squaredNorm();
    if (distance_sq < best_distance_sq) {
      best_distance_sq = distance_sq;
      best_segment = seg;
      best_fraction = fraction;
      if (length_sq > 0.0) heading_segment = seg;
    }
  }
  PolylineProjection best;
  if (best_distance_sq == std::numeric_limits<double>::infinity()) return best;
  const Vec2 start = points[best_segment];
  const Vec2 delta = points[best_segment + 1] - start;
  best.segment = best_segment;
  best.foot = start + best_fraction * delta;
  best.arcLength = cumulative[best_segment] + best_fraction * std::sqrt(delta.squaredNorm());
  if (heading_segment != kNone) best.heading = headingOf(points[heading_segment + 1] - points[heading_segment]);
  const Vec2 relative = point - best.foot;
  const double cross = delta.x() * relative.y() - delta.y() * relative.x();
  best.lateralOffset = std::copysign(std::sqrt(best_distance_sq), cross);
  return best;
}

std::uint64_t bitsOf(double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

/// Every field of the projections, bit for bit ("" if equal).
std::string projectionDifference(const PolylineProjection& a, const PolylineProjection& b) {
  std::string difference;
  const auto field = [&](const char* name, double x, double y) {
    if (bitsOf(x) != bitsOf(y)) difference += fmt::format(" {} {} != {}", name, x, y);
  };
  field("arcLength", a.arcLength, b.arcLength);
  field("lateralOffset", a.lateralOffset, b.lateralOffset);
  field("heading", a.heading, b.heading);
  field("foot.x", a.foot.x(), b.foot.x());
  field("foot.y", a.foot.y(), b.foot.y());
  if (a.segment != b.segment) difference += fmt::format(" segment {} != {}", a.segment, b.segment);
  return difference;
}

}  // namespace

// project() skips blocks of segments by their bounding boxes; its answers must be those of
// the scan over every segment, bit for bit: on random walks, arcs far from the origin,
// grids with exact ties, lines that double back over themselves, repeated (zero-length)
// points, and at points beyond the ends, on vertices and far away.
TEST(Geometry, ProjectionEqualsTheScanOverEverySegment) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> small(-3, 3);
  const auto polyline_of_kind = [&](int kind, std::size_t n) {
    Polyline points;
    Vec2 p(unit(rng) * 100.0, unit(rng) * 100.0);
    double heading = unit(rng) * 2.0 * kPi;
    const double curvature = (unit(rng) - 0.5) * 0.05;
    const Vec2 origin(1e5 * unit(rng), -4e6 * unit(rng));
    for (std::size_t i = 0; i < n; ++i) {
      switch (kind) {
        case 0:  // scattered around the origin at 1 cm to 100 m, some points repeated: where
                 // a + (b - a) != b, such a zero-length segment can be the nearest
          if (i == 0 || unit(rng) > 0.2) {
            p = Vec2(unit(rng) - 0.5, unit(rng) - 0.5) * std::pow(10.0, 4.0 * unit(rng) - 2.0);
          }
          points.push_back(p);
          break;
        case 1:  // an arc sampled every 10 m in SUMO-like net coordinates
          points.push_back(origin + Vec2(std::cos(heading), std::sin(heading)) * (static_cast<double>(i) * 10.0));
          heading += curvature;
          break;
        case 2:  // small integers: many exact ties
          points.emplace_back(small(rng), small(rng));
          break;
        default: {  // back and forth along one line, every point twice: ties between distant segments
          const std::size_t k = (i / 2) % 6;
          points.emplace_back(static_cast<double>(k <= 3 ? k : 6 - k), 0.0);
          break;
        }
      }
    }
    return points;
  };
  int compared = 0;
  int zero_length_nearest = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int kind = trial % 4;
    const std::size_t n = 2 + static_cast<std::size_t>(unit(rng) * (trial < 40 ? 20 : 180));
    const Polyline points = polyline_of_kind(kind, n);
    const MeasuredPolyline line(points);
    std::vector<Vec2> queries;
    for (int q = 0; q < 40; ++q) {
      const auto pick = static_cast<std::size_t>(unit(rng) * static_cast<double>(points.size()));
      const Vec2& vertex = points[pick % points.size()];
      const Vec2 spread(unit(rng) - 0.5, unit(rng) - 0.5);
      switch (q % 5) {
        case 0: queries.push_back(vertex); break;                                       // on a vertex
        case 1: queries.push_back(vertex + spread * 8.0); break;                        // near the line
        case 2: queries.push_back(points.front() + (points.front() - points.back()) * unit(rng)); break;  // beyond
        case 3: queries.push_back(vertex + spread * 1e4); break;                        // far away
        default: queries.emplace_back(small(rng) * 0.5, small(rng) * 0.5); break;  // half-grid: ties on grids
      }
    }
    queries.push_back(points.back() + (points.back() - points.front()));  // beyond the end
    for (const Vec2& query : queries) {
      const PolylineProjection reference = projectByScan(points, query);
      const std::string difference = projectionDifference(line.project(query), reference);
      if (reference.segment > 0 && points[reference.segment] == points[reference.segment + 1]) ++zero_length_nearest;
      ASSERT_EQ(difference, "") << "kind " << kind << ", " << n << " points, query (" << query.x() << ", " << query.y()
                                << ")";
      ++compared;
    }
  }
  EXPECT_EQ(compared, 400 * 41);
  EXPECT_GT(zero_length_nearest, 0);
}

TEST(Trace, AccelerationFromSpeedDifferences) {
  VehicleTrack track;
  for (double v : {10.0, 9.0, 9.0, 9.5}) track.states.push_back({0, 0, 0, v, 99.0});
  fillAccelerationFromSpeed(track, 0.2);
  EXPECT_NEAR(track.states[1].accel, -5.0, 1e-12);
  EXPECT_NEAR(track.states[2].accel, 0.0, 1e-12);
  EXPECT_NEAR(track.states[3].accel, 2.5, 1e-12);
  EXPECT_NEAR(track.states[0].accel, track.states[1].accel, 1e-12);
}

TEST(Trace, TrackFromPositionsRecoversASuddenBrakeAtTheStart) {
  // The simulator's trapezoidal integration along a straight heading of 0.3 rad:
  // 10 m/s, braking at -5 m/s^2 from t = 0 for 1 s, then constant speed.
  const double dt = 0.2;
  const double heading = 0.3;
  const Vec2 direction(std::cos(heading), std::sin(heading));
  std::vector<double> speed = {10.0};
  Polyline positions = {Vec2(3.0, -2.0)};
  for (int k = 1; k <= 25; ++k) {
    speed.push_back(speed.back() + (k <= 5 ? -5.0 * dt : 0.0));
    positions.push_back(positions.back() + 0.5 * (speed[k - 1] + speed[k]) * dt * direction);
  }
  const auto track = trackFromPositions(positions, dt, 10.0, heading);
  ASSERT_EQ(track.states.size(), 26u);
  // The first step's acceleration is exact: no smoothing window blurs the jump at t = 0.
  EXPECT_NEAR(track.states[1].accel, -5.0, 1e-9);
  double a_min = 0.0;
  for (std::size_t k = 1; k < track.states.size(); ++k) a_min = std::min(a_min, track.states[k].accel);
  EXPECT_NEAR(a_min, -5.0, 1e-9);
  // Where the acceleration is constant, speeds at instants are exact; at the end of the
  // braking the midpoint difference averages the two steps around it.
  EXPECT_NEAR(track.states[3].speed, speed[3], 1e-9);
  EXPECT_NEAR(track.states[20].speed, 5.0, 1e-9);
  EXPECT_NEAR(track.states[6].accel, -2.5, 1e-9);
  EXPECT_NEAR(track.states[25].accel, 0.0, 1e-9);
  for (const auto& state : track.states) EXPECT_NEAR(state.heading, heading, 1e-9);
  EXPECT_EQ(track.states[7].x, positions[7].x());
}

TEST(Trace, TrackFromPositionsKeepsHeadingAtStandstillAndHandlesShortInput) {
  const Polyline still(6, Vec2(1.0, 1.0));
  const auto track = trackFromPositions(still, 0.2, 0.0, 1.2);
  for (const auto& state : track.states) {
    EXPECT_NEAR(state.heading, 1.2, 1e-12);
    EXPECT_EQ(state.speed, 0.0);
  }
  EXPECT_TRUE(trackFromPositions({}, 0.2, 1.0, 0.0).states.empty());
  const auto single = trackFromPositions({Vec2(0, 0)}, 0.2, 4.0, 0.5);
  ASSERT_EQ(single.states.size(), 1u);
  EXPECT_EQ(single.states[0].speed, 4.0);
}
