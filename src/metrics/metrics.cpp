#include "vsd/metrics/metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "vsd/core/error.hpp"

namespace vsd::metrics {

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

const std::vector<MetricInfo>& allMetrics() {
  static const std::vector<MetricInfo> kMetrics = {
      {"a_min", "m/s^2", "Ego's minimum longitudinal acceleration", false, false},
      {"d_min", "m", "minimum bumper gap between the Ego and any other vehicle", true, false},
      {"p_lat_max", "m", "Ego's maximum lateral position y in the scenario frame", false, false},
      {"ttc_min", "s", "minimum time to collision with a vehicle ahead", true, false},
      {"thw_min", "s", "minimum time headway to a vehicle ahead", true, false},
      {"lane_offset_max", "m", "Ego's maximum distance from its lane's centre line", false, true},
  };
  return kMetrics;
}

std::optional<MetricInfo> findMetric(const std::string& name) {
  for (const auto& info : allMetrics()) {
    if (info.name == name) return info;
  }
  return std::nullopt;
}

double aMin(const VehicleTrack& ego) {
  double result = kInf;
  for (std::size_t k = 1; k < ego.states.size(); ++k) {
    if (ego.validAt(k) && ego.validAt(k - 1)) result = std::min(result, ego.states[k].accel);
  }
  return std::isinf(result) ? kNaN : result;
}

double dMin(const Trace& trace) {
  double result = kInf;
  forEachPair(trace, [&](std::size_t, const VehicleTrack&, double gap, const Vec2&) { result = std::min(result, gap); });
  return std::isinf(result) ? kNaN : result;
}

double pLatMax(const VehicleTrack& ego) {
  double result = -kInf;
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    if (ego.validAt(k)) result = std::max(result, ego.states[k].y);
  }
  return std::isinf(result) ? kNaN : result;
}

double ttcMin(const Trace& trace) {
  const VehicleTrack& ego = trace.ego();
  bool any = false;
  double result = kInf;
  forEachPair(trace, [&](std::size_t k, const VehicleTrack& other, double gap, const Vec2& towards) {
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

double thwMin(const Trace& trace) {
  const VehicleTrack& ego = trace.ego();
  bool any = false;
  double result = kInf;
  forEachPair(trace, [&](std::size_t k, const VehicleTrack&, double gap, const Vec2& towards) {
    any = true;
    const auto& e = ego.states[k];
    if (towards.dot(headingVector(e.heading)) <= 0.0 || e.speed <= 0.1) return;
    result = std::min(result, std::max(gap, 0.0) / e.speed);
  });
  return any ? result : kNaN;
}

double laneOffsetMax(const VehicleTrack& ego, const Polyline& lane_centre) {
  if (lane_centre.size() < 2) return kNaN;
  const MeasuredPolyline centre(lane_centre);
  double result = -kInf;
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    if (!ego.validAt(k)) continue;
    result = std::max(result, std::abs(centre.project(ego.states[k].position()).lateralOffset));
  }
  return std::isinf(result) ? kNaN : result;
}

MetricSet::MetricSet(const std::vector<std::string>& names, bool has_other_vehicles, const std::string& where) {
  if (names.empty()) {
    for (const auto& info : allMetrics()) {
      if (!info.needsOtherVehicle || has_other_vehicles) names_.push_back(info.name);
    }
    return;
  }
  for (const auto& name : names) {
    const auto info = findMetric(name);
    if (!info) {
      std::vector<std::string> known;
      for (const auto& metric : allMetrics()) known.push_back(metric.name);
      throw ConfigError(fmt::format("{}: unknown metric '{}' (known: {})", where, name, fmt::join(known, ", ")));
    }
    if (info->needsOtherVehicle && !has_other_vehicles) {
      throw ConfigError(fmt::format("{}: metric '{}' needs another vehicle, but the scenario has only the Ego", where,
                                    name));
    }
    if (std::find(names_.begin(), names_.end(), name) != names_.end()) {
      throw ConfigError(fmt::format("{}: metric '{}' is listed twice", where, name));
    }
    names_.push_back(name);
  }
}

std::vector<double> MetricSet::evaluate(const Trace& trace, const Polyline& ego_lane_centre) const {
  std::vector<double> values;
  values.reserve(names_.size());
  const VehicleTrack& ego = trace.ego();
  for (const auto& name : names_) {
    if (name == "a_min") values.push_back(aMin(ego));
    else if (name == "d_min") values.push_back(dMin(trace));
    else if (name == "p_lat_max") values.push_back(pLatMax(ego));
    else if (name == "ttc_min") values.push_back(ttcMin(trace));
    else if (name == "thw_min") values.push_back(thwMin(trace));
    else if (name == "lane_offset_max") values.push_back(laneOffsetMax(ego, ego_lane_centre));
  }
  return values;
}

}  // namespace vsd::metrics
