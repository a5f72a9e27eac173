#include <algorithm>
#include <cmath>
#include <limits>

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

double minGap(const MetricContext& context) {
  double result = kInf;
  forEachPair(context.trace, [&](std::size_t, const VehicleTrack&, double gap, const Vec2&) { result = std::min(result, gap); });
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
