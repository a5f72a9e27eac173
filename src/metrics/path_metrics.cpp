// Metrics relative to the Ego's lane and the path it sweeps along it (core/path_relation.hpp):
// the same relateToPath the Ego's object list uses, so a cut-in is "in path" at the same
// instant for the controller and for these metrics. And the Ego's deceleration and jerk.

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "functions.hpp"
#include "vsd/core/path_relation.hpp"

namespace vsd::metrics::detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
/// relateToPath's relative lanes are not used here: an infinite lane width keeps them 0.
constexpr double kAnyLaneWidth = std::numeric_limits<double>::infinity();

Footprint footprintAt(const VehicleTrack& track, std::size_t k) {
  return {track.states[k].position(), track.states[k].heading, track.length, track.width};
}

/// Speed along the line at the state's foot point (its projectExtended).
double speedAlong(const PolylineProjection& foot, const VehicleState& state) {
  return state.speed * std::cos(state.heading - foot.heading);
}

}  // namespace

/// For every instant at which the Ego and at least one other road user are valid: the Ego's
/// foot on its lane line and each such road user's foot and relation to the Ego's path
/// (relateFeet: what relateToPath gives, each centre projected once).
struct PathRelations {
  struct Pair {
    std::size_t vehicle = 0;  ///< index in the trace (>= 1)
    PolylineProjection foot;  ///< projectExtended of its centre
    PathRelation relation;
  };
  struct Instant {
    std::size_t k = 0;
    PolylineProjection egoFoot;
    std::vector<Pair> pairs;  ///< in the trace's order of road users
  };
  std::vector<Instant> instants;
};

namespace {

const PathRelations& pathRelationsOf(const MetricContext& context) {
  if (context.pathRelations) return *context.pathRelations;
  auto relations = std::make_shared<PathRelations>();
  const VehicleTrack& ego = context.trace.ego();
  const MeasuredPolyline line(context.egoLaneCentre);
  for (std::size_t k = 0; k < ego.states.size(); ++k) {
    if (!ego.validAt(k)) continue;
    const Footprint ego_footprint = footprintAt(ego, k);
    PathRelations::Instant instant;
    instant.k = k;
    for (std::size_t v = 1; v < context.trace.vehicles.size(); ++v) {
      const VehicleTrack& other = context.trace.vehicles[v];
      if (!other.validAt(k)) continue;
      if (instant.pairs.empty()) instant.egoFoot = projectExtended(line, ego_footprint.centre);
      const Footprint other_footprint = footprintAt(other, k);
      PathRelations::Pair pair;
      pair.vehicle = v;
      pair.foot = projectExtended(line, other_footprint.centre);
      pair.relation = relateFeet(instant.egoFoot, pair.foot, kAnyLaneWidth, ego_footprint, other_footprint);
      instant.pairs.push_back(pair);
    }
    if (!instant.pairs.empty()) relations->instants.push_back(std::move(instant));
  }
  context.pathRelations = relations;
  return *relations;
}

/// Calls visit(k, gap, ego_speed_along, object_speed_along) for the in-path object at each
/// instant where there is one: the nearest (smallest bumper gap along the Ego's lane) of the
/// road users ahead that reach into the corridor the Ego sweeps. Returns false if the trace
/// has no valid pair of instants at all.
template <typename Visitor>
bool forEachInPathObject(const MetricContext& context, Visitor&& visit) {
  const PathRelations& relations = pathRelationsOf(context);
  for (const auto& instant : relations.instants) {
    const PathRelations::Pair* nearest = nullptr;
    double nearest_gap = kInf;
    for (const auto& pair : instant.pairs) {
      if (pair.relation.inPath && pair.relation.longitudinalGap < nearest_gap) {
        nearest_gap = pair.relation.longitudinalGap;
        nearest = &pair;
      }
    }
    if (nearest == nullptr) continue;
    const std::size_t k = instant.k;
    visit(k, std::max(nearest_gap, 0.0), speedAlong(instant.egoFoot, context.trace.ego().states[k]),
          speedAlong(nearest->foot, context.trace.vehicles[nearest->vehicle].states[k]));
  }
  return !relations.instants.empty();
}

}  // namespace

double minInPathTimeToCollision(const MetricContext& context) {
  if (context.egoLaneCentre.size() < 2) return kNaN;
  double result = kInf;
  const bool any = forEachInPathObject(context, [&](std::size_t, double gap, double ego_speed, double object_speed) {
    const double closing = ego_speed - object_speed;
    if (closing > 1e-9) result = std::min(result, gap / closing);
  });
  return any ? result : kNaN;
}

double minInPathTimeHeadway(const MetricContext& context) {
  if (context.egoLaneCentre.size() < 2) return kNaN;
  double result = kInf;
  const bool any = forEachInPathObject(context, [&](std::size_t, double gap, double ego_speed, double) {
    if (ego_speed > 0.1) result = std::min(result, gap / ego_speed);
  });
  return any ? result : kNaN;
}

double minLateralClearance(const MetricContext& context) {
  if (context.egoLaneCentre.size() < 2) return kNaN;
  const PathRelations& relations = pathRelationsOf(context);
  double result = kInf;
  for (const auto& instant : relations.instants) {
    for (const auto& pair : instant.pairs) {
      // Beside the Ego: their extents along the lane overlap.
      if (pair.relation.longitudinalGap < 0.0) result = std::min(result, pair.relation.lateralGap);
    }
  }
  return relations.instants.empty() ? kNaN : result;
}

double egoMaxDeceleration(const MetricContext& context) {
  const double a_min = egoMinAcceleration(context);
  return std::isnan(a_min) ? kNaN : std::max(0.0, -a_min);
}

double egoMaxJerk(const MetricContext& context) {
  const VehicleTrack& ego = context.trace.ego();
  const double dt = context.trace.step;
  double result = -kInf;
  // Accelerations are (v_k - v_{k-1}) / dt for k >= 1; a_0 only repeats a_1.
  for (std::size_t k = 2; k < ego.states.size(); ++k) {
    if (ego.validAt(k) && ego.validAt(k - 1) && ego.validAt(k - 2)) {
      result = std::max(result, std::abs(ego.states[k].accel - ego.states[k - 1].accel) / dt);
    }
  }
  return std::isinf(result) ? kNaN : result;
}

}  // namespace vsd::metrics::detail
