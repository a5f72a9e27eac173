#include "vsd/road/road_geometry.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"

namespace vsd::road {

double RoadGeometry::laneOffset(int lane) const {
  // Lanes are spread symmetrically around the road centre; lane 0 is rightmost.
  return (static_cast<double>(lane) - 0.5 * static_cast<double>(lanes - 1)) * laneWidth;
}

Polyline RoadGeometry::laneCentre(int lane) const {
  const double offset = laneOffset(lane);
  return offset == 0.0 ? centre : offsetPolyline(centre, offset);
}

std::pair<Vec2, Vec2> RoadGeometry::bounds() const {
  Vec2 lo = centre.front();
  Vec2 hi = centre.front();
  for (const auto& p : centre) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double half_width = 0.5 * laneWidth * lanes;
  return {lo.array() - half_width, hi.array() + half_width};
}

RoadGeometry buildRoadGeometry(const scenario::ConcreteScenario& concrete) {
  const auto& spec = concrete.logical->road;
  std::vector<double> variables = concrete.inputs;
  variables.push_back(0.0);  // 'x' is the last variable of the centre expression
  auto centre_at = [&](double x) {
    variables.back() = x;
    return spec.centre.evaluate(variables);
  };

  RoadGeometry road;
  road.lanes = spec.lanes;
  road.laneWidth = concrete.laneWidth;
  road.speedLimit = spec.speedLimit;

  Polyline region;
  region.reserve(static_cast<std::size_t>(spec.points));
  for (int i = 0; i < spec.points; ++i) {
    const double x = spec.xMin + (spec.xMax - spec.xMin) * i / (spec.points - 1);
    const double y = centre_at(x) + concrete.centreNoise[static_cast<std::size_t>(i)];
    if (!std::isfinite(y)) {
      throw ConfigError(fmt::format("{}: road.centre: '{}' is not finite at x = {} (sample {})",
                                    concrete.logical->sourceFile.string(), spec.centre.text(), x, concrete.index));
    }
    region.emplace_back(x, y);
  }

  // Tangents of the noise-free centre line (central differences) give the
  // extension directions, so noise at the end points does not tilt the extensions.
  constexpr double kH = 1e-3;
  auto tangent_at = [&](double x) {
    const Vec2 direction(2.0 * kH, centre_at(x + kH) - centre_at(x - kH));
    return Vec2(direction / direction.norm());
  };
  road.centre.reserve(region.size() + 2);
  if (spec.extensionBefore > 0.0) road.centre.push_back(region.front() - spec.extensionBefore * tangent_at(spec.xMin));
  road.regionBegin = road.centre.size();
  road.centre.insert(road.centre.end(), region.begin(), region.end());
  road.regionEnd = road.centre.size();
  if (spec.extensionAfter > 0.0) road.centre.push_back(region.back() + spec.extensionAfter * tangent_at(spec.xMax));
  return road;
}

StartPose startPoseOnLane(const RoadGeometry& road, int lane, double x, const std::string& vehicle_id) {
  const MeasuredPolyline centre(road.laneCentre(lane));
  const auto point = pointAtX(centre.points(), x);
  if (!point) {
    throw ConfigError(fmt::format("vehicle '{}': x = {} m lies outside its road (x from {:.1f} to {:.1f} m)", vehicle_id,
                                  x, centre.points().front().x(), centre.points().back().x()));
  }
  const auto projection = centre.project(*point);
  return {*point, projection.heading};
}

}  // namespace vsd::road
