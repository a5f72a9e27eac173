#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "functions.hpp"

namespace vsd::metrics::detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

double gapBetween(const VehicleTrack& ego, const VehicleTrack& other, std::size_t k) {
  const double distance = (other.states[k].position() - ego.states[k].position()).norm();
  return distance - 0.5 * (ego.length + other.length);
}

/// Calls visit(k, other, gap, direction_to_other) for every instant both are valid.
template <typename Visitor>
void forEachPair(const Trace& trace, Visitor&& visit) {
  const VehicleTrack& ego = trace.ego();
  for (std::size_t v = 1; v < trace.vehicles.size(); ++v) {
    const VehicleTrack& other = trace.vehicles[v];
    for (std::size_t k = 0; k < ego.states.size() && k < other.states.size(); ++k) {
      if (!ego.validAt(k) || !other.validAt(k)) continue;
      visit(k, other, gapBetween(ego, other, k), Vec2(other.states[k].position() - ego.states[k].position()));
    }
  }
}
}  // namespace

namespace {

Footprint footprintAt(const VehicleTrack& track, std::size_t k) {
  return {track.states[k].position(), track.states[k].heading, track.length, track.width};
}

/// Half of a footprint's extent across a direction at `angle` (rad) to its heading.
double halfExtentAcross(const VehicleTrack& track, double angle) {
  return 0.5 * (std::abs(track.width * std::cos(angle)) + std::abs(track.length * std::sin(angle)));
}

}  // namespace

double minGap(const MetricContext& context) {
  // Oriented footprints: a car side by side in the next lane is ~1.7 m away, not a
  // collision (centre distance minus half lengths would say -2 m).
  // The exact gap costs six sines and cosines and a corner search per instant. The centre
  // distance less both half-diagonals is a lower bound of it (overlaps included) that costs
  // one square root: instants are visited nearest bound first, and the visit stops where
  // the bound cannot reach the gap found (1 nm of slack for rounding) - the same minimum
  // from a few exact gaps. A NaN position takes the plain visit of every instant.
  constexpr double kSlack = 1e-9;  // m
  const VehicleTrack& ego = context.trace.ego();
  struct Candidate {
    double bound;
    std::size_t k;
    const VehicleTrack* other;
  };
  std::vector<Candidate> candidates;
  bool all_finite = true;
  forEachPair(context.trace, [&](std::size_t k, const VehicleTrack& other, double, const Vec2& towards) {
    const double reach = 0.5 * (std::hypot(ego.length, ego.width) + std::hypot(other.length, other.width));
    const double bound = towards.norm() - reach;
    all_finite = all_finite && !std::isnan(bound);
    candidates.push_back({bound, k, &other});
  });
  if (all_finite) {
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.bound < b.bound; });
  }
  double result = kInf;
  for (const Candidate& candidate : candidates) {
    if (all_finite && candidate.bound - kSlack >= result) break;
    result = std::min(result, footprintGap(footprintAt(ego, candidate.k), footprintAt(*candidate.other, candidate.k)));
  }
  return std::isinf(result) ? kNaN : result;
}

double minLongitudinalGapInLane(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  double result = kInf;
  if (context.egoLaneCentre.size() >= 2 && context.laneBoundaries == nullptr) {
    // Along the Ego's lane (curves included): arc lengths and offsets on its centre line.
    const MeasuredPolyline lane(context.egoLaneCentre);
    forEachPair(context.trace, [&](std::size_t k, const VehicleTrack& other, double, const Vec2&) {
      const auto e = lane.project(ego.states[k].position());
      const auto o = lane.project(other.states[k].position());
      if (std::abs(o.lateralOffset - e.lateralOffset) >= 0.5 * (ego.width + other.width)) return;
      result = std::min(result, std::abs(o.arcLength - e.arcLength) - 0.5 * (ego.length + other.length));
    });
  } else {
    // Maps: in the Ego's frame at each instant (its lane's direction there).
    forEachPair(context.trace, [&](std::size_t k, const VehicleTrack& other, double, const Vec2& towards) {
      const Vec2 along = headingVector(ego.states[k].heading);
      const Vec2 across(-along.y(), along.x());
      const double angle = other.states[k].heading - ego.states[k].heading;
      if (std::abs(towards.dot(across)) >= 0.5 * ego.width + halfExtentAcross(other, angle)) return;
      result = std::min(result, std::abs(towards.dot(along)) - 0.5 * (ego.length + other.length));
    });
  }
  return std::isinf(result) ? kNaN : result;
}

double minTimeToCollision(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  bool any = false;
  double result = kInf;
  forEachPair(context.trace, [&](std::size_t k, const VehicleTrack& other, double gap, const Vec2& towards) {
    any = true;
    const auto& e = ego.states[k];
    const auto& o = other.states[k];
    const Vec2 ego_direction = headingVector(e.heading);
    if (towards.dot(ego_direction) <= 0.0) return;  // not ahead
    const double distance = towards.norm();
    if (distance <= 0.0) {
      result = 0.0;
      return;
    }
    const Vec2 normal = towards / distance;
    const double closing = (e.speed * ego_direction - o.speed * headingVector(o.heading)).dot(normal);
    if (closing > 1e-9) result = std::min(result, std::max(gap, 0.0) / closing);
  });
  return any ? result : kNaN;
}

double minTimeHeadway(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  bool any = false;
  double result = kInf;
  forEachPair(context.trace, [&](std::size_t k, const VehicleTrack&, double gap, const Vec2& towards) {
    any = true;
    const auto& e = ego.states[k];
    if (towards.dot(headingVector(e.heading)) <= 0.0 || e.speed <= 0.1) return;
    result = std::min(result, std::max(gap, 0.0) / e.speed);
  });
  return any ? result : kNaN;
}

}  // namespace vsd::metrics::detail
