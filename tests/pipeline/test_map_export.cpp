#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/pipeline/map_export.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/road/map_importers.hpp"
#include "vsd/road/network.hpp"
#include "vsd/sim/map_simulation.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

const fs::path kOsmMap = "/usr/share/sumo/tools/game/A10KW.sumocfg";  // OSM import with its own demand (sumo-tools)

fs::path openDriveMap() { return test::sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.xodr"; }
fs::path openDriveRoutes() { return test::sourceDir() / "sumo_nets" / "opendrive_curve" / "curve.rou.xml"; }

ExportOptions openDriveExport(const fs::path& out) {
  ExportOptions options;
  options.openDrive = openDriveMap();
  options.source.routes = {openDriveRoutes()};
  options.output = out;
  options.end = 60.0;
  return options;
}

/// Issue 29: no valid instant of `reader`'s samples moves a vehicle impossibly — the
/// second difference of consecutive valid positions stays within 15 m/s^2, on every
/// vehicle polyline and on each Ego's path (history, t0, targets). Returns the instants checked.
std::size_t checkPossibleMotion(const vector::DatasetReader& reader) {
  const double dt = reader.header().step;
  std::size_t checked = 0;
  const auto check_run = [&](const std::vector<Vec2>& points, const std::string& what) {
    for (std::size_t k = 2; k < points.size(); ++k, ++checked) {
      const double acceleration = (points[k] - 2.0 * points[k - 1] + points[k - 2]).norm() / (dt * dt);
      EXPECT_LE(acceleration, 15.0 + 1e-3) << what << " at step " << k;
    }
  };
  for (std::size_t i = 0; i < reader.size(); ++i) {
    const auto scene = reader.scene(i);
    for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
      const auto& polyline = scene.polylines[p];
      if (polyline.type == vector::ObjectType::LaneBoundary) continue;
      const bool ego = polyline.type == vector::ObjectType::Ego;
      const std::size_t motions = ego ? polyline.vectors.size() - 1 : polyline.vectors.size();  // Ego: initial vector last
      std::vector<Vec2> run;
      for (std::size_t v = 0; v <= motions; ++v) {
        if (v == motions || !polyline.valid[v]) {
          if (!(ego && v == motions)) {
            check_run(run, fmt::format("sample {} polyline {}", i, p));
            run.clear();
          }
          continue;
        }
        const auto& f = polyline.vectors[v];
        if (run.empty()) run.emplace_back(f[0], f[1]);
        run.emplace_back(f[2], f[3]);
      }
      if (!ego) continue;
      // The Ego's path goes on through t0 into its valid targets.
      if (run.empty() || (run.back() - scene.egoInitialState().position()).norm() > 1e-3) {
        run.assign(1, scene.egoInitialState().position());
      }
      for (std::size_t k = 0; k < scene.target.size(); ++k) {
        if (!scene.targetValid[k]) break;
        run.push_back(scene.target[k]);
      }
      check_run(run, fmt::format("sample {} Ego {}", i, scene.provenance.egoId));
    }
  }
  return checked;
}

}  // namespace

TEST(Export, RealOsmMapGivesValidScenesAroundTheChosenEgos) {
  TemporaryDirectory dir;
  ExportOptions options;
  options.source.config = kOsmMap;
  options.output = dir.path() / "a10.h5";
  options.egos = "random:8";
  options.seed = 3;
  options.end = 45.0;
  const auto summary = exportMap(options);
  EXPECT_GT(summary.samples, 20u);
  EXPECT_LE(summary.egos, 8u);
  EXPECT_GT(summary.vehiclesSeen, 8u);

  const auto validation = vector::validateDataset(options.output);
  EXPECT_TRUE(validation.ok()) << (validation.problems.empty() ? "" : validation.problems.front());
  const vector::DatasetReader reader(options.output);
  EXPECT_EQ(reader.header().kind, "map");
  std::set<std::string> egos;
  bool masked_vehicle = false;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    const auto scene = reader.scene(i);
    egos.insert(scene.provenance.egoId);
    EXPECT_EQ(scene.label, "A10KW");
    EXPECT_EQ(scene.provenance.source, kOsmMap.string());
    EXPECT_EQ(scene.provenance.sourceSha256, sha256OfFile(kOsmMap));
    const Vec2 ego = scene.egoInitialState().position();
    std::size_t lanes = 0;
    for (const auto& polyline : scene.polylines) {
      for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
        if (!polyline.valid[v]) {
          masked_vehicle = true;
          continue;
        }
        const auto& f = polyline.vectors[v];
        const double nearest = std::min((Vec2(f[0], f[1]) - ego).norm(), (Vec2(f[2], f[3]) - ego).norm());
        if (polyline.type == vector::ObjectType::LaneBoundary) {
          ++lanes;
          EXPECT_LE(nearest, 60.0 + 5.0);  // within the radius (+ one vector length)
        } else if (polyline.type == vector::ObjectType::Vehicle) {
          EXPECT_LE(nearest, 60.0 + 10.0);
        }
      }
    }
    EXPECT_GT(lanes, 0u);
    // The target continues the Ego's motion (lane changes are continuous, no 3.5 m jumps).
    const double first_step = (scene.target.front() - ego).norm();
    EXPECT_NEAR(first_step, scene.egoInitialState().speed * 0.2, 1.5);
  }
  EXPECT_EQ(egos.size(), summary.egos);
  EXPECT_TRUE(masked_vehicle);  // vehicles entering or leaving the radius are masked, not dropped
  EXPECT_GT(checkPossibleMotion(reader), 1000u);
  EXPECT_NE(summary.report().find("masked as impossible motion"), std::string::npos);
}

// Issue 29: an Ego asked for that gives no sample is said, in one line of the summary.
TEST(Export, FewerEgosThanAskedAreSaid) {
  TemporaryDirectory dir;
  auto options = openDriveExport(dir.path() / "few.h5");
  options.egos = "east.0,east.14";  // east.14 departs at 56 s: no whole window before the end at 60 s
  const auto summary = exportMap(options);
  EXPECT_EQ(summary.egosAsked, 2u);
  EXPECT_EQ(summary.egos, 1u);
  EXPECT_NE(summary.report().find("only 1 of the 2 Egos asked for gave a sample (the others never stayed a whole "
                                  "window in the network)"),
            std::string::npos)
      << summary.report();
  checkPossibleMotion(vector::DatasetReader(options.output));

  // Where --max-samples ended the export, that is the reason given.
  options.output = dir.path() / "limited.h5";
  options.egos = "east.0,east.1";
  options.maxSamples = 1;
  const auto limited = exportMap(options);
  EXPECT_EQ(limited.egos, 1u);
  EXPECT_NE(limited.report().find("only 1 of the 2 Egos asked for gave a sample (--max-samples 1 ended the export "
                                  "before the others)"),
            std::string::npos)
      << limited.report();
}

TEST(Export, OpenDriveMapWithHistoryAndClosedLoop) {
  TemporaryDirectory dir;
  auto options = openDriveExport(dir.path() / "od.h5");
  options.history = 1.0;
  options.stride = 2.0;
  const auto summary = exportMap(options);
  EXPECT_GT(summary.samples, 10u);
  EXPECT_TRUE(vector::validateDataset(options.output).ok());
  const vector::DatasetReader reader(options.output);
  EXPECT_EQ(reader.header().history, 5);
  const auto scene = reader.scene(0);
  EXPECT_EQ(scene.polylines[scene.egoPolyline].vectors.size(), 6u);  // 5 history vectors + initial vector
  EXPECT_EQ(scene.label, "curve");

  auto closed = openDriveExport(dir.path() / "closed.h5");
  closed.egos = "vtype:truck";
  closed.closedLoop = true;
  closed.controllerParams = {{"time_gap", 3.0}};
  const auto closed_summary = exportMap(closed);
  EXPECT_TRUE(closed_summary.closedLoop);
  EXPECT_GT(closed_summary.samples, 0u);
  EXPECT_TRUE(vector::validateDataset(closed.output).ok());

  // Every vehicle keeps the size of its vType (curve.rou.xml: cars 5 x 1.8 m, trucks 12 x 2.5 m),
  // so gaps to and from the truck Egos are bumper to bumper.
  const vector::DatasetReader trucks(closed.output);
  std::set<std::pair<double, double>> other_sizes;
  for (std::size_t i = 0; i < trucks.size(); ++i) {
    const auto truck_scene = trucks.scene(i);
    const auto& ego = truck_scene.polylines[truck_scene.egoPolyline];
    EXPECT_EQ(ego.length, 12.0);
    EXPECT_EQ(ego.width, 2.5);
    for (const auto& polyline : truck_scene.polylines) {
      if (polyline.type == vector::ObjectType::Vehicle) other_sizes.emplace(polyline.length, polyline.width);
    }
  }
  EXPECT_TRUE(other_sizes.count({5.0, 1.8})) << "no car next to a truck Ego";
  for (const auto& size : other_sizes) {
    EXPECT_TRUE(size == std::make_pair(5.0, 1.8) || size == std::make_pair(12.0, 2.5)) << size.first << " x " << size.second;
  }
}

TEST(Export, BadInputIsRejectedAndLeavesNoFile) {
  TemporaryDirectory dir;
  auto expect_error = [&](ExportOptions options, const std::string& expected) {
    options.output = dir.path() / "out.h5";
    try {
      exportMap(options);
      ADD_FAILURE() << "expected an error containing: " << expected;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
    }
    EXPECT_FALSE(fs::exists(dir.path() / "out.h5")) << expected;
    for (const auto& entry : fs::directory_iterator(dir.path())) {
      EXPECT_EQ(entry.path().filename().string().find(".out.h5"), std::string::npos) << "temporary file left";
    }
  };
  auto never = openDriveExport("");
  never.egos = "east.0,ghost42";
  expect_error(never, "vehicle 'ghost42' never appears");
  auto empty = openDriveExport("");
  empty.egos = "vtype:bus";
  expect_error(empty, "no vehicle of that type");
  auto too_long = openDriveExport("");
  too_long.end = 3.0;
  expect_error(too_long, "is longer than the simulation");
  auto too_many = openDriveExport("");
  too_many.egos = "random:1000";
  expect_error(too_many, "only");
  auto broken = openDriveExport("");
  broken.openDrive = test::writeFile(dir.path() / "broken.xodr", "<OpenDRIVE><road></OpenDRIVE>");
  expect_error(broken, "netconvert rejects");
  ExportOptions missing_net;
  missing_net.source.config = test::writeFile(
      dir.path() / "bad.sumocfg",
      "<configuration><input><net-file value=\"nowhere.net.xml\"/></input></configuration>");
  expect_error(missing_net, "SUMO could not load");
  ExportOptions no_map;
  expect_error(no_map, "no map given");
  auto bad_stride = openDriveExport("");
  bad_stride.stride = 0.3;
  expect_error(bad_stride, "--stride");
  EXPECT_THROW(EgoSelection::parse("random:zero"), ConfigError);
  EXPECT_THROW(EgoSelection::parse("a,,b"), ConfigError);
  EXPECT_EQ(EgoSelection::parse("veh12,veh40").ids.size(), 2u);
}

TEST(Export, GeneratedAndExportedSamplesAreTheSameKindOfObject) {
  TemporaryDirectory dir;
  RunOptions run;
  run.scenarioFile = test::scenarioFile("acc.yaml");
  run.outputDir = dir.path() / "acc";
  run.samples = 20;
  runScenarios(run);
  exportMap(openDriveExport(dir.path() / "od.h5"));

  vector::DatasetCollection collection;
  collection.add(dir.path() / "acc");  // a run folder: its dataset.h5
  collection.add(dir.path() / "od.h5");
  const auto counts = collection.labelCounts();
  EXPECT_EQ(counts.at("acc"), 20u);
  EXPECT_GT(counts.at("curve"), 0u);
  for (const auto& ref : {collection.withLabel("acc").front(), collection.withLabel("curve").front()}) {
    const auto scene = collection.scene(ref);
    EXPECT_EQ(scene.polylines.front().type, vector::ObjectType::LaneBoundary);
    EXPECT_EQ(scene.egoPolyline, scene.polylines.size() - 1);
    EXPECT_EQ(scene.polylines.back().type, vector::ObjectType::Ego);
    EXPECT_EQ(scene.target.size(), 25u);
    EXPECT_DOUBLE_EQ(scene.step, 0.2);
  }
  for (const auto& path : {dir.path() / "acc" / "dataset.h5", dir.path() / "od.h5"}) {
    EXPECT_TRUE(vector::validateDataset(path).ok()) << path;
  }
}

// A bus that parks at a stop (parking="true") is drawn beside the lane by SUMO: its
// position jumps sideways in one step. Parked instants are masked (other vehicles)
// or leave the window out (Egos), so no trajectory in the dataset holds the jump.
TEST(Export, ParkedVehiclesNeverJumpIntoTrajectories) {
  TemporaryDirectory dir;
  const auto routes = test::writeFile(dir.path() / "parking.rou.xml", R"(<routes>
  <vType id="car" length="5.0" width="1.8" maxSpeed="20" accel="2.6" decel="4.5" sigma="0"/>
  <vType id="bus" length="12.0" width="2.5" maxSpeed="15" accel="1.2" decel="4.0" sigma="0" vClass="bus"/>
  <vehicle id="bus" type="bus" depart="0" departSpeed="max"><route edges="-1"/>
    <stop lane="-1_0" endPos="150" duration="12" parking="true"/></vehicle>
  <flow id="east" type="car" begin="1" end="40" period="6" from="-1" to="-1" departSpeed="max"/>
</routes>)");
  auto options = openDriveExport(dir.path() / "parking.h5");
  options.source.routes = {routes};
  const auto summary = exportMap(options);
  EXPECT_GT(summary.parkedSteps, 40u);  // 12 s parked at 0.2 s steps
  EXPECT_NE(summary.report().find("parked"), std::string::npos);

  const vector::DatasetReader reader(options.output);
  // A 3 m sideways jump from standstill (a parked vehicle reappearing) would imply ~75 m/s^2.
  checkPossibleMotion(reader);
  std::size_t bus_seen = 0;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    if (reader.scene(i).provenance.egoId == "bus") ++bus_seen;
  }
  EXPECT_GT(bus_seen, 0u);  // windows of the bus before and after parking remain
}

namespace {

/// The curve map's network (its two lanes: "-1_0" along the road's s, "1_0" against it).
sim::MapSimulationOptions curveSimulation(const TemporaryDirectory& dir) {
  sim::MapSimulationOptions options;
  const auto registry = road::MapImporterRegistry::withBuiltins();
  options.source.net = registry.forFile(openDriveMap()).toNet(openDriveMap(), dir.path());
  options.step = 0.1;
  options.end = 20.0;
  return options;
}

sim::PlacedRoadUser placedAt(const std::string& id, const Vec2& centre, double heading, double speed) {
  sim::PlacedRoadUser user;
  user.id = id;
  user.centre = centre;
  user.heading = heading;
  user.speed = speed;
  user.where = "test.xosc:" + id;
  return user;
}

}  // namespace

// Road users an imported scenario places on a network start on the lane under them, facing its
// way, and keep their speed along the road (round the curve onto its last straight), whatever is
// ahead; one placed off its lane's centre line, facing against its lane or on no lane is refused
// by name.
TEST(MapSimulation, PlacedRoadUsersStartOnTheirLaneAndFollowTheRoadAtTheirSpeed) {
  TemporaryDirectory dir;
  auto options = curveSimulation(dir);
  // The curve map's right lane (-1) runs along +x at y = -1.75 on its first straight; its left
  // lane (1) the other way at y = +1.75. A slow car 30 m ahead of a scripted one on its lane.
  options.placed = {placedAt("slow", {50.0, -1.75}, 0.0, 2.0), placedAt("scripted", {20.0, -1.75}, 0.0, 12.0),
                    placedAt("oncoming", {60.0, 1.75}, kPi, 5.0)};
  options.placed[0].holdsSpeed = false;  // SUMO drives it
  {
    sim::MapSimulation simulation(options);
    while (simulation.time() < 10.0 - 1e-9) ASSERT_TRUE(simulation.step());
    // SUMO inserts them at the end of the first step (t = 0.1 s) where they were placed; they
    // have moved for 9.9 s since.
    const auto* scripted = simulation.vehicle("scripted");
    ASSERT_NE(scripted, nullptr);
    EXPECT_NEAR(scripted->state.speed, 12.0, 1e-9);  // through the slow car ahead: a script is kept
    // 118.8 m along its lane from x = 20: 80 m to the arc, then 38.8 m round it on a radius of
    // 100 + 1.75 m (the lane lies 1.75 m right of the reference line).
    const double angle = (12.0 * 9.9 - 80.0) / 101.75;
    const Vec2 expected(100.0 + 101.75 * std::sin(angle), 100.0 - 101.75 * std::cos(angle));
    EXPECT_LT((scripted->state.position() - expected).norm(), 0.1) << scripted->state.position().transpose();
    const auto* oncoming = simulation.vehicle("oncoming");
    ASSERT_NE(oncoming, nullptr);
    EXPECT_NEAR(oncoming->state.x, 60.0 - 5.0 * 9.9, 0.01);
    EXPECT_NEAR(oncoming->state.y, 1.75, 0.01);
    const auto* slow = simulation.vehicle("slow");
    ASSERT_NE(slow, nullptr);
    EXPECT_GT(slow->state.speed, 2.5);  // SUMO drives it: it speeds up
  }

  const auto refused = [&](const sim::PlacedRoadUser& user) {
    auto bad = curveSimulation(dir);
    bad.placed = {user};
    try {
      sim::MapSimulation refusing(bad);
      refusing.step();
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string("not refused");
  };
  EXPECT_THAT(refused(placedAt("beside", {20.0, -0.75}, 0.0, 5.0)),
              testing::HasSubstr("test.xosc:beside: road user 'beside' at (20.00, -0.75) lies 1.00 m beside the "
                                 "centre line of its lane"));
  EXPECT_THAT(refused(placedAt("wrong_way", {20.0, -1.75}, kPi, 5.0)),
              testing::HasSubstr("faces against the direction of its lane"));
  EXPECT_THAT(refused(placedAt("off_road", {298.0, -1.75}, 0.0, 5.0)), testing::HasSubstr("m beside the centre line"));
  // 1 m before the end of the last straight (heading 1 rad): its front would stick out.
  const Vec2 end(184.1470984807897 + 100.0 * std::cos(1.0), 45.96976941318602 + 100.0 * std::sin(1.0));
  const Vec2 right_lane = end + 1.75 * Vec2(std::sin(1.0), -std::cos(1.0)) - 1.0 * Vec2(std::cos(1.0), std::sin(1.0));
  EXPECT_THAT(refused(placedAt("at_the_end", right_lane, 1.0, 5.0)),
              testing::HasSubstr("reaches beyond the end of its lane -1_0"));
}

// A scripted road user keeps its lane until the lane ends: where the road goes on in another
// lane, it changes onto that one (SUMO's lane change, the map's 2 s) at its speed, rather than
// stopping at the end of its own.
TEST(MapSimulation, AScriptedRoadUserWhoseLaneEndsGoesOnInTheLaneThatContinues) {
  TemporaryDirectory dir;
  // 300 m along +x; right of the reference line lane -1 (3.5 m) and lane -2, which closes from
  // 3.5 m to nothing between s = 100 and 120 m.
  const auto xodr = test::writeFile(dir.path() / "closing.xodr", R"(<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="closing"/>
  <road name="closing" length="300.0" id="1" junction="-1"><link/>
    <planView><geometry s="0" x="0" y="0" hdg="0" length="300"><line/></geometry></planView>
    <lanes><laneSection s="0">
      <center><lane id="0" type="none" level="false"><link/></lane></center>
      <right>
        <lane id="-1" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        <lane id="-2" type="driving" level="false"><link/>
          <width sOffset="0" a="3.5" b="0" c="0" d="0"/>
          <width sOffset="100" a="3.5" b="0" c="-0.02625" d="0.000875"/>
          <width sOffset="120" a="0" b="0" c="0" d="0"/>
        </lane>
      </right>
    </laneSection></lanes>
  </road>
</OpenDRIVE>)");
  sim::MapSimulationOptions options;
  options.source.net = dir.path() / "closing.net.xml";
  road::convertOpenDrive(xodr, options.source.net, road::OpenDriveOrigin::AsWritten);
  options.step = 0.1;
  options.end = 15.0;
  options.placed = {placedAt("merging", {20.0, -5.25}, 0.0, 10.0)};
  sim::MapSimulation simulation(options);
  while (simulation.step()) {
  }
  const auto* merging = simulation.vehicle("merging");
  ASSERT_NE(merging, nullptr);
  EXPECT_NEAR(merging->state.speed, 10.0, 1e-9);
  EXPECT_NEAR(merging->state.x, 20.0 + 10.0 * 14.9, 0.5);  // along the road at its speed all the way
  EXPECT_NEAR(merging->state.y, -1.75, 0.05);                 // in lane -1, the one that goes on
}

// A road user is not placed inside a junction: its lanes there are SUMO's connections, which no
// scenario's position names.
TEST(MapSimulation, ARoadUserPlacedInsideAJunctionIsRefused) {
  TemporaryDirectory dir;
  // A T: A (0, 0) -> B (100, 0) -> C (200, 0), and B -> D (100, 100); SUMO's junction at B.
  test::writeFile(dir.path() / "t.nod.xml", R"(<nodes><node id="A" x="0" y="0"/><node id="B" x="100" y="0"/>
    <node id="C" x="200" y="0"/><node id="D" x="100" y="100"/></nodes>)");
  test::writeFile(dir.path() / "t.edg.xml", R"(<edges><edge id="AB" from="A" to="B"/><edge id="BC" from="B" to="C"/>
    <edge id="BD" from="B" to="D"/></edges>)");
  road::ensureSumoHome();
  sim::MapSimulationOptions options;
  options.source.net = dir.path() / "t.net.xml";
  const auto converted = test::run({"netconvert", "-n", (dir.path() / "t.nod.xml").string(), "-e",
                                    (dir.path() / "t.edg.xml").string(), "-o", options.source.net.string()},
                                   dir.path());
  ASSERT_EQ(converted.exitCode, 0) << converted.output;
  options.step = 0.1;
  options.placed = {placedAt("crossing", {101.0, -1.6}, 0.0, 5.0)};  // on the straight connection through B
  EXPECT_THAT(test::configErrorOf([&] { sim::MapSimulation simulation(options); }),
              testing::HasSubstr("test.xosc:crossing: road user 'crossing' at (101.00, -1.60) lies inside a junction "
                                 "(lane :B_0_0)"));
  options.placed = {placedAt("before", {50.0, -1.6}, 0.0, 20.0)};  // on AB: placed; at B it goes straight on
  options.end = 4.0;
  sim::MapSimulation simulation(options);
  while (simulation.step()) {
  }
  const auto* before = simulation.vehicle("before");
  ASSERT_NE(before, nullptr);
  EXPECT_NEAR(before->state.x, 50.0 + 20.0 * 3.9, 0.5);  // on BC, not turned onto BD
  EXPECT_NEAR(before->state.y, -1.6, 0.05);
}
