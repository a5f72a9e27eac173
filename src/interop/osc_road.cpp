#include "osc_road.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <stdexcept>

#include "vsd/core/files.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/road/road_geometry.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

namespace {

/// m of reference line: a road's length, summed over its geometries.
constexpr NumberRange kLength = NumberRange::aboveUpTo(0.0, 50'000.0);
/// Widths and positions of consecutive geometries must join within this (m, rad).
constexpr double kJoinTolerance = 1e-3;

/// m between a spiral's tabulated points; Simpson's rule over half of it is exact to far
/// below a micrometre for the curvatures of roads.
constexpr double kSpiralStep = 0.5;
/// m between the reference line's samples for coordinates() (chord error below 1 mm up to
/// a curvature of 0.03 1/m, a radius of 33 m; tighter curves are sampled more densely).
constexpr double kSampleSpacing = 0.5;

/// Simpson's rule for the unit tangent of a curve of heading h(u) over [a, b].
template <typename Heading>
Vec2 integrateTangent(const Heading& h, double a, double b) {
  const double m = 0.5 * (a + b);
  const auto tangent = [&](double u) { return Vec2(std::cos(h(u)), std::sin(h(u))); };
  return (b - a) / 6.0 * (tangent(a) + 4.0 * tangent(m) + tangent(b));
}


/// The plan view of a road that starts `offset` m along the chain (0: the first road):
/// geometries joined end to start (within kJoinTolerance), in order of s, appended to `result`;
/// a later road's first geometry must continue the road before it.
void readPlanView(const xml::Reader& reader, const pugi::xml_node& road, CarriagewayRoad& result, double offset) {
  const pugi::xml_node plan = reader.only(road, "planView");
  reader.requireSubset(plan, {"geometry"});
  const std::size_t first = result.geometries.size();
  for (const pugi::xml_node& node : plan.children("geometry")) {
    PlanGeometry geometry = readPlanGeometry(reader, node, offset);
    if (result.geometries.empty()) {
      result.start = geometry.point(0.0);
      result.heading = geometry.heading(0.0);
      result.turnBefore.push_back(0.0);
    } else {
      const PlanGeometry& before = result.geometries.back();
      const double gap = (before.point(before.length()) - geometry.point(0.0)).norm();
      const double kink = std::remainder(before.heading(before.length()) - geometry.heading(0.0), 2.0 * kPi);
      const bool joins = std::abs(geometry.s() - result.length) <= kJoinTolerance && gap <= kJoinTolerance &&
                         std::abs(kink) <= kJoinTolerance;
      if (!joins && result.geometries.size() == first) {
        reader.fail(node, fmt::format("road '{}' does not start where road '{}' ends, which links to it (s {} m, a gap "
                                      "of {:.3g} m, a kink of {:.3g} rad; expected s 0 and at most {})",
                                      reader.text(road, "id"), result.pieces.back().id,
                                      xml::number(geometry.s() - offset), gap, kink, kJoinTolerance));
      }
      if (!joins) {
        reader.fail(node, fmt::format("does not continue the geometry before it (s {} m after {} m of road, a gap of "
                                      "{:.3g} m, a kink of {:.3g} rad; expected at most {})",
                                      xml::number(geometry.s() - offset), xml::number(result.length - offset), gap,
                                      kink, kJoinTolerance));
      }
      result.turnBefore.push_back(result.turnBefore.back() + before.turn(before.length()));
    }
    result.length = geometry.s() + geometry.length();
    result.geometries.push_back(std::move(geometry));
  }
  if (result.geometries.size() == first) reader.fail(plan, "expected at least one <geometry>");
}

/// Lines only, or arcs of one curvature: the language's arc road, by closed formulas.
void classifyCurvature(CarriagewayRoad& road) {
  using Kind = PlanGeometry::Kind;
  const PlanGeometry& first = road.geometries.front();
  road.curvature = first.kind() == Kind::Arc ? first.curvature(0.0) : 0.0;
  road.oneCurvature = true;
  for (const PlanGeometry& geometry : road.geometries) {
    const bool same = (geometry.kind() == Kind::Line && road.curvature == 0.0) ||
                      (geometry.kind() == Kind::Arc && std::abs(geometry.curvature(0.0) - road.curvature) <= 1e-9);
    if (!same) road.oneCurvature = false;
  }
  if (road.oneCurvature) return;
  road.curvature = 0.0;
  Polyline points;
  for (const PlanGeometry& geometry : road.geometries) {
    const double spacing = vsd::road::chordSpacing(geometry.largestCurvature(), 1e-3, kSampleSpacing);
    const auto steps = static_cast<int>(std::ceil(geometry.length() / spacing));
    for (int i = points.empty() ? 0 : 1; i <= steps; ++i) {
      const double ds = geometry.length() * i / steps;
      points.push_back(geometry.point(ds));
      road.sampleS.push_back(geometry.s() + ds);
    }
  }
  road.referenceSamples = MeasuredPolyline(std::move(points));
}

/// A lane's width, which must be one constant along the road: one <width> from sOffset 0, or
/// several that all give the same constant (esmini's velodrome repeats its entries).
double constantWidth(const xml::Reader& reader, const pugi::xml_node& lane) {
  reader.requireSubset(lane, {"link", "width", "roadMark", "speed", "userData", "height", "material"});
  std::optional<double> constant;
  for (const pugi::xml_node& width : lane.children("width")) {
    for (const char* coefficient : {"b", "c", "d"}) {
      if (reader.optionalNumber(width, coefficient).value_or(0.0) != 0.0) {
        reader.fail(width, "a width that varies along the road: the scenario language's lanes keep their width");
      }
    }
    const double a = reader.number(width, "a", NumberRange::atLeast(0.0));
    if (!constant) {
      if (reader.optionalNumber(width, "sOffset").value_or(0.0) != 0.0) reader.fail(width, "sOffset: expected 0");
      constant = a;
    } else if (a != *constant) {
      reader.fail(width, fmt::format("a = {} m after {} m: a width that changes along the road (the scenario "
                                     "language's lanes keep their width)",
                                     xml::number(a), xml::number(*constant)));
    }
  }
  if (!constant) reader.fail(lane, "expected a <width>");
  return *constant;
}

/// One side of the reference line: [inner non-driving lanes] driving lanes [shoulder/stop
/// lanes] [others], read outwards from the reference line (`sign` -1: the right side, ids
/// -1, -2, ...; +1: the left side, ids 1, 2, ...), as a carriageway driven along the
/// reference line: lane 0 is the rightmost in that direction.
DrivenRun readRun(const xml::Reader& reader, const pugi::xml_node& side, int sign) {
  reader.requireSubset(side, {"lane"});
  DrivenRun run;
  enum class Part { Inner, Driving, Shoulder, Outer } part = Part::Inner;
  for (long id = sign;; id += sign) {
    pugi::xml_node lane;
    for (const pugi::xml_node& candidate : side.children("lane")) {
      if (reader.integer(candidate, "id", sign < 0 ? -100 : 1, sign < 0 ? -1 : 100) == id) lane = candidate;
    }
    if (!lane) break;
    // Lanes beyond the shoulders are not part of the road: their widths are not read.
    const auto width_of = [&reader, &lane] { return constantWidth(reader, lane); };
    const std::string type = reader.text(lane, "type");
    if (type == "driving") {
      if (part == Part::Shoulder || part == Part::Outer) {
        reader.fail(lane, "a second run of driving lanes: the scenario language has one carriageway");
      }
      const double width = width_of();
      if (!(width > 0.5)) {
        reader.fail(lane, fmt::format("width {} m: expected a driving lane wider than 0.5 m", xml::number(width)));
      }
      if (part == Part::Inner) run.innermostLaneId = static_cast<int>(id);
      part = Part::Driving;
      // Outwards is rightwards on the right side (lane 0 is the last read), leftwards on the left.
      run.laneWidths.insert(sign < 0 ? run.laneWidths.begin() : run.laneWidths.end(), width);
    } else if (part == Part::Inner) {
      run.innerShoulder += width_of();
    } else if (part != Part::Outer && (type == "shoulder" || type == "stop")) {
      part = Part::Shoulder;
      run.outerShoulder += width_of();
    } else {
      part = Part::Outer;
    }
  }
  if (run.laneWidths.empty()) {
    reader.fail(side, sign < 0 ? "no driving lane on the right side (negative lane ids)"
                               : "no driving lane on the left side (positive lane ids)");
  }
  return run;
}

/// Makes `run` the road's carriageway (`sign` as readRun's).
void takeRun(CarriagewayRoad& result, const DrivenRun& run, int sign) {
  result.lanes = static_cast<int>(run.laneWidths.size());
  result.laneWidths = run.laneWidths;
  result.innermostLaneId = run.innermostLaneId;
  const double driving = std::accumulate(run.laneWidths.begin(), run.laneWidths.end(), 0.0);
  // The driving lanes' left edge; the inner lanes lie left of a right-side run, right of a left-side one.
  result.innerT = result.laneOffset + (sign < 0 ? -run.innerShoulder : run.innerShoulder + driving);
  result.shoulderLeft = sign < 0 ? run.innerShoulder : run.outerShoulder;
  result.shoulderRight = sign < 0 ? run.outerShoulder : run.innerShoulder;
  result.leftCarriageway = sign > 0;
}

/// The left side's driving lanes 1, 2, ... while they continue the right side's carriageway
/// across the reference line (lane -1 driving), then its shoulder/stop lanes.
/// Anything else leaves them apart (adjoiningLeftLanes 0): a median. The
/// left side is not part of the road otherwise, so nothing on it refuses the road: a lane
/// the language could not read (a varying width, an unknown element) ends the run there,
/// and one among the adjoining driving lanes leaves them all apart.
void readAdjoiningLeftLanes(const xml::Reader& reader, const pugi::xml_node& left, CarriagewayRoad& result) {
  if (result.innermostLaneId != -1) return;  // a median on the right side
  const auto lane_with_id = [&left](long id) {
    for (const pugi::xml_node& candidate : left.children("lane")) {
      if (candidate.attribute("id").as_llong(0) == id) return candidate;
    }
    return pugi::xml_node();
  };
  bool shoulder = false;
  for (long id = 1;; ++id) {
    const pugi::xml_node lane = lane_with_id(id);
    if (!lane) return;
    const std::string type = lane.attribute("type").value();
    const bool driving = type == "driving" && !shoulder;
    if (!driving && !(result.adjoiningLeftLanes > 0 && (type == "shoulder" || type == "stop"))) return;
    double width = 0.0;
    try {
      width = constantWidth(reader, lane);
    } catch (const ConfigError&) {
      if (driving) {
        result.adjoiningLeftLanes = 0;
        result.adjoiningLeftWidths.clear();
      }
      return;
    }
    if (driving && !(width > 0.5)) {
      result.adjoiningLeftLanes = 0;
      result.adjoiningLeftWidths.clear();
      return;
    }
    if (driving) {
      ++result.adjoiningLeftLanes;
      result.adjoiningLeftWidths.push_back(width);
    } else {
      shoulder = true;
      result.adjoiningLeftShoulder += width;
    }
  }
}

/// The lanes of one <laneSection> into `result`'s lane fields (readLanes).
void readSection(const xml::Reader& reader, const pugi::xml_node& section, CarriagewayRoad& result) {
  reader.requireSubset(section, {"left", "center", "right", "userData"});
  if (result.leftHandTraffic) {
    // Left-hand traffic drives the left side along the reference line: that is the road.
    takeRun(result, readRun(reader, reader.only(section, "left"), +1), +1);
    if (const pugi::xml_node right = section.child("right")) result.otherSide = reader.where(right);
    return;
  }
  takeRun(result, readRun(reader, reader.only(section, "right"), -1), -1);
  const pugi::xml_node left = section.child("left");
  if (!left) return;
  result.otherSide = reader.where(left);
  readAdjoiningLeftLanes(reader, left, result);
  // The left side as a carriageway of its own, for files that drive it along the reference
  // line (esmini's left-hand traffic "by heading"); what keeps it from being one is kept.
  try {
    result.leftRun = readRun(reader, left, +1);
  } catch (const ConfigError& error) {
    result.leftRunProblem = error.what();
  }
}

/// Widths and offsets of lanes in two sections are the same within kJoinTolerance (map tools
/// write 3.4999999 for 3.5).
bool near(double a, double b) { return std::abs(a - b) <= kJoinTolerance; }

bool nearWidths(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), near);
}

bool sameRun(const DrivenRun& a, const DrivenRun& b) {
  return a.innermostLaneId == b.innermostLaneId && nearWidths(a.laneWidths, b.laneWidths) &&
         near(a.innerShoulder, b.innerShoulder) && near(a.outerShoulder, b.outerShoulder);
}

/// A section's driving lanes (ids, widths) and shoulders, as messages name them: what must stay
/// the same along vsd-sumo's road. Lanes beyond the shoulders are not part of it and may differ.
std::string sectionLayout(const CarriagewayRoad& lanes) {
  std::vector<std::string> widths;
  for (const double width : lanes.laneWidths) widths.push_back(xml::number(width));
  return fmt::format("driving lanes {} .. {} of {} m, shoulders {} m left and {} m right", lanes.innermostLaneId,
                     lanes.innermostLaneId + (lanes.leftCarriageway ? 1 : -1) * (lanes.lanes - 1),
                     fmt::join(widths, ", "), xml::number(lanes.shoulderLeft), xml::number(lanes.shoulderRight));
}

bool sameLanes(const CarriagewayRoad& a, const CarriagewayRoad& b) {
  return a.lanes == b.lanes && a.innermostLaneId == b.innermostLaneId && a.leftCarriageway == b.leftCarriageway &&
         nearWidths(a.laneWidths, b.laneWidths) && near(a.innerT, b.innerT) && near(a.shoulderLeft, b.shoulderLeft) &&
         near(a.shoulderRight, b.shoulderRight);
}

/// The other side's lanes the scenario may drive (joined lanes, or the left side's run): they
/// matter only if it does (CarriagewayRoad::leftSideChanges).
bool sameLeftSide(const CarriagewayRoad& a, const CarriagewayRoad& b) {
  return a.adjoiningLeftLanes == b.adjoiningLeftLanes && nearWidths(a.adjoiningLeftWidths, b.adjoiningLeftWidths) &&
         near(a.adjoiningLeftShoulder, b.adjoiningLeftShoulder) && a.leftRun.has_value() == b.leftRun.has_value() &&
         (!a.leftRun || sameRun(*a.leftRun, *b.leftRun));
}

/// A driving lane must go on as the same lane from one section to the next: a <predecessor>
/// link of a later section's lane, or a <successor> link of an earlier one's, naming another id
/// would move traffic across lanes. `sign`: the side that is the road (-1: right, +1: left).
void checkLaneLinks(const xml::Reader& reader, const pugi::xml_node& section, int sign, const char* kind) {
  const std::string other = std::string(kind) == "predecessor" ? "continues lane {} of the section before"
                                                               : "goes on as lane {} of the section after";
  for (const pugi::xml_node& side : section.children(sign < 0 ? "right" : "left")) {
    for (const pugi::xml_node& lane : side.children("lane")) {
      const pugi::xml_node link = lane.child("link").child(kind);
      if (!link || std::string(lane.attribute("type").value()) != "driving") continue;
      const long id = reader.integer(lane, "id", -100, 100);
      const long linked = reader.integer(link, "id", -100, 100);
      if (linked != id) {
        reader.fail(link, fmt::format("id: lane {} {}: the scenario language's lanes keep their place along the road",
                                      id, fmt::format(other, linked)));
      }
    }
  }
}

/// The links between two consecutive sections (of one road, or the last of a road and the first
/// of the road linked to it).
void checkSectionJoin(const xml::Reader& reader, const pugi::xml_node& before, const pugi::xml_node& after,
                      int sign) {
  checkLaneLinks(reader, before, sign, "successor");
  checkLaneLinks(reader, after, sign, "predecessor");
}

/// The lanes' offset from the reference line (m, > 0 left): OpenDRIVE's <laneOffset> records,
/// which must give one constant along the road (`length` m) — none (0), or records from s = 0
/// that all have the same `a` and no b, c, d (map tools write one per section). An offset that
/// varies moves the lanes across the road, which the language's lanes, parallel to its centre
/// line, cannot.
double constantLaneOffset(const xml::Reader& reader, const pugi::xml_node& lanes, double length) {
  // In order of s (the standard asks for it; a file may not keep it); a record from the road's
  // end on applies to none of it.
  std::vector<std::pair<double, pugi::xml_node>> records;
  for (const pugi::xml_node& offset : lanes.children("laneOffset")) {
    const double s = reader.number(offset, "s", NumberRange::atLeast(0.0));
    if (s < length) records.emplace_back(s, offset);
  }
  std::stable_sort(records.begin(), records.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::optional<double> constant;
  for (const auto& [s, offset] : records) {
    for (const char* coefficient : {"b", "c", "d"}) {
      if (reader.optionalNumber(offset, coefficient).value_or(0.0) != 0.0) {
        reader.fail(offset, "a lane offset that varies along the road: the scenario language's lanes run parallel "
                            "to its centre line");
      }
    }
    // Lanes a kilometre off their reference line are a broken file, not a road.
    const double a = reader.number(offset, "a", NumberRange::closed(-1000.0, 1000.0));
    if (!constant && s != 0.0 && a != 0.0) {
      reader.fail(offset, fmt::format("s = {} m: a lane offset of {} m from there, none before: the scenario "
                                      "language's lanes run parallel to its centre line",
                                      xml::number(s), xml::number(a)));
    }
    if (constant && !near(a, *constant)) {
      reader.fail(offset, fmt::format("a = {} m from s = {} m, after {} m: a lane offset that changes along the road "
                                      "(the scenario language's lanes run parallel to its centre line)",
                                      xml::number(a), xml::number(s), xml::number(*constant)));
    }
    if (!constant) constant = a;
  }
  return constant.value_or(0.0);
}

/// Lane sections: the first (at s = 0) gives the road's lanes; later ones (in order of s,
/// within the road) must repeat its driving lanes and shoulders, as the language's lanes run
/// the whole road (a road split into sections where only lanes beyond the shoulders change).
void readLanes(const xml::Reader& reader, const pugi::xml_node& road, CarriagewayRoad& result) {
  const pugi::xml_node lanes = reader.only(road, "lanes");
  reader.requireSubset(lanes, {"laneSection", "laneOffset"});
  result.laneOffset = constantLaneOffset(reader, lanes, result.length);
  const pugi::xml_node first = lanes.child("laneSection");
  if (!first) reader.fail(lanes, "expected a <laneSection>");
  if (reader.optionalNumber(first, "s").value_or(0.0) != 0.0) reader.fail(first, "s: expected 0 (the road's start)");
  readSection(reader, first, result);
  double previous_s = 0.0;
  for (pugi::xml_node section = first.next_sibling("laneSection"); section;
       section = section.next_sibling("laneSection")) {
    const double s = reader.number(section, "s", NumberRange::aboveUpTo(previous_s, result.length));
    previous_s = s;
    CarriagewayRoad own;
    own.leftHandTraffic = result.leftHandTraffic;
    own.laneOffset = result.laneOffset;
    readSection(reader, section, own);
    if (!sameLanes(own, result)) {
      reader.fail(section, fmt::format("s = {} m: {}, where the road starts with {}: the scenario language's lanes run "
                                       "the whole road",
                                       xml::number(s), sectionLayout(own), sectionLayout(result)));
    }
    if (!sameLeftSide(own, result) && result.leftSideChanges.empty()) result.leftSideChanges = reader.where(section);
    checkSectionJoin(reader, section.previous_sibling("laneSection"), section, result.leftHandTraffic ? +1 : -1);
  }
}

}  // namespace

PlanGeometry readPlanGeometry(const xml::Reader& reader, const pugi::xml_node& geometry, double offset) {
  const pugi::xml_node shape = reader.choice(geometry, {"line", "arc", "spiral", "paramPoly3"});
  const double s = offset + reader.number(geometry, "s", NumberRange::atLeast(0.0));
  const Vec2 start(reader.number(geometry, "x"), reader.number(geometry, "y"));
  const double heading = reader.number(geometry, "hdg");
  const double length = reader.number(geometry, "length", kLength);
  const std::string kind = shape.name();
  const NumberRange curvature_range = NumberRange::closed(-1.0, 1.0);
  if (kind == "line") return PlanGeometry::line(s, start, heading, length);
  if (kind == "arc") {
    return PlanGeometry::arc(s, start, heading, length, reader.number(shape, "curvature", curvature_range));
  }
  if (kind == "spiral") {
    return PlanGeometry::spiral(s, start, heading, length, reader.number(shape, "curvStart", curvature_range),
                                reader.number(shape, "curvEnd", curvature_range));
  }
  std::array<double, 4> u{};
  std::array<double, 4> v{};
  const char* names[] = {"a", "b", "c", "d"};
  for (std::size_t i = 0; i < 4; ++i) {
    u[i] = reader.number(shape, (std::string(names[i]) + "U").c_str());
    v[i] = reader.number(shape, (std::string(names[i]) + "V").c_str());
  }
  const std::string range = reader.optionalText(shape, "pRange").value_or("normalized");
  if (range != "normalized" && range != "arcLength") {
    reader.fail(shape, fmt::format("pRange=\"{}\": expected arcLength or normalized", range));
  }
  return PlanGeometry::paramPoly3(s, start, heading, length, u, v, range == "normalized");
}

void CarriagewayRoad::requireSteadyLeftSide() const {
  if (leftSideChanges.empty()) return;
  throw ConfigError(fmt::format("{}: the lanes left of the reference line change here, and the scenario drives them: "
                                "the scenario language's lanes run the whole road",
                                leftSideChanges));
}

void CarriagewayRoad::useLeftCarriageway() {
  if (!leftRun || leftCarriageway || leftLanesJoined) throw std::logic_error("useLeftCarriageway: no left run to use");
  requireSteadyLeftSide();
  takeRun(*this, *leftRun, +1);
}

double CarriagewayRoad::laneDirection(long lane_id) const {
  const bool against_file_line = (lane_id > 0) != leftHandTraffic;
  return against_file_line != reversed ? kPi : 0.0;
}

namespace {

/// `geometry` run backwards: from its end, turned by pi, its curvature negated (a spiral's ends swapped).
PlanGeometry reversedGeometry(const PlanGeometry& geometry, double s, const std::filesystem::path& file) {
  const double length = geometry.length();
  const Vec2 start = geometry.point(length);
  const double heading = geometry.heading(length) + kPi;
  switch (geometry.kind()) {
    case PlanGeometry::Kind::Line: return PlanGeometry::line(s, start, heading, length);
    case PlanGeometry::Kind::Arc: return PlanGeometry::arc(s, start, heading, length, -geometry.curvature(0.0));
    case PlanGeometry::Kind::Spiral:
      return PlanGeometry::spiral(s, start, heading, length, -geometry.curvature(length), -geometry.curvature(0.0));
    case PlanGeometry::Kind::ParamPoly3: break;
  }
  throw ConfigError(fmt::format("{}: a paramPoly3 geometry at s = {} m: the left side is driven against the reference "
                                "line, and vsd-sumo reverses lines, arcs and spirals only",
                                file.string(), xml::number(geometry.s())));
}

}  // namespace

void CarriagewayRoad::useReversedLeftCarriageway() {
  if (!leftRun || leftCarriageway || leftLanesJoined || reversed || leftHandTraffic) {
    throw std::logic_error("useReversedLeftCarriageway: no left run to use");
  }
  requireSteadyLeftSide();
  std::vector<PlanGeometry> backwards;
  for (auto it = geometries.rbegin(); it != geometries.rend(); ++it) {
    backwards.push_back(reversedGeometry(*it, length - (it->s() + it->length()), file));
  }
  geometries = std::move(backwards);
  start = geometries.front().point(0.0);
  heading = geometries.front().heading(0.0);
  turnBefore = {0.0};
  for (std::size_t g = 1; g < geometries.size(); ++g) {
    turnBefore.push_back(turnBefore.back() + geometries[g - 1].turn(geometries[g - 1].length()));
  }
  referenceSamples = MeasuredPolyline();
  sampleS.clear();
  classifyCurvature(*this);
  // The left side's run, seen from the reversed line: its right side, ids turned, lane 0 the outermost.
  DrivenRun run = *leftRun;
  run.innermostLaneId = -run.innermostLaneId;
  std::reverse(run.laneWidths.begin(), run.laneWidths.end());
  laneOffset = -laneOffset;
  takeRun(*this, run, -1);
  adjoiningLeftLanes = 0;
  adjoiningLeftWidths.clear();
  reversed = true;
}

void CarriagewayRoad::joinLeftLanes() {
  if (adjoiningLeftLanes == 0 || leftLanesJoined) throw std::logic_error("joinLeftLanes: no left lanes to join");
  requireSteadyLeftSide();
  leftLanesJoined = true;
  lanes += adjoiningLeftLanes;
  laneWidths.insert(laneWidths.end(), adjoiningLeftWidths.begin(), adjoiningLeftWidths.end());
  innerT = laneOffset + std::accumulate(adjoiningLeftWidths.begin(), adjoiningLeftWidths.end(), 0.0);
  shoulderLeft = adjoiningLeftShoulder;
}

int CarriagewayRoad::languageLane(long lane_id, const std::string& where) const {
  if (leftLanesJoined && lane_id >= 1 && lane_id <= adjoiningLeftLanes) {
    return rightLanes() + static_cast<int>(lane_id) - 1;
  }
  if (reversed) {  // the left side driven against the reference line: own ids are the file's turned
    const long own = -lane_id;
    const long outermost = innermostLaneId - lanes + 1;
    if (own <= innermostLaneId && own >= outermost) return static_cast<int>(own - outermost);
    const char* why = lane_id < 0 ? "the right side's lanes are not part of vsd-sumo's road here"
                                  : "a shoulder, stop lane, border or median: no road user drives there";
    throw ConfigError(fmt::format("{}: laneId {}: expected a driving lane of the road's left side, {} .. {}, driven "
                                  "against the reference line (as the file's Init drives it) ({})",
                                  where, lane_id, -innermostLaneId, -outermost, why));
  }
  if (leftCarriageway) {
    const long outermost = innermostLaneId + lanes - 1;
    if (lane_id >= innermostLaneId && lane_id <= outermost) return static_cast<int>(lane_id - innermostLaneId);
    const char* why = lane_id < 0 ? "the right side's lanes are not part of vsd-sumo's road here"
                                  : "a shoulder, stop lane, border or median: no road user drives there";
    throw ConfigError(fmt::format("{}: laneId {}: expected a driving lane of the road's left side, {} .. {}, driven "
                                  "along the reference line{} ({})",
                                  where, lane_id, innermostLaneId, outermost,
                                  leftHandTraffic ? " (rule LHT)" : " (as the file's Init drives it)", why));
  }
  const long outermost = innermostLaneId - rightLanes() + 1;
  if (lane_id > innermostLaneId || lane_id < outermost) {
    // Why that lane is not one: the left side is driven against the reference line; on the right
    // side it is a shoulder, a stop lane, a border or a median strip (no road user drives there).
    const char* why = lane_id > 0 ? "lanes driven against the reference line are not part of vsd-sumo's road"
                                  : "a shoulder, stop lane, border or median: no road user drives there";
    throw ConfigError(fmt::format(
        "{}: laneId {}: expected a driving lane of the road's right side, {} .. {}{} ({})", where, lane_id,
        innermostLaneId, outermost,
        leftLanesJoined ? fmt::format(", or of its left side driven along it, 1 .. {}", adjoiningLeftLanes) : "", why));
  }
  return static_cast<int>(lane_id - outermost);
}

const RoadPiece* CarriagewayRoad::piece(const std::string& road_id) const {
  for (const RoadPiece& piece : pieces) {
    if (piece.id == road_id) return &piece;
  }
  return nullptr;
}

std::string CarriagewayRoad::name() const {
  if (pieces.size() <= 1) return fmt::format("road '{}'", id);
  std::vector<std::string> ids;
  for (const RoadPiece& piece : pieces) ids.push_back("'" + piece.id + "'");
  return fmt::format("roads {}", fmt::join(ids, " -> "));
}

double CarriagewayRoad::centreT() const { return innerT - scenario::halfRoadWidth(laneWidths); }

double CarriagewayRoad::laneCentreT(int lane) const {
  if (oneLaneWidth()) return innerT - (lanes - lane - 0.5) * laneWidths.front();
  return centreT() + scenario::laneCentreOffset(lane, laneWidths);
}

int CarriagewayRoad::nearestLane(double t) const {
  if (oneLaneWidth()) {
    const long lane = std::lround((t - laneCentreT(0)) / laneWidths.front());
    return static_cast<int>(std::clamp<long>(lane, 0, lanes - 1));
  }
  return scenario::laneAtOffset(t - centreT(), laneWidths);
}

bool CarriagewayRoad::oneLaneWidth() const { return scenario::oneLaneWidth(laneWidths); }

PlanGeometry PlanGeometry::line(double s, const Vec2& start, double heading, double length) {
  PlanGeometry geometry;
  geometry.s_ = s;
  geometry.start_ = start;
  geometry.heading_ = heading;
  geometry.length_ = length;
  return geometry;
}

PlanGeometry PlanGeometry::arc(double s, const Vec2& start, double heading, double length, double curvature) {
  PlanGeometry geometry = line(s, start, heading, length);
  geometry.kind_ = Kind::Arc;
  geometry.curvatureStart_ = geometry.curvatureEnd_ = curvature;
  return geometry;
}

PlanGeometry PlanGeometry::spiral(double s, const Vec2& start, double heading, double length, double curvature_start,
                                  double curvature_end) {
  PlanGeometry geometry = line(s, start, heading, length);
  geometry.kind_ = Kind::Spiral;
  geometry.curvatureStart_ = curvature_start;
  geometry.curvatureEnd_ = curvature_end;
  const auto steps = static_cast<std::size_t>(std::ceil(length / kSpiralStep));
  geometry.spiralStep_ = length / static_cast<double>(steps);
  geometry.spiralPoints_.reserve(steps + 1);
  geometry.spiralPoints_.push_back(start);
  const auto h = [&geometry](double u) { return geometry.heading(u); };
  for (std::size_t i = 1; i <= steps; ++i) {
    const double a = geometry.spiralStep_ * static_cast<double>(i - 1);
    geometry.spiralPoints_.push_back(geometry.spiralPoints_.back() + integrateTangent(h, a, a + geometry.spiralStep_));
  }
  return geometry;
}

PlanGeometry PlanGeometry::paramPoly3(double s, const Vec2& start, double heading, double length,
                                      const std::array<double, 4>& u, const std::array<double, 4>& v, bool normalized) {
  PlanGeometry geometry = line(s, start, heading, length);
  geometry.kind_ = Kind::ParamPoly3;
  geometry.u_ = u;
  geometry.v_ = v;
  geometry.normalized_ = normalized;
  // Arc length over p by Simpson's rule on |(u', v')|, at least 64 steps and one per 0.5 m.
  const auto steps = std::max<std::size_t>(64, static_cast<std::size_t>(std::ceil(length / kSpiralStep)));
  geometry.parameterStep_ = (normalized ? 1.0 : length) / static_cast<double>(steps);
  geometry.arcLengths_.reserve(steps + 1);
  geometry.arcLengths_.push_back(0.0);
  const auto speed = [&geometry](double p) { return geometry.localTangent(p).norm(); };
  for (std::size_t i = 1; i <= steps; ++i) {
    const double a = geometry.parameterStep_ * static_cast<double>(i - 1);
    const double b = a + geometry.parameterStep_;
    geometry.arcLengths_.push_back(geometry.arcLengths_.back() +
                                   (b - a) / 6.0 * (speed(a) + 4.0 * speed(0.5 * (a + b)) + speed(b)));
  }
  return geometry;
}

double PlanGeometry::parameter(double ds) const {
  const double total = arcLengths_.back();
  if (!(total > 0.0)) return normalized_ ? ds / length_ : ds;
  const double target = std::clamp(ds, 0.0, length_) / length_ * total;
  const auto after = std::upper_bound(arcLengths_.begin(), arcLengths_.end(), target);
  const auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, std::distance(arcLengths_.begin(), after) - 1));
  if (i + 1 >= arcLengths_.size()) return parameterStep_ * static_cast<double>(arcLengths_.size() - 1);
  const double span = arcLengths_[i + 1] - arcLengths_[i];
  const double from = parameterStep_ * static_cast<double>(i);
  double p = from + parameterStep_ * (span > 0.0 ? (target - arcLengths_[i]) / span : 0.0);
  // Two Newton steps on the arc length from the step's start (Simpson's rule), from the
  // linear guess: within a micrometre where the speed changes along the step.
  const auto speed = [this](double q) { return localTangent(q).norm(); };
  for (int iteration = 0; iteration < 2; ++iteration) {
    const double arc = (p - from) / 6.0 * (speed(from) + 4.0 * speed(0.5 * (from + p)) + speed(p));
    const double rate = speed(p);
    if (!(rate > 0.0)) break;
    p = std::clamp(p - (arcLengths_[i] + arc - target) / rate, from, from + parameterStep_);
  }
  return p;
}

Vec2 PlanGeometry::localTangent(double p) const {
  return {u_[1] + 2.0 * u_[2] * p + 3.0 * u_[3] * p * p, v_[1] + 2.0 * v_[2] * p + 3.0 * v_[3] * p * p};
}

Vec2 PlanGeometry::localSecond(double p) const { return {2.0 * u_[2] + 6.0 * u_[3] * p, 2.0 * v_[2] + 6.0 * v_[3] * p}; }

Vec2 PlanGeometry::point(double ds) const {
  const Vec2 direction(std::cos(heading_), std::sin(heading_));
  switch (kind_) {
    case Kind::Line: return start_ + ds * direction;
    case Kind::Arc: {
      if (curvatureStart_ == 0.0) return start_ + ds * direction;
      const double r = 1.0 / curvatureStart_;
      const double h = heading_ + curvatureStart_ * ds;
      return start_ + Vec2(r * (std::sin(h) - std::sin(heading_)), -r * (std::cos(h) - std::cos(heading_)));
    }
    case Kind::Spiral: {
      const auto index = std::min(static_cast<std::size_t>(std::max(ds, 0.0) / spiralStep_), spiralPoints_.size() - 1);
      const double from = spiralStep_ * static_cast<double>(index);
      return spiralPoints_[index] + integrateTangent([this](double u) { return heading(u); }, from, ds);
    }
    case Kind::ParamPoly3: {
      const double p = parameter(ds);
      const Vec2 local(u_[0] + p * (u_[1] + p * (u_[2] + p * u_[3])), v_[0] + p * (v_[1] + p * (v_[2] + p * v_[3])));
      return start_ + local.x() * direction + local.y() * Vec2(-direction.y(), direction.x());
    }
  }
  return start_;
}

double PlanGeometry::heading(double ds) const {
  if (kind_ == Kind::ParamPoly3) return heading_ + headingOf(localTangent(parameter(ds)));
  return heading_ + turn(ds);
}

double PlanGeometry::turn(double ds) const {
  switch (kind_) {
    case Kind::Line: return 0.0;
    case Kind::Arc: return curvatureStart_ * ds;
    case Kind::Spiral: return curvatureStart_ * ds + (curvatureEnd_ - curvatureStart_) * ds * ds / (2.0 * length_);
    case Kind::ParamPoly3:
      return std::remainder(headingOf(localTangent(parameter(ds))) - headingOf(localTangent(0.0)), 2.0 * kPi);
  }
  return 0.0;
}

double PlanGeometry::curvature(double ds) const {
  switch (kind_) {
    case Kind::Line: return 0.0;
    case Kind::Arc: return curvatureStart_;
    case Kind::Spiral: return curvatureStart_ + (curvatureEnd_ - curvatureStart_) * ds / length_;
    case Kind::ParamPoly3: {
      const double p = parameter(ds);
      const Vec2 d1 = localTangent(p);
      const Vec2 d2 = localSecond(p);
      const double speed = d1.norm();
      return speed > 0.0 ? (d1.x() * d2.y() - d1.y() * d2.x()) / (speed * speed * speed) : 0.0;
    }
  }
  return 0.0;
}

double PlanGeometry::largestCurvature() const {
  if (kind_ != Kind::ParamPoly3) return std::max(std::abs(curvatureStart_), std::abs(curvatureEnd_));
  double largest = 0.0;
  constexpr int kProbes = 32;
  for (int i = 0; i <= kProbes; ++i) largest = std::max(largest, std::abs(curvature(length_ * i / kProbes)));
  return largest;
}

const PlanGeometry& CarriagewayRoad::geometryAt(double s) const {
  const auto after = std::upper_bound(geometries.begin(), geometries.end(), s,
                                      [](double value, const PlanGeometry& g) { return value < g.s(); });
  return after == geometries.begin() ? geometries.front() : *std::prev(after);
}

double CarriagewayRoad::turnAt(double s) const {
  if (oneCurvature) return curvature * s;
  const PlanGeometry& geometry = geometryAt(s);
  const auto index = static_cast<std::size_t>(&geometry - geometries.data());
  const double ds = std::clamp(s - geometry.s(), 0.0, geometry.length());
  return turnBefore[index] + geometry.turn(ds);
}

double CarriagewayRoad::languageS(double s) const {
  if (oneCurvature) return s * (1.0 - curvature * centreT());
  return s - centreT() * turnAt(s);
}

double CarriagewayRoad::curvatureAt(double s) const {
  if (oneCurvature) return curvature;
  if (s < 0.0 || s > length) return 0.0;  // the straight continuations beyond the ends
  const PlanGeometry& geometry = geometryAt(s);
  return geometry.curvature(std::clamp(s - geometry.s(), 0.0, geometry.length()));
}

double CarriagewayRoad::headingAt(double s) const {
  if (oneCurvature) return heading + curvature * s;
  return heading + turnAt(std::clamp(s, 0.0, length));
}

Vec2 CarriagewayRoad::point(double s, double t) const {
  const double h = headingAt(s);
  Vec2 reference;
  if (oneCurvature && std::abs(curvature) < 1e-12) {
    reference = start + s * Vec2(std::cos(heading), std::sin(heading));
  } else if (oneCurvature) {
    const double r = 1.0 / curvature;
    reference = start + Vec2(r * (std::sin(h) - std::sin(heading)), -r * (std::cos(h) - std::cos(heading)));
  } else {
    const double on_road = std::clamp(s, 0.0, length);
    const PlanGeometry& geometry = geometryAt(on_road);
    reference = geometry.point(std::clamp(on_road - geometry.s(), 0.0, geometry.length())) +
                (s - on_road) * Vec2(std::cos(h), std::sin(h));
  }
  return reference + t * Vec2(-std::sin(h), std::cos(h));
}

std::pair<double, double> CarriagewayRoad::coordinates(const Vec2& p) const {
  const Vec2 direction(std::cos(heading), std::sin(heading));
  const Vec2 normal(-direction.y(), direction.x());
  if (!oneCurvature) {
    // Nearest point of the sampled reference line; before its start and beyond its end the
    // road goes on along the end tangents.
    const PolylineProjection foot = referenceSamples.project(p);
    const auto& points = referenceSamples.points();
    const Vec2 from_start = p - points.front();
    if (foot.arcLength <= 0.0 && from_start.dot(direction) < 0.0) return {from_start.dot(direction), from_start.dot(normal)};
    const double end_heading = headingAt(length);
    const Vec2 end_direction(std::cos(end_heading), std::sin(end_heading));
    const Vec2 from_end = p - points.back();
    if (foot.arcLength >= referenceSamples.length() && from_end.dot(end_direction) > 0.0) {
      return {length + from_end.dot(end_direction), from_end.dot(Vec2(-end_direction.y(), end_direction.x()))};
    }
    const Vec2 segment = points[foot.segment + 1] - points[foot.segment];
    const double fraction = std::clamp((foot.foot - points[foot.segment]).norm() / segment.norm(), 0.0, 1.0);
    const double s = sampleS[foot.segment] + fraction * (sampleS[foot.segment + 1] - sampleS[foot.segment]);
    return {s, foot.lateralOffset};
  }
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

namespace {

bool inJunction(const pugi::xml_node& road) {
  const std::string junction = road.attribute("junction").value();
  return !junction.empty() && junction != "-1";
}

/// The road a <successor> or <predecessor> link of `road` names, if it continues `road` in its
/// direction (its start follows a successor, its end precedes a predecessor) outside junctions;
/// an empty node otherwise.
pugi::xml_node continuation(const pugi::xml_node& root, const pugi::xml_node& road, const std::string& kind) {
  const pugi::xml_node link = road.child("link").child(kind.c_str());
  if (!link || std::string(link.attribute("elementType").value()) != "road") return {};
  const std::string contact = kind == "successor" ? "start" : "end";
  if (link.attribute("contactPoint").value() != contact) return {};
  const std::string id = link.attribute("elementId").value();
  for (const pugi::xml_node& other : root.children("road")) {
    if (other.attribute("id").value() == id && !inJunction(other)) return other;
  }
  return {};
}

/// m a point may lie right and left of `road`'s reference line and be on it: the widest its lanes
/// get on each side in any section (each lane's largest `a`) beyond its largest lane offset. A
/// bound for finding the road under a point, not a reading of the road (readLanes checks it).
std::pair<double, double> lateralExtent(const pugi::xml_node& road) {
  double offset = 0.0;
  for (const pugi::xml_node& record : road.child("lanes").children("laneOffset")) {
    offset = std::max(offset, std::abs(record.attribute("a").as_double()));
  }
  const auto side_width = [](const pugi::xml_node& side) {
    double sum = 0.0;
    for (const pugi::xml_node& lane : side.children("lane")) {
      double widest = 0.0;
      for (const pugi::xml_node& width : lane.children("width")) {
        widest = std::max(widest, width.attribute("a").as_double());
      }
      sum += widest;
    }
    return sum;
  };
  double right = 0.0;
  double left = 0.0;
  for (const pugi::xml_node& section : road.child("lanes").children("laneSection")) {
    right = std::max(right, side_width(section.child("right")));
    left = std::max(left, side_width(section.child("left")));
  }
  return {right + offset, left + offset};
}

/// The road outside junctions whose lanes hold `place`'s point: a file that names no roadId places
/// its scenario on a map by world positions. Where several do (a crossing outside a junction),
/// the nearest reference line among the roads that run along the place's heading (either way,
/// within 45 degrees) wins, or among all if none does or it gives no heading. Roads whose plan
/// view vsd-sumo cannot read are not candidates.
pugi::xml_node roadUnder(const xml::Reader& reader, const pugi::xml_node& root, const WorldPlace& place,
                         const std::string& asked_where) {
  const Vec2& point = place.point;
  pugi::xml_node found;
  double found_t = std::numeric_limits<double>::infinity();
  bool found_aligned = false;
  for (const pugi::xml_node& road : root.children("road")) {
    if (inJunction(road)) continue;
    CarriagewayRoad plan;
    try {
      readPlanView(reader, road, plan, 0.0);
      classifyCurvature(plan);
    } catch (const ConfigError&) {
      continue;
    }
    const auto [s, t] = plan.coordinates(point);
    const auto [right, left] = lateralExtent(road);
    const bool on_road = s >= -kJoinTolerance && s <= plan.length + kJoinTolerance && t >= -right && t <= left;
    if (!on_road) continue;
    const bool aligned = place.heading && std::abs(std::sin(*place.heading - plan.headingAt(s))) < std::sqrt(0.5);
    if ((aligned && !found_aligned) || (aligned == found_aligned && std::abs(t) < found_t)) {
      found = road;
      found_t = std::abs(t);
      found_aligned = aligned;
    }
  }
  if (!found) {
    reader.fail(root, fmt::format("several roads, no position of the scenario names one (roadId), and its first "
                                  "world position (x {} m, y {} m; {}) lies on the lanes of none outside junctions",
                                  xml::number(point.x()), xml::number(point.y()), asked_where));
  }
  return found;
}

/// vsd-sumo's road in a file of several roads: the road `scenario_road` (the scenario's first
/// roadId, or the road under its first world position; `asked_where` names it) and the roads
/// linked to it end to start, in driving order. A file of one road is that road.
std::vector<pugi::xml_node> roadChain(const xml::Reader& reader, const pugi::xml_node& root,
                                      const std::string& scenario_road, const std::string& asked_where) {
  const auto roads = root.children("road");
  const auto count = static_cast<std::size_t>(std::distance(roads.begin(), roads.end()));
  if (count == 0) reader.fail(root, "expected a <road>");
  if (count == 1) return {*roads.begin()};
  if (scenario_road.empty()) {
    reader.fail(*std::next(roads.begin()), "several roads, and no position of the scenario names one (roadId) or "
                                           "lies on one (WorldPosition)");
  }
  pugi::xml_node found;
  for (const pugi::xml_node& road : roads) {
    if (road.attribute("id").value() == scenario_road) found = road;
  }
  if (!found) reader.fail(root, fmt::format("no <road> with id \"{}\" ({})", scenario_road, asked_where));
  if (inJunction(found)) {
    reader.fail(found, fmt::format("road '{}' lies in junction {} ({}): vsd-sumo's road is a chain of roads outside "
                                   "junctions",
                                   scenario_road, found.attribute("junction").value(), asked_where));
  }
  std::deque<pugi::xml_node> chain = {found};
  std::set<const void*> seen = {found.internal_object()};
  for (pugi::xml_node next = continuation(root, found, "successor"); next && seen.insert(next.internal_object()).second;
       next = continuation(root, next, "successor")) {
    chain.push_back(next);
  }
  for (pugi::xml_node before = continuation(root, found, "predecessor");
       before && seen.insert(before.internal_object()).second; before = continuation(root, before, "predecessor")) {
    chain.push_front(before);
  }
  return {chain.begin(), chain.end()};
}

/// Notes (once) the roads and junctions of the file that are not part of vsd-sumo's road.
void noteLeftOut(const xml::Reader& reader, const pugi::xml_node& root, const CarriagewayRoad& road,
                 Findings& findings) {
  std::vector<std::string> roads;
  pugi::xml_node first;
  for (const pugi::xml_node& node : root.children("road")) {
    if (road.piece(node.attribute("id").value())) continue;
    roads.push_back(node.attribute("id").value());
    if (!first) first = node;
  }
  std::vector<std::string> junctions;
  for (const pugi::xml_node& node : root.children("junction")) {
    junctions.push_back(node.attribute("id").value());
    if (!first) first = node;
  }
  if (!first) return;
  // A city map has hundreds of roads: the first few name them, the count says the rest.
  constexpr std::size_t kNamed = 12;
  std::string left_out;
  if (roads.size() > kNamed) {
    left_out = fmt::format("{} roads ({}, ...)", roads.size(),
                           fmt::join(roads.begin(), roads.begin() + static_cast<long>(kNamed), ", "));
  } else if (!roads.empty()) {
    left_out = fmt::format("road(s) {}", fmt::join(roads, ", "));
  }
  if (!junctions.empty()) {
    left_out += fmt::format("{}junction(s) {}", roads.empty() ? "" : " and ", fmt::join(junctions, ", "));
  }
  findings.note(reader.where(first), fmt::format("{} not simulated: vsd-sumo's road is {} (the scenario's road and the "
                                                 "roads linked to it end to start; the language has one road)",
                                                 left_out, road.name()));
}

/// What a road says about how to drive on it and the simulation does not follow: its type and
/// speed limit (scripted road users keep their own speeds, the Ego its controller's), lane
/// speeds and road marks (lane changes cross any mark). One note each, at the first.
void noteRules(const xml::Reader& reader, const pugi::xml_node& road, Findings& findings) {
  if (const pugi::xml_node type = road.child("type")) {
    findings.note(reader.where(type), "the road type and its speed limit are not simulated (scripted road users keep "
                                      "their speeds, the Ego its controller's)");
  }
  const pugi::xml_node speed = road.select_node("lanes/laneSection/*/lane/speed").node();
  if (speed) findings.note(reader.where(speed), "lane speed limits are not simulated");
  const pugi::xml_node mark = road.select_node("lanes/laneSection/*/lane/roadMark").node();
  if (mark) findings.note(reader.where(mark), "road marks are not simulated (lane changes cross any mark)");
}

/// Grade (%) from which a road's heights matter to what is simulated: gravity along it is then
/// 0.2 m/s^2 or more, a few per cent of a vehicle's braking.
constexpr double kGradeThatMatters = 2.0;

/// One road of the chain, appended to `result` (the first gives its lanes; later ones must
/// repeat them and the traffic rule; `before`: the road before it, whose lanes it continues).
void readRoadPiece(const xml::Reader& reader, const pugi::xml_node& road, const pugi::xml_node& before,
                   CarriagewayRoad& result, Findings& findings) {
  reader.requireSubset(road, {"link", "type", "planView", "elevationProfile", "lateralProfile", "lanes", "objects",
                              "signals", "userData", "surface"});
  const bool first = result.pieces.empty();
  const std::string id = reader.text(road, "id");
  const bool left_hand = road.attribute("rule") && reader.oneOf(road, "rule", {"RHT", "LHT"}) == "LHT";
  if (first) result.leftHandTraffic = left_hand;
  if (left_hand != result.leftHandTraffic) {
    reader.fail(road, fmt::format("rule: road '{}' continues road '{}' under the other traffic rule", id,
                                  result.pieces.back().id));
  }
  const double offset = result.length;
  readPlanView(reader, road, result, offset);
  const double length = result.length - offset;
  if (std::abs(length - reader.number(road, "length", kLength)) > kJoinTolerance) {
    reader.fail(road, "length: differs from the sum of its geometries' lengths");
  }
  result.pieces.push_back({id, offset, length});
  if (first) {
    readLanes(reader, road, result);
  } else {
    CarriagewayRoad own;
    own.leftHandTraffic = left_hand;
    own.length = length;
    readLanes(reader, road, own);
    const pugi::xml_node section = road.child("lanes").child("laneSection");
    if (!near(own.laneOffset, result.laneOffset)) {
      const pugi::xml_node record = road.child("lanes").child("laneOffset");
      reader.fail(record ? record : section,
                  fmt::format("road '{}' continues road '{}' with its lanes {} m left of the reference line, where "
                              "vsd-sumo's road has them {} m left (<laneOffset>): the scenario language's lanes run "
                              "parallel to its centre line",
                              id, result.pieces[result.pieces.size() - 2].id, xml::number(own.laneOffset),
                              xml::number(result.laneOffset)));
    }
    if (!sameLanes(own, result)) {
      reader.fail(section, fmt::format("road '{}' continues road '{}' with {}, where vsd-sumo's road has {}: the "
                                       "scenario language's lanes run the whole road",
                                       id, result.pieces[result.pieces.size() - 2].id, sectionLayout(own),
                                       sectionLayout(result)));
    }
    if (result.leftSideChanges.empty()) {
      result.leftSideChanges = sameLeftSide(own, result) ? own.leftSideChanges : reader.where(section);
    }
    pugi::xml_node last_before;
    for (const pugi::xml_node& candidate : before.child("lanes").children("laneSection")) last_before = candidate;
    checkSectionJoin(reader, last_before, section, left_hand ? +1 : -1);
  }
  noteElevation(reader, road, findings);
  const pugi::xml_node banking = road.child("lateralProfile");
  if (banking && banking.first_child()) {
    findings.note(reader.where(banking), "vsd-sumo is planar: banking is not simulated");
  }
  for (const char* unused : {"objects", "signals"}) {
    const pugi::xml_node node = road.child(unused);
    if (node && node.first_child()) findings.note(reader.where(node), "not simulated (the scenario language has no road furniture)");
  }
  noteRules(reader, road, findings);
}

CarriagewayRoad readRoad(const std::filesystem::path& file, std::string text, Findings& findings,
                         const std::string& scenario_road, const std::optional<WorldPlace>& place,
                         const std::string& asked_where) {
  xml::Reader reader(file, std::move(text));
  const pugi::xml_node root = reader.root();
  if (std::string(root.name()) != "OpenDRIVE") reader.fail(root, "expected the root element <OpenDRIVE>");
  reader.requireSubset(root, {"header", "road", "controller", "junction"});
  CarriagewayRoad result;
  result.file = file;
  pugi::xml_node before;  // the road before in the chain
  std::string chosen = scenario_road;
  const auto roads = root.children("road");
  if (scenario_road.empty() && place && std::distance(roads.begin(), roads.end()) > 1) {
    // A WorldPosition, not a roadId, chooses the road among several: say which and why.
    chosen = roadUnder(reader, root, *place, asked_where).attribute("id").value();
    findings.mapped(asked_where, fmt::format("lies on road '{}' of {}: the scenario's road (no position names a "
                                             "roadId)",
                                             chosen, file.filename().string()));
  }
  for (const pugi::xml_node& road : roadChain(reader, root, chosen, asked_where)) {
    readRoadPiece(reader, road, before, result, findings);
    before = road;
  }
  result.id = result.pieces.front().id;
  classifyCurvature(result);
  noteLeftOut(reader, root, result, findings);
  return result;
}

/// A road read before in this process, and the notes its reading gave.
struct ReadRoad {
  CarriagewayRoad road;
  std::vector<Findings::Line> notes;
};

}  // namespace

void noteElevation(const xml::Reader& reader, const pugi::xml_node& road, Findings& findings) {
  const pugi::xml_node profile = road.child("elevationProfile");
  if (!profile || !profile.first_child()) return;
  const double length = reader.number(road, "length");
  std::vector<pugi::xml_node> records(profile.children("elevation").begin(), profile.children("elevation").end());
  double lowest = std::numeric_limits<double>::infinity();
  double highest = -lowest;
  double steepest = 0.0;  // |dz/ds|
  for (std::size_t i = 0; i < records.size(); ++i) {
    const double start = reader.number(records[i], "s");
    const double end = i + 1 < records.size() ? reader.number(records[i + 1], "s") : length;
    const double a = reader.number(records[i], "a");
    const double b = reader.number(records[i], "b");
    const double c = reader.number(records[i], "c");
    const double d = reader.number(records[i], "d");
    const int steps = std::max(1, static_cast<int>(std::ceil((end - start) / 0.5)));
    for (int k = 0; k <= steps; ++k) {
      const double ds = (end - start) * k / steps;
      const double z = a + ds * (b + ds * (c + ds * d));
      lowest = std::min(lowest, z);
      highest = std::max(highest, z);
      steepest = std::max(steepest, std::abs(b + ds * (2.0 * c + ds * 3.0 * d)));
    }
  }
  const double grade = 100.0 * steepest;
  if (grade < kGradeThatMatters) {
    findings.note(reader.where(profile),
                  fmt::format("vsd-sumo is planar: heights are not simulated (the road rises and falls by {:.1f} m, "
                              "grades up to {:.1f} %)", highest - lowest, grade));
    return;
  }
  findings.note(reader.where(profile),
                fmt::format("vsd-sumo is planar: the road rises and falls by {:.1f} m, with grades up to {:.1f} %; "
                            "gravity along it (up to {:.2f} m/s^2), lengths over slopes and sight over crests are not "
                            "simulated", highest - lowest, grade, 9.81 * std::sin(std::atan(steepest))),
                /*warn=*/true);
}

CarriagewayRoad readCarriagewayRoad(const std::filesystem::path& file, Findings& findings,
                                    const std::string& scenario_road, const std::string& asked_where,
                                    const std::optional<WorldPlace>& place) {
  // A sweep imports its template once per parameter set (twice: to check it, to run it);
  // the road is read once per process and file content. A file that changes is read again.
  static std::mutex mutex;
  static std::map<std::string, ReadRoad> roads;
  constexpr std::size_t kRoadsKept = 8;
  std::string text = readTextFile(file, read_limits::kRoadNetwork);  // read once: hashed, then parsed
  const std::string key = std::filesystem::absolute(file).lexically_normal().string() + "\n" + sha256OfString(text) +
                          "\n" + scenario_road + "\n" +
                          (place ? fmt::format("{} {} {} {}", place->point.x(), place->point.y(),
                                               place->heading ? fmt::format("{}", *place->heading) : "-", asked_where)
                                 : std::string());
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto found = roads.find(key); found != roads.end()) {
      findings.replay(found->second.notes);
      return found->second.road;
    }
  }
  Findings own(findings.collecting());
  CarriagewayRoad road;
  try {
    road = readRoad(file, std::move(text), own, scenario_road, place, asked_where);
  } catch (const ConfigError&) {
    findings.replay(own.lines());  // the notes before the refusal, as without the cache
    throw;
  }
  findings.replay(own.lines());
  const std::lock_guard<std::mutex> lock(mutex);
  if (roads.size() >= kRoadsKept) roads.clear();
  roads.emplace(key, ReadRoad{road, own.lines()});
  return road;
}

}  // namespace vsd::interop::osc
