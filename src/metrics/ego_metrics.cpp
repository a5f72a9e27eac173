#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "functions.hpp"

namespace vsd::metrics::detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Maximum of `value(state)` over the Ego's valid instants; NaN if there is none.
template <typename Value>
double maxOverEgo(const MetricContext& context, Value&& value) {
  const VehicleTrack& ego = context.trace.ego();
  double result = -kInf;
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    if (ego.validAt(k)) result = std::max(result, value(ego.states[k]));
  }
  return std::isinf(result) ? kNaN : result;
}
}  // namespace

double egoMinAcceleration(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  double result = kInf;
  for (std::size_t k = 1; k < ego.states.size(); ++k) {
    if (ego.validAt(k) && ego.validAt(k - 1)) result = std::min(result, ego.states[k].accel);
  }
  return std::isinf(result) ? kNaN : result;
}

double egoMaxLateralOffsetFromLane(const MetricContext& context) {
  if (context.egoLaneCentre.size() < 2) return kNaN;
  const MeasuredPolyline centre(context.egoLaneCentre);
  return maxOverEgo(context, [&](const VehicleState& s) { return centre.project(s.position()).lateralOffset; });
}

double egoMaxScenarioY(const MetricContext& context) {
  return maxOverEgo(context, [](const VehicleState& s) { return s.y; });
}

namespace {

/// Lane boundaries run along the Ego's heading within this angle (rad): boundaries of
/// crossing lanes at junctions are not the Ego's.
constexpr double kAlongHeading = 30.0 * kPi / 180.0;
/// Wider than this (m), two boundaries do not enclose one lane (a gap between roads).
constexpr double kMaxLaneWidth = 8.0;

/// The Ego's offset (m) from the middle of the lane it is in: the line through its
/// centre across its heading meets the nearest boundary on its left and on its right
/// (among boundary segments running along its heading); the lane's centre is midway.
/// nullopt where it is not between two such boundaries.
std::optional<double> ownLaneOffset(const VehicleState& s, const std::vector<Polyline>& boundaries) {
  const Vec2 along = headingVector(s.heading);
  const Vec2 across(-along.y(), along.x());  // left
  double left = kInf;
  double right = -kInf;
  for (const auto& boundary : boundaries) {
    for (std::size_t i = 0; i + 1 < boundary.size(); ++i) {
      const Vec2 a = boundary[i] - s.position();
      const Vec2 b = boundary[i + 1] - s.position();
      const Vec2 direction = b - a;
      const double length = direction.norm();
      if (length <= 0.0 || std::abs(direction.dot(along)) < std::cos(kAlongHeading) * length) continue;
      // Where the segment crosses the line across the Ego (longitudinal coordinate 0).
      const double la = a.dot(along);
      const double lb = b.dot(along);
      if ((la > 0.0 && lb > 0.0) || (la < 0.0 && lb < 0.0)) continue;
      const double t = la == lb ? 0.0 : la / (la - lb);
      const double lateral = (a + t * direction).dot(across);
      if (lateral >= 0.0) left = std::min(left, lateral);
      else right = std::max(right, lateral);
    }
  }
  if (std::isinf(left) || std::isinf(right) || left - right > kMaxLaneWidth) return std::nullopt;
  return std::abs(0.5 * (left + right));
}

}  // namespace

double egoMaxAbsLaneOffset(const MetricContext& context) {
  if (context.laneBoundaries != nullptr) {
    // Maps: the lane the Ego is in at each instant (it may cross junctions and lanes end).
    double result = -kInf;
    const VehicleTrack& ego = context.trace.ego();
    for (std::size_t k = 0; k < ego.states.size(); ++k) {
      if (!ego.validAt(k)) continue;
      if (const auto offset = ownLaneOffset(ego.states[k], *context.laneBoundaries)) result = std::max(result, *offset);
    }
    return std::isinf(result) ? kNaN : result;
  }
  if (context.egoLaneCentre.size() < 2) return kNaN;
  const MeasuredPolyline centre(context.egoLaneCentre);
  return maxOverEgo(context, [&](const VehicleState& s) { return std::abs(centre.project(s.position()).lateralOffset); });
}

}  // namespace vsd::metrics::detail
