#include "vsd/road/network.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "vsd/core/error.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

BatchLayout::BatchLayout(double cell_size) : cellSize_(cell_size) {
  if (!(cell_size >= 100.0)) throw ConfigError(fmt::format("layout cell size {} m: expected >= 100 m", cell_size));
}

double BatchLayout::cellSizeFor(const scenario::RoadSpec& road) {
  const double reach = std::max(std::abs(road.xMin) + road.extensionBefore, std::abs(road.xMax) + road.extensionAfter);
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
  roads_.push_back({index, road, offset});
}

void NetworkBuilder::writePlainXml(const fs::path& stem) const {
  fmt::memory_buffer nodes;
  fmt::memory_buffer edges;
  fmt::format_to(std::back_inserter(nodes), "<nodes>\n");
  fmt::format_to(std::back_inserter(edges), "<edges>\n");
  for (const auto& placed : roads_) {
    const std::string id = edgeIdFor(placed.index);
    const Vec2 first = placed.road.centre.front() + placed.offset;
    const Vec2 last = placed.road.centre.back() + placed.offset;
    fmt::format_to(std::back_inserter(nodes), "  <node id=\"{0}_a\" x=\"{1:.6f}\" y=\"{2:.6f}\" type=\"dead_end\"/>\n", id,
                   first.x(), first.y());
    fmt::format_to(std::back_inserter(nodes), "  <node id=\"{0}_b\" x=\"{1:.6f}\" y=\"{2:.6f}\" type=\"dead_end\"/>\n", id,
                   last.x(), last.y());
    fmt::format_to(std::back_inserter(edges),
                   "  <edge id=\"{0}\" from=\"{0}_a\" to=\"{0}_b\" numLanes=\"{1}\" width=\"{2:.6f}\" speed=\"{3:.3f}\" "
                   "spreadType=\"center\" shape=\"",
                   id, placed.road.lanes, placed.road.laneWidth, placed.road.speedLimit);
    for (std::size_t i = 0; i < placed.road.centre.size(); ++i) {
      const Vec2 p = placed.road.centre[i] + placed.offset;
      fmt::format_to(std::back_inserter(edges), "{}{:.6f},{:.6f}", i == 0 ? "" : " ", p.x(), p.y());
    }
    fmt::format_to(std::back_inserter(edges), "\"/>\n");
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

void convertOpenDrive(const fs::path& xodr, const fs::path& net) {
  ensureSumoHome();
  if (!fs::exists(xodr)) throw ConfigError(fmt::format("{}: OpenDRIVE file does not exist", xodr.string()));
  const fs::path log = net.string() + ".netconvert.log";
  const auto result = runProcess({"netconvert", "--opendrive-files", xodr.string(), "--output-file", net.string(),
                                  "--no-warnings", "true"},
                                 log);
  std::error_code ignored;
  fs::remove(log, ignored);
  if (result.exitCode != 0 || !fs::exists(net)) {
    fs::remove(net, ignored);
    throw SumoError(fmt::format("netconvert cannot import OpenDRIVE map {} (exit code {}): {}", xodr.string(),
                                result.exitCode, firstErrorLine(result.output)));
  }
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
  return PendingNetwork(ChildProcess::spawn(argv, log), stem);
}

fs::path PendingNetwork::wait() {
  const auto result = process_.wait();
  const fs::path net = stem_.string() + ".net.xml";
  if (result.exitCode != 0 || !fs::exists(net)) {
    throw SumoError(fmt::format("netconvert failed (exit code {}) on {}.nod.xml/.edg.xml: {}", result.exitCode,
                                stem_.string(), firstErrorLine(result.output)));
  }
  return net;
}

}  // namespace vsd::road
