// The planned scene (before simulation) must be what the simulation then produces:
// `compare` predicts from planned scenes with models trained on simulated ones.
#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"

using namespace vsd;
using namespace vsd::pipeline;

namespace {

struct Deviation {
  double lanes = 0.0;
  double vehicles = 0.0;
  double ego = 0.0;
};

Deviation maxDeviation(const vector::VectorizedScene& planned, const vector::VectorizedScene& simulated) {
  Deviation deviation;
  EXPECT_EQ(planned.polylines.size(), simulated.polylines.size());
  EXPECT_EQ(planned.egoPolyline, simulated.egoPolyline);
  for (std::size_t p = 0; p < std::min(planned.polylines.size(), simulated.polylines.size()); ++p) {
    const auto& a = planned.polylines[p];
    const auto& b = simulated.polylines[p];
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.vectors.size(), b.vectors.size());
    EXPECT_EQ(a.valid, b.valid);
    double& worst = a.type == vector::ObjectType::LaneBoundary ? deviation.lanes
                    : a.type == vector::ObjectType::Vehicle    ? deviation.vehicles
                                                               : deviation.ego;
    for (std::size_t v = 0; v < std::min(a.vectors.size(), b.vectors.size()); ++v) {
      for (std::size_t f = 0; f < vector::kFeatures; ++f) {
        worst = std::max(worst, std::abs(a.vectors[v][f] - b.vectors[v][f]));
      }
    }
  }
  return deviation;
}

}  // namespace

TEST(PlannedScene, MatchesTheSceneTheSimulationProduces) {
  for (const char* name : {"acc_lk.yaml", "acc.yaml", "lk.yaml"}) {
    const auto logical = scenario::loadLogicalScenario(test::scenarioFile(name));
    RunOptions options;
    options.scenarioFile = logical->sourceFile;
    options.samples = 40;
    options.seed = 11;
    options.writeFiles = false;
    Deviation worst;
    std::size_t compared = 0;
    runScenarios(logical, options, [&](const ScenarioOutcome& outcome) {
      if (!outcome.ok()) return;
      const auto planned = plannedScene(scenario::sampleConcreteScenario(logical, options.seed, outcome.index));
      const auto simulated = simulatedScene(*logical, outcome);
      EXPECT_EQ(planned.sample, simulated.sample);
      EXPECT_EQ(planned.inputs, simulated.inputs);
      ASSERT_EQ(planned.targetValid.size(), simulated.target.size());
      for (auto valid : planned.targetValid) EXPECT_EQ(valid, 0);  // nothing simulated yet
      const auto deviation = maxDeviation(planned, simulated);
      worst.lanes = std::max(worst.lanes, deviation.lanes);
      worst.vehicles = std::max(worst.vehicles, deviation.vehicles);
      worst.ego = std::max(worst.ego, deviation.ego);
      ++compared;
    });
    EXPECT_GE(compared, 35u) << name;
    // Lanes: SUMO's lane shapes are the generator's points as netconvert writes them,
    // rounded to 0.01 m (up to 7 mm on a diagonal).
    EXPECT_LT(worst.lanes, 0.01) << name;
    // The Co: the simulation places it on the very path the plan computes.
    EXPECT_LT(worst.vehicles, 1e-9) << name;
    EXPECT_LT(worst.ego, 1e-6) << name;
    std::printf("%s: largest deviation planned vs simulated: lanes %.2e m, Co %.2e m, Ego %.2e m\n", name,
                worst.lanes, worst.vehicles, worst.ego);
  }
}

// A library scenario's planned scene: every lane of the arc road, and the road user with its
// drawn kind and size along its whole path (moved with the Ego's stand-in).
TEST(PlannedScene, HoldsEveryLaneAndRoadUserOfALibraryScenario) {
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("alks/cut_in.yaml"));
  for (std::uint64_t i = 0; i < 5; ++i) {
    const auto concrete = scenario::sampleConcreteScenario(logical, 3, i);
    const auto scene = plannedScene(concrete);
    std::size_t lanes = 0;
    const vector::ScenePolyline* other = nullptr;
    for (const auto& polyline : scene.polylines) {
      if (polyline.type == vector::ObjectType::LaneBoundary) ++lanes;
      if (polyline.type == vector::ObjectType::Vehicle) other = &polyline;
    }
    EXPECT_EQ(lanes, 6u);  // three lanes, two boundaries each
    ASSERT_NE(other, nullptr);
    EXPECT_EQ(other->roadUser, concrete.others[0].type);
    EXPECT_EQ(other->length, roadUserKind(concrete.others[0].type).length);
    EXPECT_EQ(other->vectors.size(), 25u);
  }
}
