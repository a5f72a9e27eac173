#include "vsd/road/road_geometry.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"

namespace vsd::road {

double RoadGeometry::laneOffset(int lane) const { return scenario::laneCentreOffset(lane, laneWidths); }

double RoadGeometry::laneWidthOf(int lane) const { return laneWidths.at(static_cast<std::size_t>(lane)); }

double RoadGeometry::halfWidth() const { return scenario::halfRoadWidth(laneWidths); }

int RoadGeometry::laneAt(double offset) const { return scenario::laneAtOffset(offset, laneWidths); }

double RoadGeometry::regionStart() const {
  double s = 0.0;
  for (std::size_t i = 1; i <= regionBegin && i < centre.size(); ++i) s += (centre[i] - centre[i - 1]).norm();
  return s;
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
  const double half_width = halfWidth();
  return {lo.array() - half_width, hi.array() + half_width};
}

namespace {


/// The region's points of a polynomial road (noise included) and the noise-free tangents at its ends.
Polyline polynomialRegion(const scenario::ConcreteScenario& concrete, Vec2& tangent_begin, Vec2& tangent_end) {
  const auto& spec = concrete.logical->road;
  std::vector<double> variables = concrete.inputs;
  variables.push_back(0.0);  // 'x' is the last variable of the centre expression
  auto centre_at = [&](double x) {
    variables.back() = x;
    return spec.centre.evaluate(variables);
  };
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
  tangent_begin = tangent_at(spec.xMin);
  tangent_end = tangent_at(spec.xMax);
  return region;
}

/// Curvature and length of an arc road, checked.
std::pair<double, double> arcOf(const scenario::LogicalScenario& logical, const std::vector<double>& inputs) {
  const auto& spec = logical.road;
  const double curvature = spec.curvature.evaluate(inputs);
  const double length = spec.length.evaluate(inputs);
  if (!std::isfinite(curvature) || !std::isfinite(length) || !(length > 0.0) ||
      !(std::abs(curvature * length) <= scenario::kMaxArcTurn)) {
    throw ConfigError(fmt::format("{}: road.curvature '{}' = {} 1/m, road.length '{}' = {} m: expected a length > 0 "
                                  "and a turn |curvature| * length of at most {} rad",
                                  logical.sourceFile.string(), spec.curvature.text(), formatValue(curvature),
                                  spec.length.text(), formatValue(length), scenario::kMaxArcTurn));
  }
  return {curvature, length};
}

Vec2 arcPoint(double curvature, double s) {
  if (std::abs(curvature) < 1e-12) return {s, 0.0};
  return {std::sin(curvature * s) / curvature, (1.0 - std::cos(curvature * s)) / curvature};
}

Polyline arcRegion(const scenario::ConcreteScenario& concrete, Vec2& tangent_begin, Vec2& tangent_end) {
  const auto [curvature, length] = arcOf(*concrete.logical, concrete.inputs);
  const double spacing = chordSpacing(curvature);
  const auto segments = static_cast<int>(std::ceil(length / spacing));
  Polyline region;
  for (int i = 0; i <= segments; ++i) region.push_back(arcPoint(curvature, length * i / segments));
  tangent_begin = headingVector(0.0);
  tangent_end = headingVector(curvature * length);
  return region;
}

/// A polyline road's region as given, the extensions along its end segments.
Polyline polylineRegion(const scenario::RoadSpec& spec, Vec2& tangent_begin, Vec2& tangent_end) {
  Polyline region;
  region.reserve(spec.centreLine.size());
  for (const auto& [x, y] : spec.centreLine) region.emplace_back(x, y);
  tangent_begin = (region[1] - region[0]).normalized();
  tangent_end = (region.back() - region[region.size() - 2]).normalized();
  return region;
}

}  // namespace

double chordSpacing(double curvature, double chord_error, double longest) {
  if (std::abs(curvature) > 0.0) return std::min(longest, std::sqrt(8.0 * chord_error / std::abs(curvature)));
  return longest;
}

std::pair<double, double> regionXRange(const scenario::LogicalScenario& logical, const std::vector<double>& inputs) {
  if (logical.road.shape == scenario::RoadSpec::Shape::Polynomial) return {logical.road.xMin, logical.road.xMax};
  if (logical.road.shape == scenario::RoadSpec::Shape::Polyline) {
    return {logical.road.centreLine.front().first, logical.road.centreLine.back().first};
  }
  const auto [curvature, length] = arcOf(logical, inputs);
  return {0.0, arcPoint(curvature, length).x()};
}

RoadGeometry buildRoadGeometry(const scenario::ConcreteScenario& concrete) {
  const auto& spec = concrete.logical->road;
  RoadGeometry road;
  road.lanes = spec.lanes;
  road.laneWidths = concrete.laneWidths;
  road.speedLimit = spec.speedLimit;

  Vec2 tangent_begin;
  Vec2 tangent_end;
  using Shape = scenario::RoadSpec::Shape;
  const Polyline region = spec.shape == Shape::Polynomial ? polynomialRegion(concrete, tangent_begin, tangent_end)
                          : spec.shape == Shape::Arc      ? arcRegion(concrete, tangent_begin, tangent_end)
                                                          : polylineRegion(spec, tangent_begin, tangent_end);
  road.centre.reserve(region.size() + 2);
  if (spec.extensionBefore > 0.0) road.centre.push_back(region.front() - spec.extensionBefore * tangent_begin);
  road.regionBegin = road.centre.size();
  road.centre.insert(road.centre.end(), region.begin(), region.end());
  road.regionEnd = road.centre.size();
  if (spec.extensionAfter > 0.0) road.centre.push_back(region.back() + spec.extensionAfter * tangent_end);
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

RoadUserStart roadUserStart(const RoadGeometry& road, const LaneFrame& frame, const scenario::ConcreteScenario& concrete,
                            const scenario::ConcreteVehicle& vehicle, double from_s, double from_length) {
  RoadUserStart start;
  start.d = road.laneOffset(vehicle.lane) + vehicle.offset;
  if (vehicle.along == scenario::VehicleSpec::Along::X) {
    const StartPose on_lane = startPoseOnLane(road, vehicle.lane, vehicle.x, vehicle.id);
    start.s = frame.coordinates(on_lane.position).first;
    if (vehicle.offset == 0.0) {
      start.position = on_lane.position;
      start.heading = vehicle.heading == 0.0 ? on_lane.heading : wrapAngle(on_lane.heading + vehicle.heading);
      return start;
    }
  } else {
    using Along = scenario::VehicleSpec::Along;
    start.s = vehicle.along == Along::S             ? road.regionStart() + vehicle.alongValue
              : vehicle.along == Along::EgoRelative ? from_s + vehicle.alongValue
                                                    : from_s + vehicle.alongValue + 0.5 * (from_length + vehicle.length);
    if (start.s < 0.0 || start.s > frame.length()) {
      throw ConfigError(fmt::format("{}: road user '{}' starts {:.1f} m along a road of {:.1f} m (lead-in and "
                                    "lead-out included): expected a start on its road",
                                    concrete.where(), vehicle.id, start.s - road.regionStart(), frame.length()));
    }
  }
  start.position = frame.point(start.s, start.d);
  start.heading = wrapAngle(frame.heading(start.s, start.d) + vehicle.heading);
  return start;
}

}  // namespace vsd::road
