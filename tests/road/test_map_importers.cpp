// Map importers: the registry picks the entry by the file, and a format added from outside
// (the test's own file plus one registry line) is converted through the same path.
#include <gtest/gtest.h>

#include <pugixml.hpp>

#include "extension/straight_road_importer.hpp"
#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/road/map_importers.hpp"

using namespace vsd;
using namespace vsd::road;

namespace {

/// Lane id -> length (m) of the normal (non-internal) lanes of a SUMO network.
std::map<std::string, double> laneLengths(const std::filesystem::path& net) {
  pugi::xml_document document;
  EXPECT_TRUE(document.load_file(net.c_str()));
  std::map<std::string, double> lengths;
  for (const auto& edge : document.child("net").children("edge")) {
    if (std::string(edge.attribute("function").as_string()) == "internal") continue;
    for (const auto& lane : edge.children("lane")) lengths[lane.attribute("id").as_string()] = lane.attribute("length").as_double();
  }
  return lengths;
}

}  // namespace

TEST(MapImporters, TheFileChoosesTheEntry) {
  const auto registry = MapImporterRegistry::withBuiltins();
  EXPECT_EQ(registry.forFile("maps/Curve.XODR").name, "opendrive");
  EXPECT_EQ(registry.forFile("maps/town.net.xml").name, "sumo");
  const auto message = test::configErrorOf([&] { registry.forFile("maps/town.osm"); });
  EXPECT_NE(message.find("town.osm"), std::string::npos) << message;
  EXPECT_NE(message.find(".xodr (opendrive)"), std::string::npos) << message;
  EXPECT_NE(test::configErrorOf([&] { registry.find("lanelet2"); }).find("known: sumo, opendrive"), std::string::npos);
}

TEST(MapImporters, OpenDriveBecomesASumoNetwork) {
  TemporaryDirectory dir;
  const auto map = test::sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.xodr";
  const auto registry = MapImporterRegistry::withBuiltins();
  const auto net = registry.forFile(map).toNet(map, dir.path());
  EXPECT_FALSE(laneLengths(net).empty());
  // A SUMO network needs no conversion: it is its own network.
  EXPECT_EQ(registry.forFile(net).toNet(net, dir.path()), net);
}

TEST(MapImporters, ANewFormatIsOneFileAndOneRegistryLine) {
  auto registry = MapImporterRegistry::withBuiltins();
  registry.add(test::straightRoadImporter());  // the one line a newcomer writes

  TemporaryDirectory dir;
  const auto map = test::writeFile(dir.path() / "short.straight", "120 2\n");
  const auto& importer = registry.forFile(map);
  ASSERT_EQ(importer.name, "straight");
  const auto lanes = laneLengths(importer.toNet(map, dir.path()));
  ASSERT_EQ(lanes.size(), 2u);
  for (const auto& [id, length] : lanes) EXPECT_NEAR(length, 120.0, 0.5) << id;
  // Bad input of the new format is the format's own one-line error.
  const auto bad = test::writeFile(dir.path() / "bad.straight", "long road\n");
  EXPECT_NE(test::configErrorOf([&] { importer.toNet(bad, dir.path()); }).find("expected '<length m> <lanes>'"),
            std::string::npos);
  // Each ending belongs to one entry.
  EXPECT_NE(test::configErrorOf([&] { registry.add(test::straightRoadImporter()); }).find("registered twice"),
            std::string::npos);
}
