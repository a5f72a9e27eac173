// A test-only map format: a straight road given by its length and lane count, turned into
// SUMO plain XML and converted by netconvert.
#include "straight_road_importer.hpp"

#include <fmt/format.h>

#include <fstream>

#include "vsd/core/error.hpp"
#include "vsd/core/process.hpp"
#include "vsd/road/network.hpp"

namespace fs = std::filesystem;

namespace vsd::test {

namespace {

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream stream(path);
  stream << text;
  if (!stream) throw IoError(path.string() + ": cannot write");
}

fs::path convertStraightRoad(const fs::path& map, const fs::path& work_dir) {
  std::ifstream in(map);
  double length = 0.0;
  int lanes = 0;
  if (!(in >> length >> lanes) || length <= 0.0 || lanes < 1) {
    throw ConfigError(fmt::format("{}: expected '<length m> <lanes>'", map.string()));
  }
  const fs::path nodes = work_dir / "straight.nod.xml";
  const fs::path edges = work_dir / "straight.edg.xml";
  writeText(nodes, fmt::format("<nodes>\n  <node id=\"a\" x=\"0\" y=\"0\"/>\n  <node id=\"b\" x=\"{}\" y=\"0\"/>\n</nodes>\n",
                               length));
  writeText(edges, fmt::format("<edges>\n  <edge id=\"road\" from=\"a\" to=\"b\" numLanes=\"{}\" speed=\"30\"/>\n</edges>\n",
                               lanes));
  const fs::path net = work_dir / "straight.net.xml";
  road::ensureSumoHome();
  std::vector<std::string> argv = {"netconvert", "--node-files", nodes.string(), "--edge-files", edges.string(),
                                   "--output-file", net.string()};
  for (const auto& option : road::baseNetconvertOptions()) argv.push_back(option);
  const auto result = runProcess(argv, work_dir / "netconvert.log");
  if (result.exitCode != 0) throw SumoError(fmt::format("netconvert: {}", firstErrorLine(result.output)));
  return net;
}

}  // namespace

road::MapImporter straightRoadImporter() {
  road::MapImporter importer;
  importer.name = "straight";
  importer.description = "a straight road: '<length m> <lanes>' (test-only)";
  importer.extensions = {".straight"};
  importer.toNet = convertStraightRoad;
  return importer;
}

}  // namespace vsd::test
