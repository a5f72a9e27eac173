#include "vsd/interop/roundtrip.hpp"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "vsd/core/error.hpp"
#include "vsd/interop/opendrive.hpp"
#include "vsd/road/network.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

std::map<std::string, Polyline> readNetLanes(const fs::path& net) {
  pugi::xml_document document;
  const auto result = document.load_file(net.c_str());
  if (!result) throw DatasetError(fmt::format("{}: cannot read SUMO network ({})", net.string(), result.description()));
  std::map<std::string, Polyline> lanes;
  for (const pugi::xml_node& edge : document.child("net").children("edge")) {
    if (edge.attribute("function")) continue;  // internal (junction) edges
    for (const pugi::xml_node& lane : edge.children("lane")) {
      Polyline shape;
      std::istringstream stream(lane.attribute("shape").value());
      std::string point;
      while (stream >> point) {
        double x = 0.0;
        double y = 0.0;
        if (std::sscanf(point.c_str(), "%lf,%lf", &x, &y) != 2) {
          throw DatasetError(fmt::format("{}: lane {}: malformed shape point '{}'", net.string(),
                                         lane.attribute("id").value(), point));
        }
        shape.emplace_back(x, y);
      }
      lanes[lane.attribute("id").value()] = std::move(shape);
    }
  }
  return lanes;
}

namespace {

/// Nearest-segment queries on a polyline in O(log n) typical time: a static tree of
/// axis-aligned boxes over its segments, built by median splits (O(n log n)), searched
/// branch and bound. A road of 100 km has 200,000 vertices: comparing every vertex with
/// every segment (the obvious way) takes minutes, this takes milliseconds.
class SegmentTree {
 public:
  explicit SegmentTree(const Polyline& points) : points_(points) {
    order_.resize(points.size() - 1);
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
    nodes_.reserve(2 * order_.size());
    build(0, order_.size());
  }

  /// Distance from `p` to the nearest segment.
  double distance(const Vec2& p) const {
    double best_sq = std::numeric_limits<double>::infinity();
    search(0, p, best_sq);
    return std::sqrt(best_sq);
  }

 private:
  struct Node {
    Vec2 low, high;
    std::size_t begin = 0, end = 0;     ///< segments order_[begin, end) (leaves)
    std::size_t left = 0, right = 0;    ///< children (0: a leaf; node 0 is the root)
  };
  static constexpr std::size_t kLeafSize = 8;

  std::size_t build(std::size_t begin, std::size_t end) {
    const std::size_t index = nodes_.size();
    nodes_.emplace_back();
    Vec2 low(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
    Vec2 high = -low;
    for (std::size_t i = begin; i < end; ++i) {
      for (const Vec2& q : {points_[order_[i]], points_[order_[i] + 1]}) {
        low = low.cwiseMin(q);
        high = high.cwiseMax(q);
      }
    }
    nodes_[index].low = low;
    nodes_[index].high = high;
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    if (end - begin <= kLeafSize) return index;
    const int axis = (high.x() - low.x()) >= (high.y() - low.y()) ? 0 : 1;
    const std::size_t middle = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + static_cast<std::ptrdiff_t>(begin), order_.begin() + static_cast<std::ptrdiff_t>(middle),
                     order_.begin() + static_cast<std::ptrdiff_t>(end), [&](std::size_t a, std::size_t b) {
                       return points_[a][axis] + points_[a + 1][axis] < points_[b][axis] + points_[b + 1][axis];
                     });
    const std::size_t left = build(begin, middle);
    const std::size_t right = build(middle, end);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }

  static double boxDistanceSq(const Node& node, const Vec2& p) {
    const Vec2 outside = (node.low - p).cwiseMax(p - node.high).cwiseMax(Vec2::Zero());
    return outside.squaredNorm();
  }

  double segmentDistanceSq(std::size_t segment, const Vec2& p) const {
    const Vec2 start = points_[segment];
    const Vec2 delta = points_[segment + 1] - start;
    const double length_sq = delta.squaredNorm();
    const double fraction = length_sq > 0.0 ? std::clamp((p - start).dot(delta) / length_sq, 0.0, 1.0) : 0.0;
    return (p - (start + fraction * delta)).squaredNorm();
  }

  void search(std::size_t index, const Vec2& p, double& best_sq) const {
    const Node& node = nodes_[index];
    if (boxDistanceSq(node, p) >= best_sq) return;
    if (node.left == 0) {
      for (std::size_t i = node.begin; i < node.end; ++i) best_sq = std::min(best_sq, segmentDistanceSq(order_[i], p));
      return;
    }
    // The nearer child first: its result prunes the other.
    const bool left_first = boxDistanceSq(nodes_[node.left], p) <= boxDistanceSq(nodes_[node.right], p);
    search(left_first ? node.left : node.right, p, best_sq);
    search(left_first ? node.right : node.left, p, best_sq);
  }

  const Polyline& points_;
  std::vector<std::size_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace

double polylineDeviation(const Polyline& a, const Polyline& b) {
  if (a.size() < 2 || b.size() < 2) return std::numeric_limits<double>::infinity();
  const SegmentTree tree_a(a);
  const SegmentTree tree_b(b);
  double worst = 0.0;
  for (const Vec2& p : a) worst = std::max(worst, tree_b.distance(p));
  for (const Vec2& p : b) worst = std::max(worst, tree_a.distance(p));
  return worst;
}

std::vector<Polyline> netconvertLanes(const fs::path& xodr, const std::string& road_id, const fs::path& work_dir) {
  const fs::path net = work_dir / (xodr.stem().string() + ".net.xml");
  road::convertOpenDrive(xodr, net, road::OpenDriveOrigin::AsWritten);
  const auto lanes = readNetLanes(net);
  std::error_code ignored;
  fs::remove(net, ignored);
  // netconvert names the right-hand side of OpenDRIVE road R edge "-R", lanes from the right.
  std::vector<Polyline> result;
  for (int lane = 0;; ++lane) {
    const auto it = lanes.find(fmt::format("-{}_{}", road_id, lane));
    if (it == lanes.end()) break;
    result.push_back(it->second);
  }
  if (result.empty()) {
    throw SumoError(fmt::format("netconvert built no lanes for road {} of {}", road_id, xodr.string()));
  }
  return result;
}

std::vector<RoundTripDeviation> netconvertRoundTrip(const std::vector<scenario::ConcreteScenario>& scenarios,
                                                    const fs::path& work_dir) {
  std::vector<RoundTripDeviation> deviations;
  if (scenarios.empty()) return deviations;
  const road::BatchLayout layout(road::BatchLayout::cellSizeFor(scenarios.front().logical->road));
  road::NetworkBuilder builder;
  std::vector<road::RoadGeometry> roads;
  for (const auto& concrete : scenarios) {
    roads.push_back(road::buildRoadGeometry(concrete));
    builder.add(concrete.index, roads.back(), layout.offsetFor(concrete.index));
  }
  const fs::path stem = work_dir / "generated";
  builder.writePlainXml(stem);
  const auto generated = readNetLanes(
      road::PendingNetwork::start(stem, scenarios.front().logical->sumo.netconvertOptions).wait());

  for (std::size_t i = 0; i < scenarios.size(); ++i) {
    const auto index = scenarios[i].index;
    const fs::path xodr = work_dir / fmt::format("road_{}.xodr", index);
    writeOpenDrive(roads[i], fmt::format("sample {}", index), xodr);
    const auto imported = netconvertLanes(xodr, "1", work_dir);
    RoundTripDeviation deviation{index, 0.0};
    if (imported.size() != static_cast<std::size_t>(roads[i].lanes)) deviation.maxDeviation = std::numeric_limits<double>::infinity();
    for (int lane = 0; lane < roads[i].lanes && lane < static_cast<int>(imported.size()); ++lane) {
      Polyline reference = generated.at(fmt::format("{}_{}", road::edgeIdFor(index), lane));
      for (auto& point : reference) point -= layout.offsetFor(index);
      deviation.maxDeviation = std::max(deviation.maxDeviation, polylineDeviation(reference, imported[static_cast<std::size_t>(lane)]));
    }
    deviations.push_back(deviation);
  }
  return deviations;
}

}  // namespace vsd::interop
