// NetworkBuilder::writeSumoNet: the .net.xml of a batch of generated roads,
// written directly instead of by a netconvert process (~1 ms of CPU per road,
// more than the whole simulation of the scenario).
//
// The roads are disjoint single edges between two dead-end nodes, so
// netconvert's work reduces to a few rules, reproduced here and checked against
// its output in tests/road:
//   - the edge shape is the plain-XML centre line (node positions at its ends)
//     without points closer than 0.1 m to their predecessor;
//   - lane i's shape is the edge shape moved sideways by its offset from the
//     centre (spreadType "center"), every inner point on the intersection of the
//     two neighbouring offset segments (SUMO's PositionVector::move2side);
//   - every lane's length is the edge shape's length;
//   - a dead-end junction's shape is the line across the road at its node;
//   - coordinates and lengths are written with 2 decimals, the order of edges and
//     junctions is by id (as netconvert writes them).
// Where a lane's shape would fold (a sideways move longer than half a segment at a
// bend), netconvert cuts lanes at the junctions in ways not reproduced here:
// directlyWritable() says so and callers use netconvert for that network.

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>

#include "vsd/core/error.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/numbers.hpp"
#include "vsd/road/network.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

namespace {

using Out = std::back_insert_iterator<fmt::memory_buffer>;

/// "x,y x,y ..." with two decimals, as {:.2f} writes them (fixedDecimalText: the same text, cheaper).
void writePoints(Out out, const Polyline& points) {
  FixedDecimalBuffer buffer;
  const auto write = [&](double value) {
    const std::string_view text = fixedDecimalText(value, 2, buffer);
    out = std::copy(text.begin(), text.end(), out);
  };
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i > 0) *out++ = ' ';
    write(points[i].x());
    *out++ = ',';
    write(points[i].y());
  }
}

Vec2 leftNormal(const Vec2& from, const Vec2& to) {
  const Vec2 direction = (to - from).normalized();
  return {-direction.y(), direction.x()};
}

/// SUMO's POSITION_EPS (m): netconvert's tolerance for "the same point" and "straight".
constexpr double kSumoPositionEps = 0.1;

/// Drops points closer than 0.1 m to the previous kept one, keeping at least two
/// points and always the last one (as netconvert does before moving a shape sideways).
Polyline withoutNearDuplicates(const Polyline& points) {
  Polyline kept;
  kept.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const bool last = i + 1 == points.size();
    const std::size_t remaining = kept.size() + (points.size() - i);
    if (!kept.empty() && remaining > 2 && (points[i] - kept.back()).norm() < kSumoPositionEps) {
      if (last) kept.back() = points[i];  // keep the end point, drop the one before it
      continue;
    }
    kept.push_back(points[i]);
  }
  return kept;
}

/// Where the line through a1, a2 meets the line through b1, b2 (not parallel).
std::optional<Vec2> lineIntersection(const Vec2& a1, const Vec2& a2, const Vec2& b1, const Vec2& b2) {
  const Vec2 da = a2 - a1;
  const Vec2 db = b2 - b1;
  const double denominator = db.y() * da.x() - db.x() * da.y();
  if (std::abs(denominator) < std::numeric_limits<double>::epsilon()) return std::nullopt;
  const double along_a = (db.x() * (a1.y() - b1.y()) - db.y() * (a1.x() - b1.x())) / denominator;
  return a1 + along_a * da;
}

/// A lane's shape as netconvert derives it from its edge's shape (`left_offset` m to
/// the left, negative: right): end points move perpendicular to their segment; an
/// inner point where the shape runs straight on (the extension of the incoming
/// segment passes within 0.1 m of the next point) moves perpendicular to the chord of
/// its neighbours, a reversing point moves along the incoming direction, any other
/// inner point goes to the intersection of its two moved segments.
Polyline sumoLaneShape(const Polyline& edge_shape, double left_offset) {
  const Polyline shape = withoutNearDuplicates(edge_shape);
  const std::size_t n = shape.size();
  Polyline lane;
  lane.reserve(n);
  lane.push_back(shape[0] + left_offset * leftNormal(shape[0], shape[1]));
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Vec2& from = shape[i - 1];
    const Vec2& me = shape[i];
    const Vec2& to = shape[i + 1];
    const Vec2 incoming = (me - from).normalized();
    const double ahead = (to - me).norm();
    const double deviation = (me + ahead * incoming - to).norm();
    if (deviation < kSumoPositionEps) {
      lane.push_back(me + left_offset * leftNormal(from, to));
    } else if (std::abs(deviation - 2.0 * ahead) < kSumoPositionEps) {
      lane.push_back(me - left_offset * incoming);
    } else {
      const Vec2 n1 = left_offset * leftNormal(from, me);
      const Vec2 n2 = left_offset * leftNormal(me, to);
      lane.push_back(lineIntersection(from + n1, me + n1, me + n2, to + n2).value_or(me + n2));
    }
  }
  lane.push_back(shape[n - 1] + left_offset * leftNormal(shape[n - 2], shape[n - 1]));
  return lane;
}

struct Bounds {
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity());
  Vec2 hi = Vec2::Constant(-std::numeric_limits<double>::infinity());
  void add(const Polyline& points) {
    for (const auto& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
};

/// One edge of the net with everything its XML needs.
struct NetEdge {
  std::string id;
  Polyline shape;  ///< net coordinates
  int lanes = 1;
  std::vector<double> laneWidths;  ///< m, lane 0 first
  double speed = 0.0;
  double laneOffset(int lane) const { return scenario::laneCentreOffset(lane, laneWidths); }
};

void writeEdge(Out out, const NetEdge& edge) {
  fmt::format_to(out, "    <edge id=\"{0}\" from=\"{0}_a\" to=\"{0}_b\" priority=\"-1\" spreadType=\"center\" shape=\"",
                 edge.id);
  writePoints(out, edge.shape);
  fmt::format_to(out, "\">\n");
  const double length = polylineLength(edge.shape);
  for (int lane = 0; lane < edge.lanes; ++lane) {
    const double offset = edge.laneOffset(lane);
    fmt::format_to(out, "        <lane id=\"{}_{}\" index=\"{}\" speed=\"{:.2f}\" length=\"{:.2f}\" width=\"{:.2f}\" "
                   "{} shape=\"",
                   edge.id, lane, lane, edge.speed, length, edge.laneWidths[static_cast<std::size_t>(lane)],
                   kNoSumoLaneChanges);
    writePoints(out, sumoLaneShape(edge.shape, offset));
    fmt::format_to(out, "\"/>\n");
  }
  fmt::format_to(out, "    </edge>\n");
}

/// The dead-end junction at the start (`at_start`) or end of an edge: a line across
/// the road, listed counter-clockwise around the node as netconvert does.
void writeJunction(Out out, const NetEdge& edge, bool at_start) {
  const Polyline& s = edge.shape;
  const Vec2& node = at_start ? s.front() : s.back();
  const Vec2 normal = at_start ? leftNormal(s[0], s[1]) : leftNormal(s[s.size() - 2], s.back());
  const Vec2 half = scenario::halfRoadWidth(edge.laneWidths) * normal;
  fmt::format_to(out, "    <junction id=\"{}_{}\" type=\"dead_end\" x=\"{:.2f}\" y=\"{:.2f}\" incLanes=\"", edge.id,
                 at_start ? 'a' : 'b', node.x(), node.y());
  if (!at_start) {
    for (int lane = 0; lane < edge.lanes; ++lane) fmt::format_to(out, "{}{}_{}", lane == 0 ? "" : " ", edge.id, lane);
  }
  fmt::format_to(out, "\" intLanes=\"\" shape=\"");
  writePoints(out, at_start ? Polyline{node + half, node - half} : Polyline{node - half, node + half});
  fmt::format_to(out, "\"/>\n");
}

/// True if moving the shape sideways by `left_offset` folds it somewhere: a mitre
/// longer than half an adjacent segment. netconvert then also cuts and drops lane
/// points at the junctions, which writeSumoNet does not reproduce.
bool foldsWhenMoved(const Polyline& shape, double left_offset) {
  if (left_offset == 0.0) return false;
  for (std::size_t i = 1; i + 1 < shape.size(); ++i) {
    const Vec2 a = (shape[i] - shape[i - 1]).normalized();
    const Vec2 b = (shape[i + 1] - shape[i]).normalized();
    const double cos_turn = std::clamp(a.dot(b), -1.0, 1.0);
    const double half_turn = 0.5 * std::acos(cos_turn);
    if (half_turn >= 0.25 * kPi) return true;  // 90 degrees or more
    const double mitre = std::abs(left_offset) * std::tan(half_turn);
    const double shorter = std::min((shape[i] - shape[i - 1]).norm(), (shape[i + 1] - shape[i]).norm());
    if (mitre > 0.5 * shorter) return true;
  }
  return false;
}

/// The shape without the inner points of straight runs (a point exactly on the line from
/// the last kept point through the next one, between them): SUMO's cost of matching a
/// vehicle to its lane (moveToXY) grows with the points of the lanes' shapes.
Polyline withoutStraightRunPoints(const Polyline& points) {
  if (points.size() <= 2) return points;
  Polyline kept{points.front()};
  for (std::size_t i = 1; i + 1 < points.size(); ++i) {
    const Vec2 in = points[i] - kept.back();
    const Vec2 out = points[i + 1] - points[i];
    if (in.x() * out.y() - in.y() * out.x() == 0.0 && in.dot(out) > 0.0) continue;
    kept.push_back(points[i]);
  }
  kept.push_back(points.back());
  return kept;
}

/// A number as SUMO reads it back from the 2-decimal text of the network.
double asWritten(double value) { return asFixedDecimalText(value, 2); }

NetEdge netEdgeOf(const std::string& id, const Polyline& plain_xml_shape, const RoadGeometry& road) {
  // netconvert drops points within 0.1 m of their predecessor from the edge's geometry.
  return {id, withoutNearDuplicates(plain_xml_shape), road.lanes, road.laneWidths, road.speedLimit};
}

}  // namespace

bool NetworkBuilder::directlyWritable() const {
  for (const auto& placed : roads_) {
    // Lanes of different widths: netconvert's lane lengths then follow a rule of its own.
    if (!scenario::oneLaneWidth(placed.road.laneWidths)) return false;
    const NetEdge edge = netEdgeOf(edgeIdFor(placed.index), edgeShape(placed), placed.road);
    for (int lane = 0; lane < edge.lanes; ++lane) {
      if (foldsWhenMoved(edge.shape, edge.laneOffset(lane))) return false;
    }
  }
  return true;
}

std::vector<LaneGeometry> NetworkBuilder::lanesAsLoaded(std::uint64_t index) const {
  std::vector<LaneGeometry> lanes;
  for (const auto& placed : roads_) {
    if (placed.index != index) continue;
    const NetEdge edge = netEdgeOf(edgeIdFor(placed.index), edgeShape(placed), placed.road);
    for (int lane = 0; lane < edge.lanes; ++lane) {
      LaneGeometry geometry;
      geometry.id = fmt::format("{}_{}", edge.id, lane);
      for (const Vec2& point : sumoLaneShape(edge.shape, edge.laneOffset(lane))) {
        geometry.centre.emplace_back(asWritten(point.x()) - placed.offset.x(), asWritten(point.y()) - placed.offset.y());
      }
      geometry.width = asWritten(edge.laneWidths[static_cast<std::size_t>(lane)]);
      lanes.push_back(std::move(geometry));
    }
    break;
  }
  return lanes;
}

fs::path NetworkBuilder::writeSumoNet(const fs::path& stem) const {
  std::vector<NetEdge> edges;
  edges.reserve(roads_.size());
  Bounds bounds;
  for (const auto& placed : roads_) {
    NetEdge edge = netEdgeOf(edgeIdFor(placed.index), edgeShape(placed), placed.road);
    edge.shape = withoutStraightRunPoints(edge.shape);
    bounds.add(edge.shape);
    edges.push_back(std::move(edge));
  }
  std::sort(edges.begin(), edges.end(), [](const NetEdge& a, const NetEdge& b) { return a.id < b.id; });
  // Junction ids sort differently from edge ids ("s10_a" < "s1_a").
  std::vector<std::pair<std::string, std::pair<std::size_t, bool>>> junctions;
  junctions.reserve(2 * edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    junctions.push_back({edges[e].id + "_a", {e, true}});
    junctions.push_back({edges[e].id + "_b", {e, false}});
  }
  std::sort(junctions.begin(), junctions.end());

  fmt::memory_buffer xml;
  Out out(xml);
  fmt::format_to(out,
                 "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n"
                 "<!-- generated by vsd-sumo {}: the network netconvert builds from the roads' plain XML -->\n\n"
                 "<net version=\"1.9\" junctionCornerDetail=\"5\" limitTurnSpeed=\"5.50\" "
                 "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
                 "xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/net_file.xsd\">\n\n",
                 toolVersion());
  if (!edges.empty()) {
    const std::string boundary =
        fmt::format("{:.2f},{:.2f},{:.2f},{:.2f}", bounds.lo.x(), bounds.lo.y(), bounds.hi.x(), bounds.hi.y());
    fmt::format_to(out,
                   "    <location netOffset=\"0.00,0.00\" convBoundary=\"{0}\" origBoundary=\"{0}\" "
                   "projParameter=\"!\"/>\n\n",
                   boundary);
  }
  for (const auto& edge : edges) writeEdge(out, edge);
  fmt::format_to(out, "\n");
  for (const auto& [id, where] : junctions) writeJunction(out, edges[where.first], where.second);
  fmt::format_to(out, "\n</net>\n");

  const fs::path net = stem.string() + ".net.xml";
  std::ofstream stream(net, std::ios::binary | std::ios::trunc);
  stream.write(xml.data(), static_cast<std::streamsize>(xml.size()));
  if (!stream) throw IoError(net.string() + ": cannot write the SUMO network");
  return net;
}

}  // namespace vsd::road
