#include "osc_road.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

namespace {

/// m of reference line: a road's length, summed over its geometries.
constexpr NumberRange kLength = NumberRange::aboveUpTo(0.0, 50'000.0);
/// Widths and positions of consecutive geometries must join within this (m, rad).
constexpr double kJoinTolerance = 1e-3;

/// The plan view: lines or arcs of one curvature, joined end to start.
void readPlanView(const xml::Reader& reader, const pugi::xml_node& road, CarriagewayRoad& result) {
  const pugi::xml_node plan = reader.only(road, "planView");
  reader.requireSubset(plan, {"geometry"});
  bool first = true;
  for (const pugi::xml_node& geometry : plan.children("geometry")) {
    const pugi::xml_node shape = reader.choice(geometry, {"line", "arc"});
    const double curvature = std::string(shape.name()) == "arc" ? reader.number(shape, "curvature", NumberRange::closed(-1.0, 1.0)) : 0.0;
    const double s = reader.number(geometry, "s", NumberRange::atLeast(0.0));
    const Vec2 start(reader.number(geometry, "x"), reader.number(geometry, "y"));
    const double heading = reader.number(geometry, "hdg");
    const double length = reader.number(geometry, "length", kLength);
    if (first) {
      result.start = start;
      result.heading = heading;
      result.curvature = curvature;
      first = false;
    } else if (std::abs(curvature - result.curvature) > 1e-9 || std::abs(s - result.length) > kJoinTolerance ||
               (result.point(s, 0.0) - start).norm() > kJoinTolerance ||
               std::abs(std::remainder(result.headingAt(s) - heading, 2.0 * kPi)) > kJoinTolerance) {
      reader.fail(geometry, "a second curvature: the scenario language's roads are one line or one arc "
                            "(docs/openscenario-import.md \"Roads\")");
    }
    result.length = s + length;
  }
  if (first) reader.fail(plan, "expected at least one <geometry>");
}

double constantWidth(const xml::Reader& reader, const pugi::xml_node& lane) {
  reader.requireSubset(lane, {"link", "width", "roadMark", "speed", "userData", "height", "material"});
  const pugi::xml_node width = reader.only(lane, "width");
  for (const char* coefficient : {"b", "c", "d"}) {
    if (reader.optionalNumber(width, coefficient).value_or(0.0) != 0.0) {
      reader.fail(width, "a width that varies along the road: the scenario language's lanes have one width");
    }
  }
  if (reader.optionalNumber(width, "sOffset").value_or(0.0) != 0.0) reader.fail(width, "sOffset: expected 0");
  return reader.number(width, "a", NumberRange::atLeast(0.0));
}

/// The right side: [inner non-driving lanes] driving lanes [shoulder/stop lanes] [others].
void readRightLanes(const xml::Reader& reader, const pugi::xml_node& right, CarriagewayRoad& result) {
  reader.requireSubset(right, {"lane"});
  enum class Part { Inner, Driving, Shoulder, Outer } part = Part::Inner;
  for (long id = -1;; --id) {
    pugi::xml_node lane;
    for (const pugi::xml_node& candidate : right.children("lane")) {
      if (reader.integer(candidate, "id", -100, -1) == id) lane = candidate;
    }
    if (!lane) break;
    const double width = constantWidth(reader, lane);
    const std::string type = reader.text(lane, "type");
    if (type == "driving") {
      if (part == Part::Shoulder || part == Part::Outer) {
        reader.fail(lane, "a second run of driving lanes: the scenario language has one carriageway");
      }
      if (part == Part::Driving && std::abs(width - result.laneWidth) > 1e-9) {
        reader.fail(lane, fmt::format("width {} m, the lanes before are {} m: the language's lanes have one width",
                                      xml::number(width), xml::number(result.laneWidth)));
      }
      if (part == Part::Inner) result.innermostLaneId = static_cast<int>(id);
      part = Part::Driving;
      result.laneWidth = width;
      ++result.lanes;
    } else if (part == Part::Inner) {
      result.shoulderLeft += width;
    } else if (part != Part::Outer && (type == "shoulder" || type == "stop")) {
      part = Part::Shoulder;
      result.shoulderRight += width;
    } else {
      part = Part::Outer;
    }
  }
  if (result.lanes == 0) reader.fail(right, "no driving lane on the right side (negative lane ids)");
  result.innerT = -result.shoulderLeft;
}

void readLanes(const xml::Reader& reader, const pugi::xml_node& road, CarriagewayRoad& result, Findings& findings) {
  const pugi::xml_node lanes = reader.only(road, "lanes");
  reader.requireSubset(lanes, {"laneSection", "laneOffset"});
  for (const pugi::xml_node& offset : lanes.children("laneOffset")) {
    for (const char* coefficient : {"a", "b", "c", "d"}) {
      if (reader.optionalNumber(offset, coefficient).value_or(0.0) != 0.0) {
        reader.fail(offset, "a lane offset: the scenario language's lanes lie symmetric about its centre line");
      }
    }
  }
  const pugi::xml_node section = reader.only(lanes, "laneSection");
  reader.requireSubset(section, {"left", "center", "right", "userData"});
  if (section.child("left")) {
    findings.note(reader.where(section.child("left")),
                  "the left side (lanes driven against the reference line) is not part of vsd-sumo's road");
  }
  readRightLanes(reader, reader.only(section, "right"), result);
}

}  // namespace

int CarriagewayRoad::languageLane(long lane_id, const std::string& where) const {
  const long outermost = innermostLaneId - lanes + 1;
  if (lane_id > innermostLaneId || lane_id < outermost) {
    throw ConfigError(fmt::format("{}: laneId {}: expected a driving lane of the road's right side, {} .. {} "
                                  "(lanes driven against the reference line are not part of vsd-sumo's road)",
                                  where, lane_id, innermostLaneId, outermost));
  }
  return static_cast<int>(lane_id - outermost);
}

double CarriagewayRoad::laneCentreT(int lane) const { return innerT - (lanes - lane - 0.5) * laneWidth; }

int CarriagewayRoad::nearestLane(double t) const {
  const long lane = std::lround((t - laneCentreT(0)) / laneWidth);
  return static_cast<int>(std::clamp<long>(lane, 0, lanes - 1));
}

Vec2 CarriagewayRoad::point(double s, double t) const {
  const double h = headingAt(s);
  Vec2 reference;
  if (std::abs(curvature) < 1e-12) {
    reference = start + s * Vec2(std::cos(heading), std::sin(heading));
  } else {
    const double r = 1.0 / curvature;
    reference = start + Vec2(r * (std::sin(h) - std::sin(heading)), -r * (std::cos(h) - std::cos(heading)));
  }
  return reference + t * Vec2(-std::sin(h), std::cos(h));
}

std::pair<double, double> CarriagewayRoad::coordinates(const Vec2& p) const {
  const Vec2 direction(std::cos(heading), std::sin(heading));
  const Vec2 normal(-direction.y(), direction.x());
  if (std::abs(curvature) < 1e-12) {
    const Vec2 d = p - start;
    return {d.dot(direction), d.dot(normal)};
  }
  const double r = 1.0 / curvature;  // signed: the centre of the circle lies r along the left normal
  const Vec2 centre = start + r * normal;
  const Vec2 from = start - centre;
  const Vec2 radial = p - centre;
  // Angle swept from the start in the direction of travel (counter-clockwise when turning left).
  double swept = std::atan2(from.x() * radial.y() - from.y() * radial.x(), from.dot(radial));
  if (curvature < 0) swept = -swept;
  // Points a little before the start keep a small negative s rather than wrapping round.
  const double spare = std::max(0.0, 2.0 * kPi - length / std::abs(r)) / 2.0;
  if (swept < -spare) swept += 2.0 * kPi;
  return {swept * std::abs(r), r - (r > 0 ? 1.0 : -1.0) * radial.norm()};
}

CarriagewayRoad readCarriagewayRoad(const std::filesystem::path& file, Findings& findings) {
  xml::Reader reader(file, read_limits::kRoadNetwork);
  const pugi::xml_node root = reader.root();
  if (std::string(root.name()) != "OpenDRIVE") reader.fail(root, "expected the root element <OpenDRIVE>");
  reader.requireSubset(root, {"header", "road", "controller", "junction"});
  if (root.child("junction")) reader.fail(root.child("junction"), "junctions: the scenario language has one road");
  const pugi::xml_node road = reader.only(root, "road");
  reader.requireSubset(road, {"link", "type", "planView", "elevationProfile", "lateralProfile", "lanes", "objects",
                              "signals", "userData", "surface"});
  CarriagewayRoad result;
  result.file = file;
  result.id = reader.text(road, "id");
  if (reader.optionalText(road, "rule").value_or("RHT") != "RHT") {
    reader.fail(road, "rule: only right-hand traffic (RHT) maps onto the language's lanes");
  }
  readPlanView(reader, road, result);
  if (std::abs(result.length - reader.number(road, "length", kLength)) > kJoinTolerance) {
    reader.fail(road, "length: differs from the sum of its geometries' lengths");
  }
  readLanes(reader, road, result, findings);
  for (const char* planar : {"elevationProfile", "lateralProfile"}) {
    const pugi::xml_node profile = road.child(planar);
    if (profile && profile.first_child()) {
      findings.note(reader.where(profile), "vsd-sumo is planar: heights and banking are not simulated");
    }
  }
  for (const char* unused : {"objects", "signals"}) {
    const pugi::xml_node node = road.child(unused);
    if (node && node.first_child()) findings.note(reader.where(node), "not simulated (the scenario language has no road furniture)");
  }
  return result;
}

}  // namespace vsd::interop::osc
