#include <algorithm>
#include <cmath>
#include <limits>

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

double egoMaxAbsLaneOffset(const MetricContext& context) {
  if (context.egoLaneCentre.size() < 2) return kNaN;
  const MeasuredPolyline centre(context.egoLaneCentre);
  return maxOverEgo(context, [&](const VehicleState& s) { return std::abs(centre.project(s.position()).lateralOffset); });
}

}  // namespace vsd::metrics::detail
