#include "vsd/core/path_relation.hpp"

#include <cmath>

namespace vsd {

namespace {

/// Half extents of a footprint along and across a line it makes `relative_heading` with.
std::pair<double, double> halfExtents(const Footprint& footprint, double relative_heading) {
  const double c = std::abs(std::cos(relative_heading));
  const double s = std::abs(std::sin(relative_heading));
  const double along = 0.5 * (footprint.length * c + footprint.width * s);
  const double across = 0.5 * (footprint.length * s + footprint.width * c);
  return {along, across};
}

}  // namespace

PolylineProjection projectExtended(const MeasuredPolyline& line, const Vec2& point) {
  PolylineProjection projection = line.project(point);
  const Polyline& points = line.points();
  const bool before = projection.arcLength <= 0.0 && projection.segment == 0;
  const bool after = projection.arcLength >= line.length() && projection.segment + 2 == points.size();
  if (!before && !after) return projection;
  // Beyond an end the nearest point is the end itself; measure along the end segment instead.
  const Vec2 origin = before ? points.front() : points.back();
  const Vec2 direction = headingVector(projection.heading);
  const Vec2 relative = point - origin;
  const double along = direction.dot(relative);
  if ((before && along >= 0.0) || (after && along <= 0.0)) return projection;  // beside the end, not beyond it
  projection.arcLength = (before ? 0.0 : line.length()) + along;
  projection.lateralOffset = direction.x() * relative.y() - direction.y() * relative.x();
  projection.foot = origin + along * direction;
  return projection;
}

PathRelation relateToPath(const MeasuredPolyline& reference_line, double lane_width, const Footprint& ego,
                          const Footprint& object) {
  return relateFeet(projectExtended(reference_line, ego.centre), projectExtended(reference_line, object.centre),
                    lane_width, ego, object);
}

PathRelation relateFeet(const PolylineProjection& ego_foot, const PolylineProjection& object_foot, double lane_width,
                        const Footprint& ego, const Footprint& object) {
  const auto [ego_along, ego_across] = halfExtents(ego, wrapAngle(ego.heading - ego_foot.heading));

  PathRelation relation;
  relation.relativeHeading = wrapAngle(object.heading - object_foot.heading);
  const auto [object_along, object_across] = halfExtents(object, relation.relativeHeading);
  relation.longitudinalDistance = object_foot.arcLength - ego_foot.arcLength;
  relation.longitudinalGap = std::abs(relation.longitudinalDistance) - ego_along - object_along;
  relation.lateralDistance = object_foot.lateralOffset - ego_foot.lateralOffset;
  relation.lateralGap = std::abs(relation.lateralDistance) - ego_across - object_across;
  relation.objectOffset = object_foot.lateralOffset;
  relation.relativeLane = static_cast<int>(std::lround(object_foot.lateralOffset / lane_width));
  relation.inPath = relation.longitudinalDistance > 0.0 && relation.lateralGap < 0.0;
  return relation;
}

}  // namespace vsd
