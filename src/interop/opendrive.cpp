#include "vsd/interop/opendrive.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "xml_support.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {

/// Road marks make the lanes visible in viewers (esmini, netedit); they carry no geometry.
constexpr double kRoadMarkWidth = 0.12;  // m
/// Arcs are sampled into chords whose midpoints stay within a millimetre of the arc.
constexpr double kArcSampleSpacing = 0.5;  // m
/// Consecutive geometries must join (OpenDRIVE requires a continuous reference line).
constexpr double kJoinTolerance = 0.01;  // m
/// Bounds of a road the reader accepts, checked before any point is computed: the
/// longest road a YAML scenario can make (a 10 km region and two 10 km extensions)
/// fits with room to spare; 50 km of arcs are 100,000 points.
constexpr double kMaxRoadLength = 50'000.0;  // m, summed over the geometries
constexpr std::size_t kMaxGeometries = 100'000;
/// m: coordinates of SUMO networks (and of every road vsd-sumo writes) stay well inside.
constexpr double kMaxCoordinate = 1e7;
/// 1/m: a radius of at least 0.1 m.
constexpr double kMaxCurvature = 10.0;

void addRoadMark(pugi::xml_node lane, const char* type) {
  xml::child(lane, "roadMark",
             {{"sOffset", "0"}, {"type", type}, {"color", "standard"}, {"width", xml::number(kRoadMarkWidth)}});
}

void addPolynomial(pugi::xml_node parent, const char* name, const char* s_attribute, double constant) {
  xml::child(parent, name, {{s_attribute, "0"}, {"a", xml::number(constant)}, {"b", "0"}, {"c", "0"}, {"d", "0"}});
}

void writePlanView(pugi::xml_node road_node, const Polyline& centre) {
  pugi::xml_node plan_view = road_node.append_child("planView");
  double s = 0.0;
  for (std::size_t i = 0; i + 1 < centre.size(); ++i) {
    const Vec2 delta = centre[i + 1] - centre[i];
    const double length = delta.norm();
    pugi::xml_node geometry = xml::child(plan_view, "geometry",
                                         {{"s", xml::number(s)},
                                          {"x", xml::number(centre[i].x())},
                                          {"y", xml::number(centre[i].y())},
                                          {"hdg", xml::number(headingOf(delta))},
                                          {"length", xml::number(length)}});
    geometry.append_child("line");
    s += length;
  }
}

void writeLanes(pugi::xml_node road_node, const road::RoadGeometry& road) {
  pugi::xml_node lanes = road_node.append_child("lanes");
  // Lane 0 (the centre lane) sits on the left edge of the road; the road is centred on the reference line.
  addPolynomial(lanes, "laneOffset", "s", road.halfWidth());
  pugi::xml_node section = xml::child(lanes, "laneSection", {{"s", "0"}});
  pugi::xml_node centre_lane = xml::child(section.append_child("center"), "lane",
                                          {{"id", "0"}, {"type", "none"}, {"level", "false"}});
  // The 1.6 XSD requires a width record for the centre lane as well; it has none (0 m).
  addPolynomial(centre_lane, "width", "sOffset", 0.0);
  addRoadMark(centre_lane, "solid");
  pugi::xml_node right = section.append_child("right");
  for (int id = -1; id >= -road.lanes; --id) {
    pugi::xml_node lane = xml::child(right, "lane", {{"id", std::to_string(id)}, {"type", "driving"}, {"level", "false"}});
    addPolynomial(lane, "width", "sOffset", road.laneWidthOf(road.lanes + id));  // id -1: the leftmost lane
    addRoadMark(lane, id == -road.lanes ? "solid" : "broken");
  }
}

}  // namespace

int openDriveLaneId(int lane, int lanes) { return -(lanes - lane); }

std::optional<int> laneFromOpenDrive(int lane_id, int lanes) {
  if (lane_id > -1 || lane_id < -lanes) return std::nullopt;
  return lanes + lane_id;
}

std::string openDriveText(const road::RoadGeometry& road, const std::string& name) {
  if (road.centre.size() < 2) throw ConfigError(fmt::format("road '{}': needs at least 2 points", name));
  for (std::size_t i = 0; i + 1 < road.centre.size(); ++i) {
    if ((road.centre[i + 1] - road.centre[i]).norm() <= 0.0) {
      throw ConfigError(fmt::format("road '{}': points {} and {} coincide (no OpenDRIVE geometry has length 0)", name,
                                    i, i + 1));
    }
  }
  pugi::xml_document document;
  pugi::xml_node root = document.append_child("OpenDRIVE");
  const auto [lo, hi] = road.bounds();
  xml::child(root, "header",
             {{"revMajor", "1"},
              {"revMinor", "6"},
              {"name", name},
              {"north", xml::number(hi.y())},
              {"south", xml::number(lo.y())},
              {"east", xml::number(hi.x())},
              {"west", xml::number(lo.x())},
              {"vendor", "vsd-sumo"}});
  pugi::xml_node road_node = xml::child(
      root, "road",
      {{"name", name}, {"length", xml::number(polylineLength(road.centre))}, {"id", "1"}, {"junction", "-1"}, {"rule", "RHT"}});
  pugi::xml_node type = xml::child(road_node, "type", {{"s", "0"}, {"type", "unknown"}});
  xml::child(type, "speed", {{"max", xml::number(road.speedLimit)}, {"unit", "m/s"}});
  writePlanView(road_node, road.centre);
  writeLanes(road_node, road);
  return xml::toText(document);
}

void writeOpenDrive(const road::RoadGeometry& road, const std::string& name, const fs::path& file) {
  writeTextFileAtomically(file, openDriveText(road, name));
}

// --- reading --------------------------------------------------------------------------

namespace {

/// Appends the points of one geometry (without its start point, which the caller has).
void appendGeometry(const xml::Reader& reader, const pugi::xml_node& geometry, Polyline& points) {
  const NumberRange coordinate = NumberRange::closed(-kMaxCoordinate, kMaxCoordinate);
  const Vec2 start(reader.number(geometry, "x", coordinate), reader.number(geometry, "y", coordinate));
  const double heading = reader.number(geometry, "hdg", NumberRange::closed(-1e3, 1e3));
  const double length = reader.number(geometry, "length", NumberRange::aboveUpTo(0.0, kMaxRoadLength));
  if (!points.empty() && (points.back() - start).norm() > kJoinTolerance) {
    reader.fail(geometry, fmt::format("starts at ({}, {}), {:.3f} m from where the previous geometry ends (expected a "
                                      "continuous reference line)",
                                      xml::number(start.x()), xml::number(start.y()), (points.back() - start).norm()));
  }
  if (points.empty()) points.push_back(start);
  else points.back() = start;  // the file's start point is exact; the computed end is rounded
  const pugi::xml_node shape = reader.choice(geometry, {"line", "arc"});
  if (std::string(shape.name()) == "line") {
    points.push_back(start + length * headingVector(heading));
    return;
  }
  const double curvature = reader.number(shape, "curvature", NumberRange::closed(-kMaxCurvature, kMaxCurvature));
  const int chords = std::max(1, static_cast<int>(std::ceil(length / kArcSampleSpacing)));
  for (int i = 1; i <= chords; ++i) {
    const double s = length * i / chords;
    if (std::abs(curvature) < 1e-12) {
      points.push_back(start + s * headingVector(heading));
      continue;
    }
    const double radius = 1.0 / curvature;
    const double turned = heading + curvature * s;
    points.push_back(start + radius * Vec2(std::sin(turned) - std::sin(heading), std::cos(heading) - std::cos(turned)));
  }
}

double constantPolynomial(const xml::Reader& reader, const pugi::xml_node& node) {
  for (const char* coefficient : {"b", "c", "d"}) {
    if (reader.number(node, coefficient) != 0.0) {
      reader.fail(node, fmt::format("{}=\"{}\": only constant values (b = c = d = 0) are in the supported subset",
                                    coefficient, reader.text(node, coefficient)));
    }
  }
  return reader.number(node, "a");
}

/// Widths of the right lanes (constant), lane 0 (the rightmost) first.
std::vector<double> readRightLanes(const xml::Reader& reader, const pugi::xml_node& section) {
  reader.requireSubset(section, {"center", "right", "userData"});
  const pugi::xml_node right = reader.only(section, "right");
  reader.requireSubset(right, {"lane", "userData"});
  int lanes = 0;
  std::vector<double> widths;
  for (const pugi::xml_node& lane : right.children("lane")) {
    reader.requireSubset(lane, {"link", "width", "roadMark", "userData"});
    if (lanes == scenario_bounds::kMaxLanes) {
      reader.fail(lane, fmt::format("more than {} lanes (the most a scenario may have)", scenario_bounds::kMaxLanes));
    }
    const auto id = reader.integer(lane, "id", -scenario_bounds::kMaxLanes, scenario_bounds::kMaxLanes);
    if (id != -(lanes + 1)) reader.fail(lane, fmt::format("id=\"{}\": expected {} (right lanes numbered -1, -2, ... from the centre)", reader.text(lane, "id"), -(lanes + 1)));
    reader.oneOf(lane, "type", {"driving"});
    const double lane_width = constantPolynomial(reader, reader.only(lane, "width"));
    if (!(lane_width > 0.5 && scenario_bounds::kLaneWidth.contains(lane_width))) {
      reader.fail(lane, fmt::format("width {} m: expected > 0.5 m and {} m", xml::number(lane_width),
                                    scenario_bounds::kLaneWidth.text()));
    }
    widths.insert(widths.begin(), lane_width);  // ids run from the reference line outwards
    ++lanes;
  }
  if (lanes == 0) reader.fail(right, "expected at least one <lane>");
  return widths;
}

/// The number of geometries and their summed length, bounded before any point is made.
void requireBoundedPlanView(const xml::Reader& reader, const pugi::xml_node& plan_view) {
  std::size_t count = 0;
  double total = 0.0;
  for (const pugi::xml_node& geometry : plan_view.children("geometry")) {
    if (++count > kMaxGeometries) {
      reader.fail(geometry, fmt::format("more than {} geometries (the most the reader accepts)", kMaxGeometries));
    }
    total += reader.number(geometry, "length", NumberRange::aboveUpTo(0.0, kMaxRoadLength));
    if (total > kMaxRoadLength) {
      reader.fail(geometry, fmt::format("the road is longer than {} m here (the longest the reader accepts; a "
                                        "scenario's road is at most {} m)",
                                        xml::number(kMaxRoadLength), xml::number(3 * scenario_bounds::kMaxExtent)));
    }
  }
}

}  // namespace

OpenDriveRoad readOpenDrive(const fs::path& file) {
  const xml::Reader reader(file, read_limits::kRoadNetwork);
  const pugi::xml_node root = reader.root();
  if (std::string(root.name()) != "OpenDRIVE") reader.fail(root, "expected the root element <OpenDRIVE>");
  reader.requireSubset(root, {"header", "road", "userData"});
  const pugi::xml_node header = reader.only(root, "header");
  reader.requireSubset(header, {"geoReference", "userData"});
  if (reader.number(header, "revMajor") != 1.0) reader.fail(header, "revMajor: expected 1");
  const pugi::xml_node road_node = reader.only(root, "road");
  reader.requireSubset(road_node, {"link", "type", "planView", "lanes", "userData"});
  if (const auto rule = reader.optionalText(road_node, "rule"); rule && *rule != "RHT") {
    reader.fail(road_node, fmt::format("rule=\"{}\": only right-hand traffic (RHT) is in the supported subset", *rule));
  }

  OpenDriveRoad result;
  result.id = reader.text(road_node, "id");
  road::RoadGeometry& road = result.geometry;
  const pugi::xml_node plan_view = reader.only(road_node, "planView");
  reader.requireSubset(plan_view, {"geometry"});
  requireBoundedPlanView(reader, plan_view);
  for (const pugi::xml_node& geometry : plan_view.children("geometry")) appendGeometry(reader, geometry, road.centre);
  if (road.centre.size() < 2) reader.fail(plan_view, "expected at least one <geometry>");
  road.regionBegin = 0;
  road.regionEnd = road.centre.size();

  const pugi::xml_node lanes = reader.only(road_node, "lanes");
  reader.requireSubset(lanes, {"laneOffset", "laneSection", "userData"});
  double lane_offset = 0.0;
  if (lanes.child("laneOffset")) {
    const pugi::xml_node offset = reader.only(lanes, "laneOffset");
    if (reader.number(offset, "s") != 0.0) reader.fail(offset, "s: expected 0 (one constant lane offset)");
    lane_offset = constantPolynomial(reader, offset);
  }
  road.laneWidths = readRightLanes(reader, reader.only(lanes, "laneSection"));
  road.lanes = static_cast<int>(road.laneWidths.size());
  // vsd-sumo spreads lanes symmetrically around the reference line (SUMO spreadType=center).
  if (std::abs(lane_offset - road.halfWidth()) > 1e-6) {
    reader.fail(lanes, fmt::format("laneOffset {} m: the supported subset centres the lanes on the reference line "
                                   "(expected half the lanes' width, {} m)",
                                   xml::number(lane_offset), xml::number(road.halfWidth())));
  }
  road.speedLimit = scenario::RoadSpec{}.speedLimit;
  for (const pugi::xml_node& type : road_node.children("type")) {
    reader.requireSubset(type, {"speed", "userData"});
    if (const pugi::xml_node speed = type.child("speed")) {
      const std::string unit = reader.optionalText(speed, "unit").value_or("m/s");
      const double factor = unit == "m/s" ? 1.0 : unit == "km/h" ? 1.0 / 3.6 : unit == "mph" ? 0.44704 : -1.0;
      if (factor < 0.0) reader.fail(speed, fmt::format("unit=\"{}\": expected m/s, km/h or mph", unit));
      road.speedLimit = reader.number(speed, "max", NumberRange::aboveUpTo(0.0, 1000.0)) * factor;
    }
  }
  return result;
}

RoadCoordinate toRoadCoordinate(const road::RoadGeometry& road, const Vec2& point) {
  const auto projection = MeasuredPolyline(road.centre).project(point);
  return {projection.arcLength, projection.lateralOffset};
}

Vec2 fromRoadCoordinate(const road::RoadGeometry& road, const RoadCoordinate& coordinate) {
  const MeasuredPolyline centre(road.centre);
  const double heading = centre.headingAt(coordinate.s);
  return centre.pointAt(coordinate.s) + coordinate.t * Vec2(-std::sin(heading), std::cos(heading));
}

}  // namespace vsd::interop
