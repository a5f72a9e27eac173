// Positions and initial speeds of an OpenSCENARIO file's entities, resolved into road
// coordinates (relative ones after the entity they refer to).

#include <fmt/format.h>

#include <cmath>

#include "osc_template.hpp"

namespace vsd::interop::osc {

void requirePlanar(const xml::Reader& reader, const pugi::xml_node& node) {
  for (const char* unsupported : {"p", "r"}) {
    if (reader.optionalNumber(node, unsupported).value_or(0.0) != 0.0) {
      reader.fail(node, fmt::format("{}: vsd-sumo is planar (pitch and roll 0)", unsupported));
    }
  }
}

std::optional<OrientationElement> readOrientation(const xml::Reader& reader, const pugi::xml_node& position) {
  const pugi::xml_node node = position.child("Orientation");
  if (!node) return std::nullopt;
  reader.requireSubset(node, {});
  requirePlanar(reader, node);
  return OrientationElement{reader.optionalNumber(node, "h").value_or(0.0),
                            reader.optionalText(node, "type").value_or("relative") == "absolute"};
}

namespace {

Placement placementOf(Translation& translation, Entity& entity);

/// The heading (rad, relative to the road) an <Orientation> under `position` gives,
/// `base` when it has none. Relative orientations count from `base`.
double orientation(const Translation& translation, const pugi::xml_node& position, double s, double base) {
  const auto given = readOrientation(translation.reader, position);
  if (!given) return base;
  if (given->absolute) return std::remainder(given->h - translation.road.headingAt(s), 2.0 * kPi);
  return std::remainder(base + given->h, 2.0 * kPi);
}

/// `heading`: rad relative to the road that a relative <Orientation> counts from (and the
/// heading without one): pi on a lane whose driving direction is against the reference line.
Placement onRoad(const Translation& translation, const pugi::xml_node& position, double s, double t,
                 double heading = 0.0) {
  const CarriagewayRoad& road = translation.road;
  if (!(s >= 0.0 && s <= road.length)) {
    translation.reader.fail(position, fmt::format("s = {} m is off the road (0 .. {} m)", xml::number(s),
                                                  xml::number(road.length)));
  }
  return {s, t, orientation(translation, position, s, heading), road.nearestLane(t)};
}

/// m along vsd-sumo's road (the chain's reference line, before any reversal) of the position's
/// roadId and s; refuses a road that is not part of it and an s off that road.
double chainS(const Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  const CarriagewayRoad& road = translation.road;
  const std::string road_id = reader.text(position, "roadId");
  const RoadPiece* piece = road.piece(road_id);
  if (!piece) {
    reader.fail(position, fmt::format("roadId=\"{}\": not part of vsd-sumo's road, which is {} (the scenario's "
                                      "first road and the roads linked to it end to start; the language has one road)",
                                      road_id, road.name()));
  }
  const double s = reader.number(position, "s");
  if (road.pieces.size() > 1 && !(s >= 0.0 && s <= piece->length)) {
    reader.fail(position, fmt::format("s = {} m is off road '{}' (0 .. {} m)", xml::number(s), road_id,
                                      xml::number(piece->length)));
  }
  return piece->start + s;
}

Placement lanePosition(const Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  const CarriagewayRoad& road = translation.road;
  const double s = road.ownS(chainS(translation, position));
  const long lane_id = static_cast<long>(reader.integer(position, "laneId", -100, 100));
  const int lane = road.languageLane(lane_id, reader.where(position));
  // The offset counts along t (left of the reference line), as esmini reads it.
  const double offset = road.ownT(reader.optionalNumber(position, "offset").value_or(0.0));
  // A relative orientation counts from the lane's driving direction under the road's rule
  // (as esmini reads it): against the reference line on the left side in right-hand traffic.
  Placement placement = onRoad(translation, position, s, road.laneCentreT(lane) + offset, road.laneDirection(lane_id));
  placement.lane = lane;
  return placement;
}

/// A RoadPosition: s and t of the file's reference line; a relative orientation counts from its direction.
Placement roadPosition(const Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  const CarriagewayRoad& road = translation.road;
  return onRoad(translation, position, road.ownS(chainS(translation, position)),
                road.ownT(reader.number(position, "t")), road.reversed ? kPi : 0.0);
}

Placement relativeLanePosition(Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  if (position.attribute("dsLane")) reader.fail(position, "dsLane: use ds (along the road's reference line)");
  const Placement base = placementOf(translation, translation.entity(position, reader.text(position, "entityRef")));
  // dLane counts lane ids (esmini's reading with ds): on a reversed road, the other way.
  const CarriagewayRoad& road = translation.road;
  const long d_lane = reader.integer(position, "dLane", -100, 100);
  // From a road user beside the driving lanes (a shoulder), lane ids count from the lane that
  // shoulder is, one beyond the outer driving lane (as esmini counts them).
  const double right_edge = road.laneCentreT(0) - 0.5 * road.laneWidths.front();
  const double left_edge = road.laneCentreT(road.lanes - 1) + 0.5 * road.laneWidths.back();
  const int base_lane = base.t < right_edge ? -1 : base.t > left_edge ? road.lanes : base.lane;
  const long lane = base_lane + road.ownLaneId(d_lane);
  if (lane < 0 || lane >= translation.road.lanes) {
    reader.fail(position, fmt::format("dLane={} from lane {} leaves the road's {} driving lanes",
                                      reader.text(position, "dLane"), base_lane, translation.road.lanes));
  }
  const double offset = road.ownT(reader.optionalNumber(position, "offset").value_or(0.0));
  const double s = base.s + road.ownDs(reader.optionalNumber(position, "ds").value_or(0.0));
  // With ds, esmini counts a relative orientation from the file's reference line.
  Placement placement = onRoad(translation, position, s, road.laneCentreT(static_cast<int>(lane)) + offset,
                               road.reversed ? kPi : 0.0);
  placement.lane = static_cast<int>(lane);
  return placement;
}

/// Positions in the plane: WorldPosition, RelativeWorldPosition, RelativeObjectPosition.
Placement planePosition(Translation& translation, const pugi::xml_node& position) {
  const xml::Reader& reader = translation.reader;
  const CarriagewayRoad& road = translation.road;
  const std::string kind = position.name();
  Vec2 point;
  double heading = 0.0;  // absolute, of the reference (relative orientations count from it)
  // Heights: vsd-sumo is planar, a road user stands on its road.
  const auto height = reader.optionalNumber(position, kind == "WorldPosition" ? "z" : "dz");
  if (height && *height != 0.0) {
    translation.findings.note(reader.where(position), fmt::format("{} m of height: vsd-sumo is planar, not simulated",
                                                                  xml::number(*height)));
  }
  if (kind == "WorldPosition") {
    point = Vec2(reader.number(position, "x"), reader.number(position, "y"));
    requirePlanar(reader, position);
  } else {
    const Placement base = placementOf(translation, translation.entity(position, reader.text(position, "entityRef")));
    const Vec2 offset(reader.number(position, "dx"), reader.number(position, "dy"));
    heading = road.headingAt(base.s) + base.heading;
    const Vec2 along(std::cos(heading), std::sin(heading));
    const Vec2 across(-along.y(), along.x());
    point = road.point(base.s, base.t) +
            (kind == "RelativeObjectPosition" ? Vec2(offset.x() * along + offset.y() * across) : offset);
  }
  const auto [s, t] = road.coordinates(point);
  Placement placement = onRoad(translation, position, s, t);
  if (kind == "WorldPosition") {
    const auto h = reader.optionalNumber(position, "h");
    placement.heading = h ? std::remainder(*h - road.headingAt(s), 2.0 * kPi) : 0.0;
  } else {
    placement.heading = orientation(translation, position, s, heading - road.headingAt(s));
  }
  return placement;
}

Placement resolvePosition(Translation& translation, const pugi::xml_node& position_node) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node position = reader.choice(
      position_node, {"WorldPosition", "LanePosition", "RelativeLanePosition", "RoadPosition", "RelativeRoadPosition",
                      "RelativeObjectPosition", "RelativeWorldPosition"});
  const std::string kind = position.name();
  reader.requireSubset(position, {"Orientation"});
  if (kind == "LanePosition") return lanePosition(translation, position);
  if (kind == "RelativeLanePosition") return relativeLanePosition(translation, position);
  if (kind == "RoadPosition") return roadPosition(translation, position);
  if (kind == "RelativeRoadPosition") {
    const CarriagewayRoad& road = translation.road;
    const Placement base = placementOf(translation, translation.entity(position, reader.text(position, "entityRef")));
    return onRoad(translation, position, base.s + road.ownDs(reader.number(position, "ds")),
                  base.t + road.ownT(reader.number(position, "dt")), road.reversed ? kPi : 0.0);
  }
  return planePosition(translation, position);
}

double speedOf(Translation& translation, Entity& entity);

/// Where a LongitudinalDistanceAction puts its actor: its displacement; without one, behind the
/// referenced entity in OpenSCENARIO 1.1+ (the standard's default, esmini's too), on its own
/// side in 1.0 (which had no such attribute).
std::string displacementOf(const xml::Reader& reader, const pugi::xml_node& action) {
  if (action.attribute("displacement")) {
    return reader.oneOf(action, "displacement", {"any", "leadingReferencedEntity", "trailingReferencedEntity"});
  }
  const pugi::xml_node header = action.root().child("OpenSCENARIO").child("FileHeader");
  return header.attribute("revMinor").as_int() >= 1 ? "trailingReferencedEntity" : "any";
}

/// An Init LongitudinalDistanceAction (continuous="false", no DynamicConstraints): the actor
/// moves along the road to the gap (freespace) or distance from the referenced entity, as a
/// player executes it at once at t = 0.
void applyDistance(Translation& translation, Entity& entity, Placement& placement) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node action = entity.distanceAction;
  reader.requireSubset(action, {});
  if (reader.boolean(action, "continuous")) {
    reader.fail(action, "continuous=\"true\": the language does not keep a distance (in the Init: continuous=\"false\")");
  }
  Entity& other = translation.entity(action, reader.text(action, "entityRef"));
  const Placement base = placementOf(translation, other);
  const auto time_gap = reader.optionalNumber(action, "timeGap", NumberRange::atLeast(0.0));
  const auto distance = reader.optionalNumber(action, "distance", NumberRange::atLeast(0.0));
  if (time_gap.has_value() == distance.has_value()) reader.fail(action, "expected one of timeGap and distance");
  double gap = distance ? *distance : *time_gap * speedOf(translation, other);
  // freespace: between the bodies (their centres that gap plus half of each length apart);
  // else between the reference points, which positions give (OpenSCENARIO's distances).
  const bool freespace = reader.boolean(action, "freespace");
  const std::string side = displacementOf(reader, action);
  requireLaneFrame(reader, action, "the language places a road user along the road");
  const double sign = side == "trailingReferencedEntity" ? -1.0
                      : side == "leadingReferencedEntity" ? 1.0
                      : (placement.s + entity.centreAhead >= base.s + other.centreAhead ? 1.0 : -1.0);
  const double stretch = 1.0 - translation.road.curvatureAt(placement.s) * placement.t;
  placement.s = freespace ? base.s + other.centreAhead +
                                sign * (gap + (entity.length + other.length) / 2.0) / stretch - entity.centreAhead
                          : base.s + sign * gap / stretch;
  translation.findings.mapped(reader.where(action),
                              fmt::format("'{}' placed {} m ({}) {} '{}'", entity.name, xml::number(gap),
                                          freespace ? "bumper to bumper" : "reference points",
                                          sign > 0 ? "ahead of" : "behind", other.name));
  if (!entity.speedTarget) entity.speed = speedOf(translation, other);
}

/// Marks an entity as being resolved while it is (the check for positions or speeds that refer
/// back to themselves), also when resolving it fails: a later reference gets the real refusal.
class Resolving {
 public:
  explicit Resolving(bool& flag) : flag_(flag) { flag_ = true; }
  ~Resolving() { flag_ = false; }
  Resolving(const Resolving&) = delete;
  Resolving& operator=(const Resolving&) = delete;

 private:
  bool& flag_;
};

Placement placementOf(Translation& translation, Entity& entity) {
  if (entity.placement) return *entity.placement;
  if (!entity.position && entity.controller) {
    // esmini's SumoController brings traffic that SUMO drives from a route file of its own: such an
    // entity starts nowhere in the file.
    translation.reader.fail(
        translation.reader.root(),
        fmt::format("entity '{}' has no TeleportAction in the Init, only a controller ('{}', at {}): "
                    "vsd-sumo's road users start where the Init places them (traffic a controller "
                    "brings from elsewhere, such as a SUMO route file, is not imported){}",
                    entity.name, *entity.controller, entity.controllerWhere, kTryTheNetwork));
  }
  if (!entity.position) {
    translation.reader.fail(translation.reader.root(),
                            fmt::format("entity '{}' has no TeleportAction in the Init (where does it start?)", entity.name));
  }
  if (entity.placing) {
    translation.reader.fail(entity.position, fmt::format("the position of '{}' refers back to itself", entity.name));
  }
  const Resolving resolving(entity.placing);
  Placement placement = resolvePosition(translation, entity.position);
  if (entity.distanceAction) applyDistance(translation, entity, placement);
  entity.placement = placement;
  return *entity.placement;
}

double speedOf(Translation& translation, Entity& entity) {
  if (entity.speed) return *entity.speed;
  if (!entity.speedTarget) return 0.0;  // no speed in the Init: standing
  const xml::Reader& reader = translation.reader;
  if (entity.speeding) reader.fail(entity.speedTarget, fmt::format("the speed of '{}' refers back to itself", entity.name));
  const Resolving resolving(entity.speeding);
  const pugi::xml_node target = reader.choice(entity.speedTarget, {"AbsoluteTargetSpeed", "RelativeTargetSpeed"});
  double speed = 0.0;
  if (std::string(target.name()) == "AbsoluteTargetSpeed") {
    speed = reader.number(target, "value");
  } else {
    const double base = speedOf(translation, translation.entity(target, reader.text(target, "entityRef")));
    const std::string type = reader.oneOf(target, "speedTargetValueType", {"delta", "factor"});
    speed = type == "delta" ? base + reader.number(target, "value") : base * reader.number(target, "value");
  }
  entity.speed = speed;
  return speed;
}

}  // namespace

Placement fixedPlace(Translation& translation, const pugi::xml_node& position_node) {
  const xml::Reader& reader = translation.reader;
  const pugi::xml_node position = reader.choice(position_node, {"WorldPosition", "LanePosition", "RoadPosition"});
  const std::string kind = position.name();
  if (kind == "WorldPosition") {
    reader.requireSubset(position, {});
    return planePosition(translation, position);
  }
  reader.requireSubset(position, {"Orientation"});
  if (kind == "LanePosition") return lanePosition(translation, position);
  return roadPosition(translation, position);
}

InitCarriageway initCarriageway(const Translation& translation) {
  const CarriagewayRoad& road = translation.road;
  bool right_along = false;
  bool left_along = false;
  bool left_against = false;
  for (const Entity& entity : translation.entities) {
    if (!entity.isVehicle()) continue;  // a pedestrian's heading says no driving direction
    // A vehicle placed on the road by other than a lane (a road or world position) keeps the
    // right side; one placed relative to another follows it.
    if (entity.position.child("RoadPosition") || entity.position.child("WorldPosition")) right_along = true;
    const pugi::xml_node position = entity.position.child("LanePosition");
    if (!position) continue;
    try {  // a value that does not resolve counts as nothing; placing reports it
      const long lane_id = static_cast<long>(translation.reader.integer(position, "laneId", -100, 100));
      const double s = chainS(translation, position);
      const bool along = std::cos(orientation(translation, position, s, road.laneDirection(lane_id))) > 0.0;
      if (lane_id < 0) right_along = right_along || along;
      if (lane_id > 0) (along ? left_along : left_against) = true;
    } catch (const ConfigError&) {
    }
  }
  if (right_along || left_along == left_against) return InitCarriageway::Right;
  return left_along ? InitCarriageway::LeftAlong : InitCarriageway::LeftAgainst;
}

void placeEntities(Translation& translation) {
  for (auto& entity : translation.entities) {
    translation.findings.attempt([&] {
      placementOf(translation, entity);
      speedOf(translation, entity);
    });
  }
}

}  // namespace vsd::interop::osc
