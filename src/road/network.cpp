#include "vsd/road/network.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "vsd/core/error.hpp"
#include "vsd/core/numbers.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

BatchLayout::BatchLayout(double cell_size) : cellSize_(cell_size) {
  if (!(cell_size >= 100.0)) throw ConfigError(fmt::format("layout cell size {} m: expected >= 100 m", cell_size));
}

double BatchLayout::cellSizeFor(const scenario::RoadSpec& road) {
  // Arc roads start at the origin: no point of theirs is farther from it than its path length.
  double reach = std::max(std::abs(road.xMin) + road.extensionBefore, std::abs(road.xMax) + road.extensionAfter);
  if (road.shape == scenario::RoadSpec::Shape::Arc) {
    reach = std::max(road.extensionBefore, road.length.evaluate({}) + road.extensionAfter);
  } else if (road.shape == scenario::RoadSpec::Shape::Polyline) {
    double farthest = 0.0;
    for (const auto& [x, y] : road.centreLine) farthest = std::max(farthest, std::hypot(x, y));
    reach = farthest + std::max(road.extensionBefore, road.extensionAfter);
  }
  // Rounded up to 100 m so that offsets stay round numbers.
  return std::max(1000.0, std::ceil((2.0 * reach + 200.0) / 100.0) * 100.0);
}

Vec2 BatchLayout::offsetFor(std::uint64_t sample_index) const {
  const std::uint64_t slot = sample_index % kMaxBatch;
  // Cells start one cell away from the origin so that no net coordinate is negative.
  const auto column = static_cast<double>(slot % kColumns + 1);
  const auto row = static_cast<double>(slot / kColumns + 1);
  return {column * cellSize_, row * cellSize_};
}

bool BatchLayout::fits(const RoadGeometry& road) const {
  constexpr double kMargin = 25.0;
  const auto [lo, hi] = road.bounds();
  const double half = 0.5 * cellSize_ - kMargin;
  return lo.x() >= -half && lo.y() >= -half && hi.x() <= half && hi.y() <= half;
}

std::string edgeIdFor(std::uint64_t index) { return fmt::format("s{}", index); }

void ensureSumoHome() {
  const char* home = std::getenv("SUMO_HOME");
  if (home == nullptr || *home == '\0') ::setenv("SUMO_HOME", "/usr/share/sumo", 1);
}

void NetworkBuilder::add(std::uint64_t index, const RoadGeometry& road, const Vec2& offset) {
  roads_.push_back({index, road, offset, edgeShape(road, offset)});
}

NetWriter parseNetWriter(const std::string& text, const std::string& where) {
  if (text == "direct") return NetWriter::Direct;
  if (text == "netconvert") return NetWriter::Netconvert;
  throw ConfigError::field(where, "net writer", text, "direct or netconvert");
}

std::string netWriterName(NetWriter writer) { return writer == NetWriter::Direct ? "direct" : "netconvert"; }

Polyline NetworkBuilder::edgeShape(const RoadGeometry& road, const Vec2& offset) {
  // Exactly the decimal text of the plain XML ({:.6f}), parsed back.
  Polyline shape;
  shape.reserve(road.centre.size());
  for (const Vec2& point : road.centre) {
    const Vec2 net = point + offset;
    shape.emplace_back(asFixedDecimalText(net.x(), 6), asFixedDecimalText(net.y(), 6));
  }
  return shape;
}

namespace {

/// Ends an edge's element with its lanes: none changes lanes by SUMO's model
/// (kNoSumoLaneChanges); lanes wider or narrower than lane 0 get their own width (spreadType
/// center keeps them around the shape).
void writeLanes(fmt::memory_buffer& edges, const RoadGeometry& road) {
  fmt::format_to(std::back_inserter(edges), "\">\n");
  for (int lane = 0; lane < road.lanes; ++lane) {
    const bool own_width = road.laneWidthOf(lane) != road.laneWidthOf(0);
    fmt::format_to(std::back_inserter(edges), "    <lane index=\"{}\" {}{}/>\n", lane, kNoSumoLaneChanges,
                   own_width ? fmt::format(" width=\"{:.6f}\"", road.laneWidthOf(lane)) : "");
  }
  fmt::format_to(std::back_inserter(edges), "  </edge>\n");
}

}  // namespace

void NetworkBuilder::writePlainXml(const fs::path& stem) const {
  fmt::memory_buffer nodes;
  fmt::memory_buffer edges;
  fmt::format_to(std::back_inserter(nodes), "<nodes>\n");
  fmt::format_to(std::back_inserter(edges), "<edges>\n");
  for (const auto& placed : roads_) {
    const std::string id = edgeIdFor(placed.index);
    const Polyline shape = edgeShape(placed);
    const Vec2& first = shape.front();
    const Vec2& last = shape.back();
    fmt::format_to(std::back_inserter(nodes), "  <node id=\"{0}_a\" x=\"{1:.6f}\" y=\"{2:.6f}\" type=\"dead_end\"/>\n", id,
                   first.x(), first.y());
    fmt::format_to(std::back_inserter(nodes), "  <node id=\"{0}_b\" x=\"{1:.6f}\" y=\"{2:.6f}\" type=\"dead_end\"/>\n", id,
                   last.x(), last.y());
    fmt::format_to(std::back_inserter(edges),
                   "  <edge id=\"{0}\" from=\"{0}_a\" to=\"{0}_b\" numLanes=\"{1}\" width=\"{2:.6f}\" speed=\"{3:.3f}\" "
                   "spreadType=\"center\" shape=\"",
                   id, placed.road.lanes, placed.road.laneWidthOf(0), placed.road.speedLimit);
    for (std::size_t i = 0; i < shape.size(); ++i) {
      fmt::format_to(std::back_inserter(edges), "{}{:.6f},{:.6f}", i == 0 ? "" : " ", shape[i].x(), shape[i].y());
    }
    writeLanes(edges, placed.road);
  }
  fmt::format_to(std::back_inserter(nodes), "</nodes>\n");
  fmt::format_to(std::back_inserter(edges), "</edges>\n");
  auto write = [](const fs::path& path, const fmt::memory_buffer& buffer) {
    std::ofstream stream(path, std::ios::binary | std::ios::trunc);
    stream.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    if (!stream) throw IoError(path.string() + ": cannot write netconvert input");
  };
  write(fs::path(stem.string() + ".nod.xml"), nodes);
  write(fs::path(stem.string() + ".edg.xml"), edges);
}

std::vector<std::string> baseNetconvertOptions() {
  return {
      "--offset.disable-normalization", "true",  // net coordinates = generator coordinates + our offsets
      "--no-turnarounds", "true",               // disjoint roads: nothing to turn into
      "--geometry.remove", "false",             // keep every lane point
      "--no-warnings", "true",
  };
}

PendingNetwork PendingNetwork::start(const fs::path& stem, const std::vector<std::string>& extra_options) {
  ensureSumoHome();
  std::vector<std::string> argv = {"netconvert",
                                   "--node-files", stem.string() + ".nod.xml",
                                   "--edge-files", stem.string() + ".edg.xml",
                                   "--output-file", stem.string() + ".net.xml"};
  const auto base = baseNetconvertOptions();
  argv.insert(argv.end(), base.begin(), base.end());
  argv.insert(argv.end(), extra_options.begin(), extra_options.end());
  const fs::path log = stem.string() + ".netconvert.log";
  std::error_code ignored;
  fs::remove(log, ignored);
  return PendingNetwork(ChildProcess::spawn(argv, log), stem, stem.string() + ".net.xml");
}

PendingNetwork PendingNetwork::ready(const fs::path& net) { return PendingNetwork(std::nullopt, {}, net); }

fs::path PendingNetwork::wait() {
  if (!process_) return net_;
  const auto result = process_->wait();
  process_.reset();
  if (result.exitCode != 0 || !fs::exists(net_)) {
    throw SumoError(fmt::format("netconvert failed (exit code {}) on {}.nod.xml/.edg.xml: {}", result.exitCode,
                                stem_.string(), firstErrorLine(result.output)));
  }
  return net_;
}

}  // namespace vsd::road
