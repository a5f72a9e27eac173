#include "frames.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "vsd/core/defaults.hpp"
#include "vsd/core/error.hpp"

namespace vsd::model {

namespace {

/// Translated to the Ego's initial position and rotated by its initial heading.
class EgoFrame final : public SceneFrame {
 public:
  explicit EgoFrame(const VehicleState& ego)
      : origin_(ego.position()), heading_(ego.heading), c_(std::cos(ego.heading)), s_(std::sin(ego.heading)) {}
  Vec2 toModel(const Vec2& p) const override {
    const Vec2 d = p - origin_;
    return {c_ * d.x() + s_ * d.y(), -s_ * d.x() + c_ * d.y()};
  }
  Vec2 toScene(const Vec2& q) const override { return {origin_.x() + c_ * q.x() - s_ * q.y(), origin_.y() + s_ * q.x() + c_ * q.y()}; }
  double headingToScene(const Vec2&, double heading) const override { return wrapAngle(heading + heading_); }
  double headingToModel(const Vec2&, double heading) const override { return wrapAngle(heading - heading_); }
  Eigen::Matrix2d jacobian(const Vec2&) const override {
    Eigen::Matrix2d rotation;
    rotation << c_, -s_, s_, c_;
    return rotation;
  }

 private:
  Vec2 origin_;
  double heading_;
  double c_;
  double s_;
};

/// A lane-boundary vector of the scene.
struct BoundarySegment {
  Vec2 start;
  Vec2 end;
  Vec2 direction;  ///< unit
};

std::vector<BoundarySegment> boundarySegments(const vector::VectorizedScene& scene) {
  std::vector<BoundarySegment> segments;
  for (const auto& polyline : scene.polylines) {
    if (polyline.type != vector::ObjectType::LaneBoundary) continue;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      const auto& f = polyline.vectors[v];
      const Vec2 start(f[0], f[1]);
      const Vec2 end(f[2], f[3]);
      const double length = (end - start).norm();
      if (!polyline.valid[v] || !(length > 1e-3) || !start.allFinite() || !end.allFinite()) continue;
      segments.push_back({start, end, (end - start) / length});
    }
  }
  return segments;
}

/// Traces the centre line of the lane through a point, along and against a direction, from
/// the lane boundaries that pass beside it (README "Representations": lane frame).
class LaneTracer {
 public:
  static constexpr double kSpacing = 2.0;          ///< m between traced centre points
  static constexpr double kAhead = 200.0;          ///< m traced ahead of the Ego (5 s at 40 m/s)
  static constexpr double kBehind = 60.0;          ///< m traced behind it (the export radius)
  static constexpr double kMaxOffset = 6.0;        ///< m: boundaries farther to the side do not count
  static constexpr double kMinAlignment = 0.82;    ///< cos 35 deg: boundaries must run roughly along
  static constexpr double kDefaultWidth = kDefaultLaneWidth;  ///< m, until a lane with both boundaries is seen

  explicit LaneTracer(std::vector<BoundarySegment> segments) : segments_(std::move(segments)) {}

  /// Centre points from kBehind behind to kAhead ahead of `origin` (at least the origin's
  /// own point, which is the origin itself if no lane is found there).
  Polyline trace(const Vec2& origin, const Vec2& direction) {
    const auto here = centreAt(origin, direction);
    if (!here) return {origin};
    Polyline backward = march(here->first, -here->second, kBehind);
    Polyline forward = march(here->first, here->second, kAhead);
    Polyline line(backward.rbegin(), backward.rend());
    line.push_back(here->first);
    line.insert(line.end(), forward.begin(), forward.end());
    return line;
  }

 private:
  /// The lane centre beside `point` and the lane's direction there.
  std::optional<std::pair<Vec2, Vec2>> centreAt(const Vec2& point, const Vec2& direction) {
    const BoundarySegment* left = nullptr;
    const BoundarySegment* right = nullptr;
    double left_offset = kMaxOffset;
    double right_offset = -kMaxOffset;
    Vec2 left_foot = Vec2::Zero();
    Vec2 right_foot = Vec2::Zero();
    for (const auto& segment : segments_) {
      if (std::abs(segment.direction.dot(direction)) < kMinAlignment) continue;
      const Vec2 delta = segment.end - segment.start;
      const double fraction = (point - segment.start).dot(delta) / delta.squaredNorm();
      if (fraction < -0.01 || fraction > 1.01) continue;  // does not pass beside the point
      const Vec2 foot = segment.start + std::clamp(fraction, 0.0, 1.0) * delta;
      const Vec2 relative = foot - point;
      const double offset = direction.x() * relative.y() - direction.y() * relative.x();  // > 0: left
      if (offset > 0.05 && offset < left_offset) {
        left_offset = offset;
        left = &segment;
        left_foot = foot;
      } else if (offset < -0.05 && offset > right_offset) {
        right_offset = offset;
        right = &segment;
        right_foot = foot;
      }
    }
    const Vec2 normal(-direction.y(), direction.x());
    if (left && right) {
      width_ = left_offset - right_offset;
      Vec2 along = aligned(left->direction, direction) + aligned(right->direction, direction);
      return std::pair{0.5 * (left_foot + right_foot), Vec2(along.normalized())};
    }
    if (left) return std::pair{left_foot - 0.5 * width_ * normal, aligned(left->direction, direction)};
    if (right) return std::pair{right_foot + 0.5 * width_ * normal, aligned(right->direction, direction)};
    return std::nullopt;
  }

  static Vec2 aligned(const Vec2& segment_direction, const Vec2& direction) {
    return segment_direction.dot(direction) >= 0.0 ? segment_direction : Vec2(-segment_direction);
  }

  /// Centre points every kSpacing m from `start` along the lane, up to `length` m, until
  /// no boundary is found.
  Polyline march(const Vec2& start, const Vec2& direction, double length) {
    Polyline points;
    Vec2 point = start;
    Vec2 heading = direction;
    const double width = width_;
    for (double travelled = kSpacing; travelled <= length; travelled += kSpacing) {
      const auto next = centreAt(point + kSpacing * heading, heading);
      if (!next) break;
      // A step that jumps sideways (into a merging or crossing lane) ends the trace.
      if ((next->first - point).norm() > 2.0 * kSpacing) break;
      point = next->first;
      heading = next->second;
      points.push_back(point);
    }
    width_ = width;
    return points;
  }

  std::vector<BoundarySegment> segments_;
  double width_ = kDefaultWidth;
};

/// Moving average over +-`half_m` m of points `spacing` m apart (a point at the window's
/// edge weighs by the share of its spacing inside; ends keep their shorter windows): the lane
/// points of generated roads carry +-0.5 m of noise that drivers, previewing a few metres
/// ahead, do not follow, and a frame should not zigzag with it.
Polyline smoothed(const Polyline& line, double half_m, double spacing) {
  const double reach_points = half_m / spacing;
  const auto half = static_cast<std::size_t>(std::ceil(reach_points));
  Polyline out;
  out.reserve(line.size());
  for (std::size_t i = 0; i < line.size(); ++i) {
    const std::size_t reach = std::min({half, i, line.size() - 1 - i});
    Vec2 sum = Vec2::Zero();
    double weights = 0.0;
    for (std::size_t j = i - reach; j <= i + reach; ++j) {
      const double d = std::abs(static_cast<double>(j) - static_cast<double>(i));
      const double w = std::clamp(reach_points - d + 1.0, 0.0, 1.0);
      sum += w * line[j];
      weights += w;
    }
    out.push_back(sum / weights);
  }
  return out;
}

/// The reference line of the lane frame: the traced lane centre, smoothed, extended far
/// along its end directions so that every point of a scene projects inside it.
Polyline referenceLine(const vector::VectorizedScene& scene, const VehicleState& ego, double smoothing_m) {
  constexpr double kExtension = 1000.0;
  LaneTracer tracer(boundarySegments(scene));
  Polyline line = smoothed(tracer.trace(ego.position(), headingVector(ego.heading)), smoothing_m, LaneTracer::kSpacing);
  const Vec2 first_direction = line.size() >= 2 ? Vec2((line[1] - line[0]).normalized()) : headingVector(ego.heading);
  const Vec2 last_direction =
      line.size() >= 2 ? Vec2((line.back() - line[line.size() - 2]).normalized()) : headingVector(ego.heading);
  line.insert(line.begin(), line.front() - kExtension * first_direction);
  line.push_back(line.back() + kExtension * last_direction);
  return line;
}

/// Frenet frame along the reference line: x = arc length from the Ego's foot point,
/// y = signed offset (> 0 left).
class LaneFrame final : public SceneFrame {
 public:
  LaneFrame(const vector::VectorizedScene& scene, const VehicleState& ego, double smoothing_m)
      : line_(referenceLine(scene, ego, smoothing_m)) {
    origin_ = line_.project(ego.position()).arcLength;
  }
  Vec2 toModel(const Vec2& p) const override {
    const auto projection = line_.project(p);
    return {projection.arcLength - origin_, projection.lateralOffset};
  }
  Vec2 toScene(const Vec2& q) const override {
    const double s = q.x() + origin_;
    const double heading = line_.headingAt(s);
    return line_.pointAt(s) + q.y() * Vec2(-std::sin(heading), std::cos(heading));
  }
  double headingToScene(const Vec2& q, double heading) const override {
    return wrapAngle(heading + line_.headingAt(q.x() + origin_));
  }
  double headingToModel(const Vec2& p, double heading) const override {
    return wrapAngle(heading - line_.project(p).heading);
  }
  Eigen::Matrix2d jacobian(const Vec2& q) const override {
    const double heading = line_.headingAt(q.x() + origin_);
    Eigen::Matrix2d rotation;
    rotation << std::cos(heading), -std::sin(heading), std::sin(heading), std::cos(heading);
    return rotation;
  }

 private:
  MeasuredPolyline line_;
  double origin_ = 0.0;
};

}  // namespace

std::unique_ptr<SceneFrame> makeFrame(const std::string& name, const vector::VectorizedScene& scene,
                                      double lane_smoothing_m) {
  const auto ego = scene.egoInitialState();
  if (name == "ego") return std::make_unique<EgoFrame>(ego);
  if (name == "lane") return std::make_unique<LaneFrame>(scene, ego, lane_smoothing_m);
  throw ModelError("unknown model frame '" + name + "'");
}

}  // namespace vsd::model
