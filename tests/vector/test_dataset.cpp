#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/vectorize.hpp"

using namespace vsd;
using namespace vsd::vector;
namespace fs = std::filesystem;

namespace {

/// A scene far from the origin (map coordinates), with a masked vector.
VectorizedScene sceneAt(const Vec2& origin, std::uint64_t sample, const std::string& label) {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.length = 4.6;
  ego.width = 1.9;
  VehicleTrack other;
  other.length = 12.0;  // a truck
  other.width = 2.55;
  for (int k = 0; k < 26; ++k) {
    ego.states.push_back({origin.x() + 2.0 * k, origin.y(), 0.0, 10.0, 0.0});
    other.states.push_back({origin.x() + 20.0 + 1.6 * k, origin.y() + 3.5, 0.0, 8.0, 0.0});
    ego.valid.push_back(1);
    other.valid.push_back(k == 7 ? 0 : 1);
  }
  trace.vehicles = {ego, other};
  LaneGeometry lane;
  lane.id = "l";
  lane.width = 3.5;
  lane.centre = {origin - Vec2(50, 0), origin + Vec2(100, 0)};
  auto scene = buildScene(label, trace, 0, regionLanePolylines({lane}, origin.x() - 40, origin.x() + 60));
  scene.sample = sample;
  scene.inputs = {1.5, static_cast<double>(sample)};
  scene.metrics = {-2.0};
  scene.provenance = {"map.sumocfg", "abc123", "veh" + std::to_string(sample), 12.4};
  return scene;
}

DatasetHeader header() {
  DatasetHeader h;
  h.step = 0.2;
  h.horizon = 25;
  h.inputNames = {"a", "b"};
  h.metricNames = {"a_min"};
  return h;
}

void expectSame(const VectorizedScene& a, const VectorizedScene& b, double tolerance) {
  ASSERT_EQ(a.polylines.size(), b.polylines.size());
  EXPECT_EQ(a.egoPolyline, b.egoPolyline);
  for (std::size_t p = 0; p < a.polylines.size(); ++p) {
    ASSERT_EQ(a.polylines[p].vectors.size(), b.polylines[p].vectors.size());
    EXPECT_EQ(a.polylines[p].valid, b.polylines[p].valid);
    EXPECT_EQ(a.polylines[p].type, b.polylines[p].type);
    EXPECT_NEAR(a.polylines[p].length, b.polylines[p].length, 1e-6) << p;  // vehicle sizes survive (schema 2)
    EXPECT_NEAR(a.polylines[p].width, b.polylines[p].width, 1e-6) << p;
    for (std::size_t v = 0; v < a.polylines[p].vectors.size(); ++v) {
      for (std::size_t f = 0; f < kFeatures; ++f) {
        EXPECT_NEAR(a.polylines[p].vectors[v][f], b.polylines[p].vectors[v][f], tolerance) << p << "/" << v << "/" << f;
      }
    }
  }
  ASSERT_EQ(a.target.size(), b.target.size());
  for (std::size_t k = 0; k < a.target.size(); ++k) EXPECT_LT((a.target[k] - b.target[k]).norm(), tolerance);
}

}  // namespace

TEST(Dataset, RoundTripKeepsMillimetresFarFromTheOrigin) {
  TemporaryDirectory dir;
  const auto path = dir.path() / "d.h5";
  std::vector<VectorizedScene> scenes;
  {
    DatasetWriter writer(path, header());
    for (std::uint64_t i = 0; i < 600; ++i) {  // more than one buffered chunk
      scenes.push_back(sceneAt(Vec2(4000.0 + 7.0 * static_cast<double>(i), -2500.0), i, i % 3 ? "acc" : "lk"));
      writer.append(scenes.back());
    }
    writer.close();
  }
  const DatasetReader reader(path);
  ASSERT_EQ(reader.size(), 600u);
  EXPECT_EQ(reader.header().inputNames, header().inputNames);
  for (std::size_t i : {0u, 255u, 256u, 599u}) {
    const auto scene = reader.scene(i);
    expectSame(scenes[i], scene, 1e-3);
    EXPECT_EQ(scene.label, scenes[i].label);
    EXPECT_EQ(scene.sample, i);
    EXPECT_EQ(scene.inputs, scenes[i].inputs);
    EXPECT_EQ(scene.metrics, scenes[i].metrics);
    EXPECT_EQ(scene.provenance.egoId, "veh" + std::to_string(i));
    EXPECT_EQ(scene.provenance.sourceSha256, "abc123");
    EXPECT_DOUBLE_EQ(scene.provenance.t0, 12.4);
  }
  EXPECT_EQ(reader.samplesWithLabel("lk").size(), 200u);
  EXPECT_TRUE(validateDataset(path).ok());
}

TEST(Dataset, SharedLanePoolIsStoredOnceAndReadBack) {
  TemporaryDirectory dir;
  LaneGeometry lane;
  lane.id = "road_0";
  lane.width = 3.2;
  lane.centre = {{0, 0}, {300, 0}, {400, 80}};
  const LaneIndex index({lane}, 5.0);
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.length = 5.0;
  ego.width = 1.8;
  for (int k = 0; k < 26; ++k) {
    ego.states.push_back({100.0 + 2.0 * k, 0.0, 0.0, 10.0, 0.0});
    ego.valid.push_back(1);
  }
  trace.vehicles = {ego};
  const auto scene = buildScene("map", trace, 0, index.query({100.0, 0.0}, 60.0));
  DatasetHeader map_header;
  map_header.kind = "map";
  map_header.step = 0.2;
  map_header.horizon = 25;
  const auto path = dir.path() / "map.h5";
  {
    DatasetWriter writer(path, map_header);
    writer.setSharedVectors(index.pool());
    for (int i = 0; i < 50; ++i) writer.append(scene);
    writer.close();
  }
  const DatasetReader reader(path);
  expectSame(scene, reader.scene(49), 1e-3);
  EXPECT_TRUE(validateDataset(path).ok());
  // 50 samples of ~50 lane vectors each, but the lane vectors are stored once: the inline
  // vectors are only each sample's Ego vector.
  H5::H5File file(path.string(), H5F_ACC_RDONLY);
  EXPECT_EQ(h5::shapeOf(file.openDataSet("vectors")).front(), 50u * scene.polylines.at(scene.egoPolyline).vectors.size());
  EXPECT_GT(h5::shapeOf(file.openDataSet("shared_vectors")).front(), 20u);
}

TEST(Dataset, ForeignCorruptAndUnknownFilesAreRejectedByName) {
  TemporaryDirectory dir;
  const auto text = test::writeFile(dir.path() / "notes.h5", "not hdf5 at all");
  try {
    DatasetReader reader(text);
    FAIL();
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("notes.h5: not an HDF5 file"), std::string::npos) << error.what();
  }
  EXPECT_THROW(DatasetReader(dir.path() / "missing.h5"), DatasetError);
  // Another schema version: written by a future vsd-sumo, or tampered with.
  const auto path = dir.path() / "future.h5";
  {
    DatasetWriter writer(path, header());
    writer.append(sceneAt(Vec2(0, 0), 0, "acc"));
    writer.close();
  }
  const auto script = test::writeFile(dir.path() / "bump.py",
                                      "import h5py, sys\nwith h5py.File(sys.argv[1], 'a') as f:\n"
                                      "    f.attrs['schema'] = 'vsd-dataset/4'\n");
  ASSERT_EQ(test::run({test::python(), script.string(), path.string()}, dir.path()).exitCode, 0);
  try {
    DatasetReader reader(path);
    FAIL();
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("'vsd-dataset/4' is not supported"), std::string::npos) << error.what();
  }
  const auto validation = validateDataset(path);
  EXPECT_FALSE(validation.ok());
  ASSERT_EQ(validation.problems.size(), 1u);
}

TEST(Dataset, VersionOneFilesStillReadWithAssumedVehicleSizes) {
  TemporaryDirectory dir;
  const auto path = dir.path() / "old.h5";
  {
    DatasetWriter writer(path, header());
    writer.append(sceneAt(Vec2(0, 0), 0, "acc"));
    writer.close();
  }
  // What vsd-sumo wrote before vehicle sizes were stored.
  const auto script = test::writeFile(dir.path() / "downgrade.py",
                                      "import h5py, sys\nwith h5py.File(sys.argv[1], 'a') as f:\n"
                                      "    f.attrs['schema'] = 'vsd-dataset/1'\n"
                                      "    del f['polyline_length']\n    del f['polyline_width']\n"
                                      "    del f['polyline_road_user']\n");
  ASSERT_EQ(test::run({test::python(), script.string(), path.string()}, dir.path()).exitCode, 0);
  const DatasetReader reader(path);
  EXPECT_TRUE(reader.header().vehicleSizesAssumed);
  const auto scene = reader.scene(0);
  for (const auto& polyline : scene.polylines) {
    const bool vehicle = polyline.type != ObjectType::LaneBoundary;
    EXPECT_EQ(polyline.length, vehicle ? kAssumedVehicleLength : 0.0);
    EXPECT_EQ(polyline.width, vehicle ? kAssumedVehicleWidth : 0.0);
  }
  EXPECT_TRUE(validateDataset(path).ok());
  EXPECT_NE(summarizeDataset(path).report().find("vsd-dataset/1"), std::string::npos);
}

// Road-user kinds travel with their polylines (vsd-dataset/3); files of version 2, which
// store none, are read with every road user a car.
TEST(Dataset, RoadUserKindsAreStoredAndVersionTwoFilesReadAsCars) {
  TemporaryDirectory dir;
  auto scene = sceneAt(Vec2(0, 0), 0, "acc");
  for (auto& polyline : scene.polylines) {
    if (polyline.type == ObjectType::Vehicle) polyline.roadUser = RoadUserType::Pedestrian;
  }
  const auto path = dir.path() / "kinds.h5";
  {
    DatasetWriter writer(path, header());
    writer.append(scene);
    writer.close();
  }
  const auto expect_kinds = [&](RoadUserType other) {
    const auto read = DatasetReader(path).scene(0);
    for (const auto& polyline : read.polylines) {
      if (polyline.type == ObjectType::Vehicle) {
        EXPECT_EQ(polyline.roadUser, other);
      } else if (polyline.type == ObjectType::Ego) {
        EXPECT_EQ(polyline.roadUser, RoadUserType::Car);
      }
    }
  };
  expect_kinds(RoadUserType::Pedestrian);
  const auto script = test::writeFile(dir.path() / "downgrade.py",
                                      "import h5py, sys\nwith h5py.File(sys.argv[1], 'a') as f:\n"
                                      "    f.attrs['schema'] = 'vsd-dataset/2'\n    del f['polyline_road_user']\n");
  ASSERT_EQ(test::run({test::python(), script.string(), path.string()}, dir.path()).exitCode, 0);
  EXPECT_TRUE(DatasetReader(path).header().roadUsersAssumed);
  expect_kinds(RoadUserType::Car);
  EXPECT_TRUE(validateDataset(path).ok());
}

TEST(Dataset, ValidationFindsBrokenInvariants) {
  TemporaryDirectory dir;
  auto scene = sceneAt(Vec2(0, 0), 0, "acc");
  scene.polylines[2].vectors[3][6] = 99.0;  // a timestamp beyond the horizon
  scene.polylines[0].vectors[0][5] = 7.0;   // a wrong polyline id
  const auto path = dir.path() / "bad.h5";
  {
    DatasetWriter writer(path, header());
    writer.append(scene);
    writer.close();
  }
  const auto validation = validateDataset(path);
  ASSERT_EQ(validation.problems.size(), 2u);
  EXPECT_NE(validation.problems[0].find("polyline_id"), std::string::npos) << validation.problems[0];
  EXPECT_NE(validation.problems[1].find("timestamp 99"), std::string::npos) << validation.problems[1];
}

// Numbers in a file that do not match the data are refused where they enter, naming
// the attribute or array: never a huge allocation, an out-of-range read or a crash.
TEST(Dataset, NumbersThatDoNotMatchTheDataAreRefusedByField) {
  TemporaryDirectory dir;
  const auto good = dir.path() / "good.h5";
  {
    DatasetWriter writer(good, header());
    for (std::uint64_t i = 0; i < 3; ++i) writer.append(sceneAt(Vec2(100.0 * static_cast<double>(i), 0), i, "acc"));
    writer.close();
  }
  // One Python process edits every copy (starting h5py costs seconds on a busy machine).
  const auto script = test::writeFile(dir.path() / "mutate.py", R"(
import sys, h5py, numpy as np
for path, what in zip(sys.argv[1::2], sys.argv[2::2]):
  with h5py.File(path, "a") as f:
    if what == "huge_horizon": f.attrs["horizon"] = np.int64(2**31)
    elif what == "tiny_step": f.attrs["step"] = 1e-9
    elif what == "other_horizon": f.attrs["horizon"] = np.int64(24)
    elif what == "float_horizon": f.attrs["horizon"] = 25.5
    elif what == "array_history": f.attrs["history"] = np.array([1, 2], dtype=np.int64)
    elif what == "polyline_count": f["sample_polyline_count"][0] = 2**31 - 1
    elif what == "ego_index": f["sample_ego_polyline"][1] = 99
    elif what == "label_index": f["sample_label"][2] = -3
    elif what == "vector_count": f["polyline_vector_count"][1] = 2**31 - 1
    elif what == "claimed_rows": f["sample_t0"].resize((10**12,))
    elif what == "no_targets": del f["targets"]
    elif what == "nan_origin": f["sample_origin"][0, 0] = np.nan
)");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"huge_horizon", "attribute 'horizon': got 2147483648, expected 1 .. 1000 steps"},
      {"tiny_step", "attribute 'step': got 1e-09"},
      {"other_horizon", "array 'targets' has shape [3, 25, 2], expected [3, 24, 2]"},
      {"float_horizon", "attribute 'horizon' is not a single whole number"},
      {"array_history", "attribute 'history' is not a single whole number"},
      {"polyline_count", "sample 0: polylines 0 .. 2147483647 outside"},
      {"ego_index", "sample 1: Ego polyline 99 of 4"},
      {"label_index", "sample 2 refers to label #-3 of 1"},
      {"vector_count", "sample 0 polyline 1: vectors"},
      {"claimed_rows", "its shape claims"},
      {"no_targets", "cannot read 'targets'"},
      {"nan_origin", "sample 0: non-finite origin"},
  };
  std::vector<std::string> command = {test::python(), script.string()};
  for (const auto& [what, expected] : cases) {
    fs::copy_file(good, dir.path() / (what + ".h5"));
    command.insert(command.end(), {(dir.path() / (what + ".h5")).string(), what});
  }
  const auto mutated = test::run(command, dir.path());
  ASSERT_EQ(mutated.exitCode, 0) << mutated.output;
  for (const auto& [what, expected] : cases) {
    const auto path = dir.path() / (what + ".h5");
    try {
      const DatasetReader reader(path);
      for (std::size_t i = 0; i < reader.size(); ++i) reader.scene(i);
      ADD_FAILURE() << what << ": accepted";
    } catch (const DatasetError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(expected), std::string::npos) << what << ": " << message;
      EXPECT_EQ(message.rfind(path.string(), 0), 0u) << what << ": the message names the file first: " << message;
    }
  }
}

// A write that fails (here: a full disk) names the file as the user knows it (not the
// temporary name it is written under), the array, and the operating system's cause.
TEST(Dataset, WriteFailuresNameTheFileTheArrayAndTheCause) {
  try {
    DatasetWriter writer("/dev/full", header(), "out/acc/dataset.h5");
    for (std::uint64_t i = 0; i < 600; ++i) writer.append(sceneAt(Vec2(0, 0), i, "acc"));
    writer.close();
    ADD_FAILURE() << "writing to a full disk succeeded";
  } catch (const IoError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("out/acc/dataset.h5: ", 0), 0u) << message;
    EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
  }
}

TEST(DatasetCollection, CombinesFilesAndSelectsByLabelWithoutCopying) {
  TemporaryDirectory dir;
  for (const char* name : {"one", "two"}) {
    DatasetWriter writer(dir.path() / (std::string(name) + ".h5"), header());
    for (std::uint64_t i = 0; i < 10; ++i) writer.append(sceneAt(Vec2(0, 0), i, i < 4 ? "acc" : name));
    writer.close();
  }
  DatasetCollection collection;
  collection.add(dir.path() / "one.h5");
  collection.add(dir.path() / "two.h5");
  EXPECT_EQ(collection.all().size(), 20u);
  const auto counts = collection.labelCounts();
  EXPECT_EQ(counts.at("acc"), 8u);
  EXPECT_EQ(counts.at("one"), 6u);
  const auto acc = collection.withLabel("acc");
  ASSERT_EQ(acc.size(), 8u);
  EXPECT_EQ(acc[4].file, 1u);
  EXPECT_EQ(collection.scene(acc[4]).label, "acc");
}
