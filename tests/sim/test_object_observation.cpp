// The object list inside a SUMO co-simulation: the Ego's controller sees the other road
// users where the simulation has them at each instant, with the relation relateToPath gives.

#include <gtest/gtest.h>

#include <memory>

#include "test_support.hpp"
#include "vsd/road/network.hpp"
#include "vsd/sim/batch_simulation.hpp"
#include "vsd/sim/builtin_controllers.hpp"

using namespace vsd;
using namespace vsd::sim;

namespace {

/// Keeps its lane at constant speed and records every observation.
class Recorder final : public EgoController {
 public:
  explicit Recorder(std::shared_ptr<std::vector<Observation>> seen) : seen_(std::move(seen)) {}
  void init(const ControllerParams& /*params*/) override {}
  void reset() override {}
  bool observesObjects() const override { return true; }
  Command step(const Observation& observation, double /*dt*/) override {
    seen_->push_back(observation);
    return {0.0, lateral_.curvature(observation)};
  }

 private:
  std::shared_ptr<std::vector<Observation>> seen_;
  PurePursuitLateral lateral_;
};

}  // namespace

TEST(ObjectObservation, TheEgoSeesTheOtherRoadUsersWhereTheSimulationHasThem) {
  TemporaryDirectory dir;
  const auto logical = scenario::loadLogicalScenario(test::scenarioFile("acc.yaml"));
  constexpr std::size_t kCount = 4;
  std::vector<scenario::ConcreteScenario> scenarios;
  std::vector<road::RoadGeometry> roads;
  const road::BatchLayout layout(road::BatchLayout::cellSizeFor(logical->road));
  road::NetworkBuilder builder;
  for (std::uint64_t i = 0; i < kCount; ++i) {
    scenarios.push_back(scenario::sampleConcreteScenario(logical, 1, i));
    roads.push_back(road::buildRoadGeometry(scenarios.back()));
    builder.add(i, roads.back(), layout.offsetFor(i));
  }
  builder.writePlainXml(dir.path() / "net");
  const auto net = road::PendingNetwork::start(dir.path() / "net", {}).wait();
  std::vector<std::shared_ptr<std::vector<Observation>>> seen;
  ControllerRegistry registry;
  registry.add(logical->ego.controller.name, "records its observations", [&seen] {
    seen.push_back(std::make_shared<std::vector<Observation>>());
    return std::make_unique<Recorder>(seen.back());
  });
  std::vector<ScenarioRun> runs;
  for (std::size_t i = 0; i < kCount; ++i) runs.push_back({&scenarios[i], &roads[i], layout.offsetFor(i)});
  BatchOptions options;
  options.step = logical->step;
  options.steps = logical->steps();
  const auto results = simulateBatch(net, runs, registry, options);

  ASSERT_EQ(seen.size(), kCount);
  std::size_t observed = 0;
  for (std::size_t i = 0; i < kCount; ++i) {
    ASSERT_TRUE(results[i].ok()) << results[i].failure;
    const auto& co = results[i].trace.vehicles[1];
    ASSERT_EQ(seen[i]->size(), static_cast<std::size_t>(options.steps));
    for (std::size_t k = 0; k < seen[i]->size(); ++k) {
      const auto& objects = (*seen[i])[k].objects;
      const auto& ego = results[i].trace.vehicles[0].states[k];
      const Vec2 towards = co.states[k].position() - ego.position();
      // This Ego never brakes: it may drive into and past the Co (behind it: rear range 0 m).
      if (towards.dot(headingVector(ego.heading)) <= 0.0) continue;
      const double gap = towards.norm() - 0.5 * (co.length + results[i].trace.vehicles[0].length);
      if (gap > 46.5) continue;  // near the forward range: either way
      if (gap < 45.5) {
        ASSERT_EQ(objects.size(), 1u) << "scenario " << i << " instant " << k << " gap " << gap;
      }
      if (objects.empty()) continue;
      ++observed;
      const auto& object = objects[0];
      EXPECT_EQ(object.id, 1);
      EXPECT_EQ(object.type, RoadUserType::Car);
      EXPECT_EQ(object.state.x, co.states[k].x);  // the state of instant k, the observation's time
      EXPECT_EQ(object.state.speed, co.states[k].speed);
      EXPECT_EQ(object.length, co.length);
      EXPECT_TRUE(object.relation.inPath);  // the Co drives ahead in the Ego's lane
      EXPECT_EQ(object.relation.relativeLane, 0);
      EXPECT_NEAR(object.relation.longitudinalGap, gap, 0.5);  // along the lane vs straight line
    }
  }
  EXPECT_GT(observed, 20u);
}
