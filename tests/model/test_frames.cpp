// Model frames: the Ego frame and the lane-relative (Frenet) frame on generated scenes and
// on an export of a real map.
#include <gtest/gtest.h>

#include <cmath>

#include "../../src/model/frames.hpp"
#include "synthetic_scenes.hpp"
#include "test_support.hpp"
#include "vsd/model/model.hpp"
#include "vsd/pipeline/map_export.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/scenario/logical_scenario.hpp"

using namespace vsd;
using namespace vsd::model;
using namespace vsd::test;
namespace fs = std::filesystem;

namespace {

/// Planned (not simulated) scenes of a paper scenario: lanes and the Co as the generator builds them.
std::vector<vector::VectorizedScene> plannedScenes(const std::string& scenario, std::uint64_t count) {
  const auto logical = scenario::loadLogicalScenario(scenarioFile(scenario));
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < count; ++i) {
    scenes.push_back(pipeline::plannedScene(scenario::sampleConcreteScenario(logical, 5, i)));
  }
  return scenes;
}

}  // namespace

TEST(LaneFrame, StraightensACurvedRoadAroundTheEgo) {
  for (const auto& scene : plannedScenes("acc_lk.yaml", 20)) {
    const auto frame = makeFrame("lane", scene, VectorNetConfig{}.laneSmoothing);
    const auto ego = scene.egoInitialState();
    // The Ego starts on its lane's centre, heading along it (up to the lane points' noise).
    const Vec2 start = frame->toModel(ego.position());
    EXPECT_NEAR(start.x(), 0.0, 1e-6);
    EXPECT_LT(std::abs(start.y()), 0.4);
    EXPECT_LT(std::abs(frame->headingToModel(ego.position(), ego.heading)), 0.2);
    // Lane boundaries become lines at about +-w/2 (w = 3.5 +- 0.3 m), the Co stays in the lane.
    for (const auto& polyline : scene.polylines) {
      for (const auto& f : polyline.vectors) {
        const Vec2 p = frame->toModel({f[2], f[3]});
        if (std::abs(p.x()) > 40.0) continue;  // near the Ego, where the reference line follows the lane
        if (polyline.type == vector::ObjectType::LaneBoundary) {
          EXPECT_GT(std::abs(p.y()), 1.2) << p.transpose();
          EXPECT_LT(std::abs(p.y()), 2.6) << p.transpose();
        } else if (polyline.type == vector::ObjectType::Vehicle) {
          EXPECT_LT(std::abs(p.y()), 0.6) << p.transpose();
        }
      }
    }
    // Scene -> model -> scene returns every point near the lane.
    for (const auto& polyline : scene.polylines) {
      if (polyline.type != vector::ObjectType::Vehicle) continue;
      for (const auto& f : polyline.vectors) {
        const Vec2 p(f[2], f[3]);
        EXPECT_LT((frame->toScene(frame->toModel(p)) - p).norm(), 0.02);
      }
    }
  }
}

TEST(LaneFrame, WorksOnAnExportOfARealMapAndTrainsThere) {
  TemporaryDirectory dir;
  pipeline::ExportOptions exporting;
  exporting.source.config = "/usr/share/sumo/tools/game/A10KW.sumocfg";
  exporting.output = dir.path() / "a10.h5";
  exporting.egos = "random:20";
  exporting.seed = 3;
  exporting.end = 120.0;
  pipeline::exportMap(exporting);
  const vector::DatasetReader reader(exporting.output);
  ASSERT_GT(reader.size(), 20u);
  std::size_t on_lane = 0;
  std::size_t points = 0;
  std::size_t returned = 0;
  for (std::size_t i = 0; i < reader.size(); ++i) {
    const auto scene = reader.scene(i);
    const auto frame = makeFrame("lane", scene, VectorNetConfig{}.laneSmoothing);
    const auto ego = scene.egoInitialState();
    const Vec2 start = frame->toModel(ego.position());
    on_lane += std::abs(start.y()) < 1.0 ? 1 : 0;
    for (std::size_t k = 0; k < scene.target.size(); ++k) {
      if (!scene.targetValid[k]) continue;
      ++points;
      returned += (frame->toScene(frame->toModel(scene.target[k])) - scene.target[k]).norm() < 0.05 ? 1 : 0;
    }
  }
  // SUMO's drivers keep to their lanes: nearly every Ego starts near its traced lane centre,
  // and its future maps into the frame and back.
  EXPECT_GT(static_cast<double>(on_lane), 0.95 * static_cast<double>(reader.size()));
  EXPECT_GT(static_cast<double>(returned), 0.97 * static_cast<double>(points));

  // A kinematic model in the lane frame trains and predicts on the map. Map scenes are
  // large (every lane boundary near the Ego), so a few dozen of them keep this cheap.
  const fs::path subset = dir.path() / "a10_subset.h5";
  {
    vector::DatasetWriter writer(subset, reader.header());
    for (std::size_t i = 0; i < reader.size(); i += reader.size() / 24) writer.append(reader.scene(i));
    writer.close();
  }
  auto options = tinyTraining(subset, dir.path() / "lane.pt");
  options.config.decoder = "kinematic";
  options.config.frame = "lane";
  options.steps = 6;
  train(options);
  const Predictor predictor(options.output);
  EXPECT_EQ(predictor.info().config.frame, "lane");
  const auto evaluation = evaluate(predictor, {subset});
  EXPECT_EQ(evaluation.overall.samples, vector::DatasetReader(subset).size());
  EXPECT_TRUE(std::isfinite(evaluation.overall.ade));
  EXPECT_TRUE(std::isfinite(evaluation.overall.nll));
}
