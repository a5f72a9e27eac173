// Criticality measures that SUMO's SSM device reports (README "Metrics", "Cross-check
// against SUMO's SSM device"): post-encroachment time, deceleration rate to avoid a
// crash, and the time-to-collision / headway / gap of a leader along the Ego's lane.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "functions.hpp"

namespace vsd::metrics::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Headway is undefined for an Ego at (almost) standstill, as for thw_min.
constexpr double kMinHeadwaySpeed = 0.1;  // m/s
/// Paths meeting at less than this angle merge or run alongside; PET covers crossings.
const double kMinCrossingAngle = 10.0 * kPi / 180.0;

// --- along the Ego's lane (SSM's convention) -------------------------------------------

/// One vehicle ahead of the Ego on its lane at one instant, measured along the lane.
struct LaneLeader {
  /// m: s(front of O) - L_O - s(front of Ego), s = arc length on the lane centre; for O driving
  /// against the lane, s(front of O) - s(front of Ego)
  double gap = 0.0;
  double egoSpeed = 0.0;    ///< m/s
  double otherSpeed = 0.0;  ///< m/s along the lane (< 0 against it)
};

Vec2 frontOf(const VehicleTrack& track, std::size_t k) {
  const auto& state = track.states[k];
  return state.position() + 0.5 * track.length * headingVector(state.heading);
}

/// Heading more than 120 deg off the lane's direction: a vehicle driving against the lane
/// (oncoming traffic). A pedestrian crossing (about 90 deg) is not.
bool againstLane(double heading, double lane_heading) { return std::cos(heading - lane_heading) < -0.5; }

/// Where another vehicle is along the Ego's lane: the far and near ends of it (m of arc
/// length), and its speed along the lane (m/s, < 0 against it).
struct AlongLane {
  double far = 0.0;
  double near = 0.0;
  double speed = 0.0;
};

AlongLane alongLane(const MeasuredPolyline& lane, const VehicleTrack& track, std::size_t k) {
  const auto& state = track.states[k];
  const Vec2 front = frontOf(track, k);
  const PolylineProjection front_foot = lane.project(front);
  if (!againstLane(state.heading, front_foot.heading)) {
    return {front_foot.arcLength, front_foot.arcLength - track.length, state.speed};
  }
  // Its rear is ahead along the lane, its front faces the Ego.
  const Vec2 rear = 2.0 * state.position() - front;
  return {lane.project(rear).arcLength, front_foot.arcLength, -state.speed};
}

/// Calls visit(leader) for every instant and other vehicle that is ahead on the Ego's lane:
/// its front beyond the Ego's along the lane, and the two overlapping sideways
/// (|lateral offset difference| < half the sum of widths). Returns false if no pair
/// of vehicles was valid at any instant.
template <typename Visitor>
bool forEachLaneLeader(const MetricContext& context, Visitor&& visit) {
  const Trace& trace = context.trace;
  const VehicleTrack& ego = trace.ego();
  if (context.egoLaneCentre.size() < 2) return false;
  const MeasuredPolyline lane(context.egoLaneCentre);
  bool any = false;
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    if (!ego.validAt(k)) continue;
    const double ego_front = lane.project(frontOf(ego, k)).arcLength;
    const double ego_lateral = lane.project(ego.states[k].position()).lateralOffset;
    for (std::size_t v = 1; v < trace.vehicles.size(); ++v) {
      const VehicleTrack& other = trace.vehicles[v];
      if (!other.validAt(k)) continue;
      any = true;
      const AlongLane other_along = alongLane(lane, other, k);
      const double other_lateral = lane.project(other.states[k].position()).lateralOffset;
      if (other_along.far <= ego_front || std::abs(other_lateral - ego_lateral) >= 0.5 * (ego.width + other.width)) {
        continue;
      }
      visit(LaneLeader{other_along.near - ego_front, ego.states[k].speed, other_along.speed});
    }
  }
  return any;
}

// --- post-encroachment time ---------------------------------------------------------------

/// A vehicle's centre path with the arc length and time of every recorded point.
struct TimedPath {
  Polyline points;
  std::vector<double> arc;   ///< m
  std::vector<double> time;  ///< s
};

TimedPath timedPath(const VehicleTrack& track, double step) {
  TimedPath path;
  for (std::size_t k = 0; k < track.states.size(); ++k) {
    if (!track.validAt(k)) continue;
    const Vec2 point = track.states[k].position();
    path.arc.push_back(path.points.empty() ? 0.0 : path.arc.back() + (point - path.points.back()).norm());
    path.points.push_back(point);
    path.time.push_back(static_cast<double>(k) * step);
  }
  return path;
}

/// When the path reaches arc length `s`: -inf before the recording, +inf after it.
double timeAtArc(const TimedPath& path, double s) {
  if (s < path.arc.front()) return -kInf;
  for (std::size_t i = 0; i + 1 < path.arc.size(); ++i) {
    if (s <= path.arc[i + 1] && path.arc[i + 1] > path.arc[i]) {
      const double fraction = std::max(0.0, (s - path.arc[i]) / (path.arc[i + 1] - path.arc[i]));
      return path.time[i] + fraction * (path.time[i + 1] - path.time[i]);
    }
  }
  return kInf;
}

/// Where two segments cross: the fraction along each, if they do (parallel ones never do).
std::optional<std::pair<double, double>> segmentCrossing(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1) {
  const Vec2 da = a1 - a0;
  const Vec2 db = b1 - b0;
  const double denominator = da.x() * db.y() - da.y() * db.x();
  if (std::abs(denominator) < 1e-12) return std::nullopt;
  const Vec2 offset = b0 - a0;
  const double u = (offset.x() * db.y() - offset.y() * db.x()) / denominator;
  const double w = (offset.x() * da.y() - offset.y() * da.x()) / denominator;
  if (u < 0.0 || u > 1.0 || w < 0.0 || w > 1.0) return std::nullopt;
  return std::make_pair(u, w);
}

/// The time a vehicle occupies the conflict area around a crossing at arc length `s` of its
/// path: from its front reaching the other's strip (half-width / sin angle before s) until
/// its rear leaves it.
std::pair<double, double> occupation(const TimedPath& path, double s, double half_strip, double length) {
  return {timeAtArc(path, s - half_strip - 0.5 * length), timeAtArc(path, s + half_strip + 0.5 * length)};
}

/// Post-encroachment time at one crossing, if the recording shows it: the second vehicle's
/// entry minus the first one's exit (0 if both occupy the area at once).
std::optional<double> crossingPet(std::pair<double, double> first, std::pair<double, double> second) {
  if (std::isfinite(first.second) && std::isfinite(second.first) && first.second <= second.first) {
    return second.first - first.second;
  }
  if (std::isfinite(second.second) && std::isfinite(first.first) && second.second <= first.first) {
    return first.first - second.second;
  }
  const bool overlap = first.first < second.second && second.first < first.second;
  if (overlap && (std::isfinite(first.first) || std::isfinite(second.first))) return 0.0;
  return std::nullopt;
}

/// Minimum PET between two vehicles over every crossing of their centre paths.
std::optional<double> pairPet(const VehicleTrack& a, const VehicleTrack& b, double step) {
  const TimedPath path_a = timedPath(a, step);
  const TimedPath path_b = timedPath(b, step);
  std::optional<double> best;
  for (std::size_t i = 0; i + 1 < path_a.points.size(); ++i) {
    for (std::size_t j = 0; j + 1 < path_b.points.size(); ++j) {
      const auto crossing = segmentCrossing(path_a.points[i], path_a.points[i + 1], path_b.points[j], path_b.points[j + 1]);
      if (!crossing) continue;
      const Vec2 da = path_a.points[i + 1] - path_a.points[i];
      const Vec2 db = path_b.points[j + 1] - path_b.points[j];
      const double sine = std::abs(da.x() * db.y() - da.y() * db.x()) / (da.norm() * db.norm());
      if (sine < std::sin(kMinCrossingAngle)) continue;
      const double s_a = path_a.arc[i] + crossing->first * (path_a.arc[i + 1] - path_a.arc[i]);
      const double s_b = path_b.arc[j] + crossing->second * (path_b.arc[j + 1] - path_b.arc[j]);
      const auto pet = crossingPet(occupation(path_a, s_a, 0.5 * b.width / sine, a.length),
                                   occupation(path_b, s_b, 0.5 * a.width / sine, b.length));
      if (pet && (!best || *pet < *best)) best = pet;
    }
  }
  return best;
}

}  // namespace

double minPostEncroachmentTime(const MetricContext& context) {
  const Trace& trace = context.trace;
  double result = kInf;
  for (std::size_t v = 1; v < trace.vehicles.size(); ++v) {
    if (const auto pet = pairPet(trace.ego(), trace.vehicles[v], trace.step)) result = std::min(result, *pet);
  }
  return result;
}

double maxDecelerationToAvoidCrash(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  bool any = false;
  double result = 0.0;
  for (std::size_t v = 1; v < context.trace.vehicles.size(); ++v) {
    const VehicleTrack& other = context.trace.vehicles[v];
    for (std::size_t k = 0; k < ego.states.size() && k < other.states.size(); ++k) {
      if (!ego.validAt(k) || !other.validAt(k)) continue;
      any = true;
      const auto& e = ego.states[k];
      const auto& o = other.states[k];
      const Vec2 towards = o.position() - e.position();
      const double distance = towards.norm();
      const Vec2 ego_direction = headingVector(e.heading);
      if (distance <= 0.0 || towards.dot(ego_direction) <= 0.0) continue;  // not ahead
      const double closing = (e.speed * ego_direction - o.speed * headingVector(o.heading)).dot(towards / distance);
      if (closing <= 0.0) continue;
      const double gap = distance - 0.5 * (ego.length + other.length);
      result = std::max(result, gap > 0.0 ? closing * closing / (2.0 * gap) : kInf);
    }
  }
  return any ? result : kNaN;
}

double minLaneTimeToCollision(const MetricContext& context) {
  double result = kInf;
  const bool any = forEachLaneLeader(context, [&](const LaneLeader& leader) {
    const double closing = leader.egoSpeed - leader.otherSpeed;
    if (closing > 0.0) result = std::min(result, std::max(leader.gap, 0.0) / closing);
  });
  return any ? result : kNaN;
}

double minLaneTimeHeadway(const MetricContext& context) {
  double result = kInf;
  const bool any = forEachLaneLeader(context, [&](const LaneLeader& leader) {
    if (leader.egoSpeed > kMinHeadwaySpeed) result = std::min(result, std::max(leader.gap, 0.0) / leader.egoSpeed);
  });
  return any ? result : kNaN;
}

double maxLaneDecelerationToAvoidCrash(const MetricContext& context) {
  double result = 0.0;
  const bool any = forEachLaneLeader(context, [&](const LaneLeader& leader) {
    const double closing = leader.egoSpeed - leader.otherSpeed;
    if (closing > 0.0) result = std::max(result, leader.gap > 0.0 ? closing * closing / (2.0 * leader.gap) : kInf);
  });
  return any ? result : kNaN;
}

double minLaneGap(const MetricContext& context) {
  double result = kInf;
  const bool any = forEachLaneLeader(context, [&](const LaneLeader& leader) { result = std::min(result, leader.gap); });
  return any ? result : kNaN;
}

}  // namespace vsd::metrics::detail
