#include "vsd/core/geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "vsd/core/error.hpp"

namespace vsd {

double wrapAngle(double angle_rad) {
  double wrapped = std::fmod(angle_rad + kPi, 2.0 * kPi);
  if (wrapped <= 0.0) wrapped += 2.0 * kPi;
  return wrapped - kPi;
}

Vec2 headingVector(double heading_rad) { return {std::cos(heading_rad), std::sin(heading_rad)}; }

double headingOf(const Vec2& direction) { return std::atan2(direction.y(), direction.x()); }

namespace {

constexpr std::size_t kNoSegment = std::numeric_limits<std::size_t>::max();
/// Beyond this |coordinate| project() scans every segment (squares stay far from overflow).
constexpr double kLargestIndexedCoordinate = 1e100;

/// The point of segment start-end nearest to `point`, as a fraction along it, and the
/// squared distance to it. The one definition both searches of project() use.
struct SegmentFoot {
  double fraction = 0.0;
  double distanceSq = 0.0;
  double lengthSq = 0.0;  ///< of the segment
};

inline SegmentFoot footOn(const Vec2& point, const Vec2& start, const Vec2& end) {
  SegmentFoot foot;
  const Vec2 delta = end - start;
  foot.lengthSq = delta.squaredNorm();
  if (foot.lengthSq > 0.0) foot.fraction = std::clamp((point - start).dot(delta) / foot.lengthSq, 0.0, 1.0);
  foot.distanceSq = (point - (start + foot.fraction * delta)).squaredNorm();
  return foot;
}

}  // namespace

MeasuredPolyline::MeasuredPolyline(Polyline points) : points_(std::move(points)) {
  if (points_.size() < 2) throw Error("MeasuredPolyline needs at least 2 points, got " + std::to_string(points_.size()));
  cumulative_.resize(points_.size());
  cumulative_[0] = 0.0;
  for (std::size_t i = 1; i < points_.size(); ++i) {
    cumulative_[i] = cumulative_[i - 1] + (points_[i] - points_[i - 1]).norm();
  }
  // Bounding boxes of blocks of segments for project(); only where they can pay off and
  // where every coordinate is finite and small enough that no square overflows.
  const std::size_t segments = points_.size() - 1;
  if (segments < 2 * kBlock) return;
  for (const Vec2& p : points_) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return;
    scale_ = std::max({scale_, std::abs(p.x()), std::abs(p.y())});
  }
  if (scale_ > kLargestIndexedCoordinate) return;
  blocks_.reserve((segments + kBlock - 1) / kBlock);
  for (std::size_t first = 0; first < segments; first += kBlock) {
    const std::size_t last = std::min(first + kBlock, segments);  // the block's last end point
    Block box{points_[first].x(), points_[first].y(), points_[first].x(), points_[first].y()};
    for (std::size_t i = first + 1; i <= last; ++i) {
      box.minX = std::min(box.minX, points_[i].x());
      box.minY = std::min(box.minY, points_[i].y());
      box.maxX = std::max(box.maxX, points_[i].x());
      box.maxY = std::max(box.maxY, points_[i].y());
    }
    blocks_.push_back(box);
  }
}

std::size_t MeasuredPolyline::segmentAt(double arc_length) const {
  // upper_bound finds the first vertex beyond s; the segment starts one before it.
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), arc_length);
  const auto index = static_cast<std::size_t>(std::distance(cumulative_.begin(), it));
  if (index == 0) return 0;
  return std::min(index - 1, points_.size() - 2);
}

Vec2 MeasuredPolyline::pointAt(double arc_length) const {
  const std::size_t seg = segmentAt(arc_length);
  const Vec2 delta = points_[seg + 1] - points_[seg];
  const double seg_length = cumulative_[seg + 1] - cumulative_[seg];
  if (seg_length <= 0.0) return points_[seg];
  return points_[seg] + delta * ((arc_length - cumulative_[seg]) / seg_length);
}

double MeasuredPolyline::headingAt(double arc_length) const {
  std::size_t seg = segmentAt(arc_length);
  // Zero-length segments have no direction: use the next one that has.
  while (seg + 2 < points_.size() && (points_[seg + 1] - points_[seg]).squaredNorm() == 0.0) ++seg;
  return headingOf(points_[seg + 1] - points_[seg]);
}

PolylineProjection MeasuredPolyline::project(const Vec2& point) const {
  if (blocks_.empty() || !std::isfinite(point.x()) || !std::isfinite(point.y()) ||
      std::max(std::abs(point.x()), std::abs(point.y())) > kLargestIndexedCoordinate) {
    return projectScan(point);
  }
  return projectIndexed(point);
}

PolylineProjection MeasuredPolyline::projectScan(const Vec2& point) const {
  // The search compares squared distances only; arc length, heading (an atan2) and side
  // are worked out once, for the nearest segment. A zero-length nearest segment keeps the
  // heading of the last nearer segment that has a direction (0 if none has).
  std::size_t best_segment = 0;
  std::size_t heading_segment = kNoSegment;
  double best_fraction = 0.0;
  double best_distance_sq = std::numeric_limits<double>::infinity();
  for (std::size_t seg = 0; seg + 1 < points_.size(); ++seg) {
    const SegmentFoot foot = footOn(point, points_[seg], points_[seg + 1]);
    if (foot.distanceSq < best_distance_sq) {
      best_distance_sq = foot.distanceSq;
      best_segment = seg;
      best_fraction = foot.fraction;
      if (foot.lengthSq > 0.0) heading_segment = seg;
    }
  }
  if (best_distance_sq == std::numeric_limits<double>::infinity()) return {};
  return projectionOn(point, best_segment, best_fraction, best_distance_sq, heading_segment);
}

PolylineProjection MeasuredPolyline::projectIndexed(const Vec2& point) const {
  // The scan's answer is the first segment at the least computed distance. Any segment of a
  // block whose box is farther than the nearest segment found so far - by a margin far above
  // the rounding of both distances - is farther than that segment in the scan's arithmetic
  // too, so it can be neither the first nearest segment nor tie with it. The block with the
  // nearest box goes first; the others follow in order; ties go to the lower index.
  const double margin = 1e-9 * (std::max({scale_, std::abs(point.x()), std::abs(point.y())}) + 1.0);
  const auto box_distance_sq = [&](const Block& box) {
    const double dx = std::max({box.minX - point.x(), point.x() - box.maxX, 0.0});
    const double dy = std::max({box.minY - point.y(), point.y() - box.maxY, 0.0});
    return dx * dx + dy * dy;
  };
  const std::size_t segments = points_.size() - 1;
  std::size_t best_segment = kNoSegment;
  double best_fraction = 0.0;
  double best_distance_sq = std::numeric_limits<double>::infinity();
  bool best_has_length = false;
  double skip_beyond_sq = std::numeric_limits<double>::infinity();  // boxes farther than this are skipped
  const auto search_block = [&](std::size_t block) {
    const std::size_t first = block * kBlock;
    const std::size_t end = std::min(first + kBlock, segments);
    bool improved = false;
    for (std::size_t seg = first; seg < end; ++seg) {
      const SegmentFoot foot = footOn(point, points_[seg], points_[seg + 1]);
      if (foot.distanceSq < best_distance_sq || (foot.distanceSq == best_distance_sq && seg < best_segment)) {
        best_distance_sq = foot.distanceSq;
        best_segment = seg;
        best_fraction = foot.fraction;
        best_has_length = foot.lengthSq > 0.0;
        improved = true;
      }
    }
    if (improved) {
      constexpr double kSlack = 1.0 + 1e-12;
      const double reach = std::sqrt(best_distance_sq) * kSlack + margin;
      skip_beyond_sq = reach * reach * kSlack;
    }
  };
  std::size_t nearest_block = 0;
  double nearest_box_sq = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const double d = box_distance_sq(blocks_[b]);
    if (d < nearest_box_sq) {
      nearest_box_sq = d;
      nearest_block = b;
    }
  }
  search_block(nearest_block);
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    if (b != nearest_block && !(box_distance_sq(blocks_[b]) > skip_beyond_sq)) search_block(b);
  }
  // A zero-length nearest segment takes its heading from the scan's history: scan.
  if (!best_has_length) return projectScan(point);
  return projectionOn(point, best_segment, best_fraction, best_distance_sq, best_segment);
}

PolylineProjection MeasuredPolyline::projectionOn(const Vec2& point, std::size_t segment, double fraction,
                                                  double distance_sq, std::size_t heading_segment) const {
  PolylineProjection best;
  const Vec2 start = points_[segment];
  const Vec2 delta = points_[segment + 1] - start;
  best.segment = segment;
  best.foot = start + fraction * delta;
  best.arcLength = cumulative_[segment] + fraction * std::sqrt(delta.squaredNorm());
  if (heading_segment != kNoSegment) best.heading = headingOf(points_[heading_segment + 1] - points_[heading_segment]);
  const Vec2 relative = point - best.foot;
  const double cross = delta.x() * relative.y() - delta.y() * relative.x();
  best.lateralOffset = std::copysign(std::sqrt(distance_sq), cross);
  return best;
}

double polylineLength(const Polyline& points) {
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

Polyline offsetPolyline(const Polyline& points, double left_offset) {
  const std::size_t n = points.size();
  Polyline result(n);
  if (n < 2) return points;
  auto segment_normal = [&](std::size_t seg) -> Vec2 {
    const Vec2 delta = points[seg + 1] - points[seg];
    const double length = delta.norm();
    if (length <= 0.0) return Vec2::Zero();
    return Vec2(-delta.y(), delta.x()) / length;  // left normal
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 before = i > 0 ? segment_normal(i - 1) : segment_normal(0);
    const Vec2 after = i + 1 < n ? segment_normal(i) : segment_normal(n - 2);
    Vec2 bisector = before + after;
    const double bisector_length = bisector.norm();
    if (bisector_length < 1e-9) {
      bisector = after.squaredNorm() > 0.0 ? after : before;
      result[i] = points[i] + left_offset * bisector;
      continue;
    }
    bisector /= bisector_length;
    // Mitre: the offset along the bisector is d / cos(half turn angle); capped at 4 d.
    const double cos_half = std::max(bisector.dot(after.squaredNorm() > 0.0 ? after : before), 0.25);
    result[i] = points[i] + (left_offset / cos_half) * bisector;
  }
  return result;
}

std::optional<Vec2> pointAtX(const Polyline& points, double x) {
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    const Vec2& a = points[i];
    const Vec2& b = points[i + 1];
    const double lo = std::min(a.x(), b.x());
    const double hi = std::max(a.x(), b.x());
    if (x < lo || x > hi) continue;
    if (b.x() == a.x()) return a;
    const double fraction = (x - a.x()) / (b.x() - a.x());
    return Vec2(x, a.y() + fraction * (b.y() - a.y()));
  }
  return std::nullopt;
}

Polyline clipToXRange(const Polyline& points, double x_min, double x_max) {
  Polyline clipped;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec2& p = points[i];
    const bool inside = p.x() >= x_min && p.x() <= x_max;
    if (i > 0) {
      const Vec2& prev = points[i - 1];
      // Add crossings of the range borders between prev and p, in travel order.
      for (double border : {x_min, x_max}) {
        const bool crosses = (prev.x() - border) * (p.x() - border) < 0.0;
        if (!crosses) continue;
        const double fraction = (border - prev.x()) / (p.x() - prev.x());
        clipped.emplace_back(border, prev.y() + fraction * (p.y() - prev.y()));
      }
    }
    if (inside) clipped.push_back(p);
  }
  return clipped;
}

double headingFromSumoAngle(double sumo_angle_deg) { return wrapAngle(kPi / 2.0 - sumo_angle_deg * kPi / 180.0); }

double sumoAngleFromHeading(double heading_rad) {
  double angle = 90.0 - heading_rad * 180.0 / kPi;
  angle = std::fmod(angle, 360.0);
  if (angle < 0.0) angle += 360.0;
  return angle;
}

namespace {

std::array<Vec2, 4> cornersOf(const Footprint& f) {
  const Vec2 along = 0.5 * f.length * headingVector(f.heading);
  const Vec2 across = 0.5 * f.width * headingVector(f.heading + 0.5 * kPi);
  return {f.centre + along + across, f.centre - along + across, f.centre - along - across, f.centre + along - across};
}

double pointSegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double length_sq = ab.squaredNorm();
  const double t = length_sq > 0.0 ? std::clamp((p - a).dot(ab) / length_sq, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

}  // namespace

double footprintGap(const Footprint& a, const Footprint& b) {
  const auto ca = cornersOf(a);
  const auto cb = cornersOf(b);
  // Separating-axis test over both rectangles' edge normals: rectangles overlap iff
  // their projections overlap on all four axes; the smallest separating move over
  // these axes is then the penetration depth (exact for convex polygons).
  double depth = std::numeric_limits<double>::infinity();
  for (const double heading : {a.heading, a.heading + 0.5 * kPi, b.heading, b.heading + 0.5 * kPi}) {
    const Vec2 axis = headingVector(heading);
    double min_a = std::numeric_limits<double>::infinity(), max_a = -min_a, min_b = min_a, max_b = -min_a;
    for (const auto& c : ca) {
      min_a = std::min(min_a, c.dot(axis));
      max_a = std::max(max_a, c.dot(axis));
    }
    for (const auto& c : cb) {
      min_b = std::min(min_b, c.dot(axis));
      max_b = std::max(max_b, c.dot(axis));
    }
    // The shorter of the two moves along this axis that separate the projections
    // (not the length of their intersection: one may contain the other).
    depth = std::min(depth, std::min(max_a - min_b, max_b - min_a));
  }
  if (depth > 0.0) return -depth;
  // Apart: the shortest distance between two disjoint convex polygons runs from a
  // corner of one to an edge of the other.
  double distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = 0; j < 4; ++j) {
      distance = std::min(distance, pointSegmentDistance(ca[i], cb[j], cb[(j + 1) % 4]));
      distance = std::min(distance, pointSegmentDistance(cb[i], ca[j], ca[(j + 1) % 4]));
    }
  }
  return distance;
}

}  // namespace vsd
