#include "vsd/interop/roundtrip.hpp"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <sstream>

#include "vsd/core/error.hpp"
#include "vsd/core/process.hpp"
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

double polylineDeviation(const Polyline& a, const Polyline& b) {
  if (a.size() < 2 || b.size() < 2) return std::numeric_limits<double>::infinity();
  const MeasuredPolyline measured_a(a);
  const MeasuredPolyline measured_b(b);
  double worst = 0.0;
  for (const Vec2& p : a) worst = std::max(worst, (measured_b.project(p).foot - p).norm());
  for (const Vec2& p : b) worst = std::max(worst, (measured_a.project(p).foot - p).norm());
  return worst;
}

void importWithNetconvert(const fs::path& xodr, const fs::path& net) {
  road::ensureSumoHome();
  const fs::path log = net.string() + ".log";
  const auto result = runProcess({"netconvert", "--opendrive-files", xodr.string(), "--output-file", net.string(),
                                  "--offset.disable-normalization", "true", "--no-warnings", "true"},
                                 log);
  std::error_code ignored;
  fs::remove(log, ignored);
  if (result.exitCode != 0 || !fs::exists(net)) {
    fs::remove(net, ignored);
    throw SumoError(fmt::format("netconvert rejects {} (exit code {}): {}", xodr.string(), result.exitCode,
                                firstErrorLine(result.output)));
  }
}

std::vector<Polyline> netconvertLanes(const fs::path& xodr, const std::string& road_id, const fs::path& work_dir) {
  const fs::path net = work_dir / (xodr.stem().string() + ".net.xml");
  importWithNetconvert(xodr, net);
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
