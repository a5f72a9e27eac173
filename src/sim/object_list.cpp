#include "vsd/sim/object_list.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"

namespace vsd::sim {

double ObservedObject::longitudinalSpeed() const { return state.speed * std::cos(relation.relativeHeading); }

double ObservedObject::lateralSpeed() const { return state.speed * std::sin(relation.relativeHeading); }

void ObjectSensor::validate(const std::string& where) const {
  auto check = [&](const char* field, double value, bool ok, const char* expected) {
    if (!ok) throw ConfigError(fmt::format("{}.{}: got {}, expected {}", where, field, value, expected));
  };
  check("forward_range", forwardRange, std::isfinite(forwardRange) && forwardRange >= 0.0, "a distance >= 0 m");
  check("rear_range", rearRange, std::isfinite(rearRange) && rearRange >= 0.0, "a distance >= 0 m");
  if (lateralRange) {
    check("lateral_range", *lateralRange, std::isfinite(*lateralRange) && *lateralRange >= 0.0, "a distance >= 0 m");
  }
  check("field_of_view", fieldOfView, fieldOfView > 0.0 && fieldOfView <= 2.0 * kPi,
        "an angle in (0, 2 pi] rad");
}

namespace {

bool covered(const ObjectSensor& sensor, double lateral_range, const Footprint& ego, const RoadUserState& other,
             const PathRelation& relation) {
  const double range = relation.longitudinalDistance > 0.0 ? sensor.forwardRange : sensor.rearRange;
  if (relation.longitudinalGap > range) return false;
  if (relation.lateralGap > lateral_range) return false;
  if (sensor.fieldOfView >= 2.0 * kPi) return true;
  const Vec2 towards = other.state.position() - ego.centre;
  return std::abs(wrapAngle(headingOf(towards) - ego.heading)) <= 0.5 * sensor.fieldOfView;
}

}  // namespace

std::vector<ObservedObject> observeObjects(const MeasuredPolyline& reference_line, double lane_width,
                                           const Footprint& ego, const std::vector<RoadUserState>& others,
                                           const ObjectSensor& sensor) {
  const double lateral_range = sensor.lateralRange.value_or(1.5 * lane_width - 0.5 * ego.width);
  std::vector<ObservedObject> objects;
  objects.reserve(others.size());
  if (others.empty()) return objects;
  const PolylineProjection ego_foot = projectExtended(reference_line, ego.centre);
  for (const auto& other : others) {
    const Footprint footprint{other.state.position(), other.state.heading, other.length, other.width};
    const PathRelation relation =
        relateFeet(ego_foot, projectExtended(reference_line, footprint.centre), lane_width, ego, footprint);
    if (!covered(sensor, lateral_range, ego, other, relation)) continue;
    ObservedObject object;
    static_cast<RoadUserState&>(object) = other;
    object.relation = relation;
    objects.push_back(object);
  }
  return objects;
}

const ObservedObject* nearestInPath(const std::vector<ObservedObject>& objects) {
  const ObservedObject* nearest = nullptr;
  for (const auto& object : objects) {
    if (!object.relation.inPath) continue;
    if (nearest == nullptr || object.relation.longitudinalGap < nearest->relation.longitudinalGap) nearest = &object;
  }
  return nearest;
}

}  // namespace vsd::sim
