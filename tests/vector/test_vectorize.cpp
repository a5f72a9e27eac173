#include <gtest/gtest.h>

#include <cmath>

#include <regex>

#include "vsd/vector/scene_svg.hpp"
#include "vsd/vector/vectorize.hpp"

using namespace vsd;
using namespace vsd::vector;

namespace {

/// Ego along +x at 10 m/s; a leader 20 m ahead at 8 m/s; 26 instants of 0.2 s.
Trace followingTrace() {
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.role = VehicleRole::Ego;
  ego.length = 4.5;
  ego.width = 1.8;
  VehicleTrack co;
  co.length = 5.5;
  co.width = 2.0;
  for (int k = 0; k < 26; ++k) {
    const double t = 0.2 * k;
    ego.states.push_back({-50.0 + 10.0 * t, 1.0, 0.0, 10.0, 0.0});
    co.states.push_back({-30.0 + 8.0 * t, 1.0, 0.0, 8.0, 0.0});
    ego.valid.push_back(1);
    co.valid.push_back(1);
  }
  trace.vehicles = {ego, co};
  return trace;
}

LaneGeometry straightLane(double x0, double x1, double y, int points, double width) {
  LaneGeometry lane;
  lane.id = "lane";
  lane.width = width;
  for (int i = 0; i < points; ++i) lane.centre.emplace_back(x0 + (x1 - x0) * i / (points - 1), y);
  return lane;
}

}  // namespace

TEST(Vectorize, SplitKeepsVectorsShortAndContiguous) {
  const Polyline line = {{0, 0}, {12, 0}, {12, 3}};
  const auto vectors = splitIntoVectors(line, 5.0);
  ASSERT_EQ(vectors.size(), 4u);  // 12 m -> 3 parts, 3 m -> 1 part
  for (std::size_t i = 0; i < vectors.size(); ++i) {
    EXPECT_LE((vectors[i].second - vectors[i].first).norm(), 5.0 + 1e-12);
    if (i > 0) {
      EXPECT_TRUE(vectors[i].first.isApprox(vectors[i - 1].second));
    }
  }
  EXPECT_EQ(splitIntoVectors(line, 0.0).size(), 2u);
}

TEST(Vectorize, PaperSceneHasTheFootnotesVectorCountAndTheTracesGeometry) {
  // The paper's road: 25 lane points over [-55, 55] plus extensions outside the region.
  LaneGeometry lane = straightLane(-55.0, 55.0, 1.0, 25, 3.5);
  lane.centre.insert(lane.centre.begin(), Vec2(-85.0, 1.0));
  lane.centre.emplace_back(205.0, 1.0);
  const Trace trace = followingTrace();
  const auto scene = buildScene("acc", trace, 0, regionLanePolylines({lane}, -55.0, 55.0));

  // (2 lanes * 24 + Co * 25 + Ego * 1) vectors * 7 features.
  ASSERT_EQ(scene.polylines.size(), 4u);
  EXPECT_EQ(scene.polylines[0].vectors.size(), 24u);
  EXPECT_EQ(scene.polylines[1].vectors.size(), 24u);
  EXPECT_EQ(scene.polylines[2].vectors.size(), 25u);
  EXPECT_EQ(scene.polylines[3].vectors.size(), 1u);
  EXPECT_EQ(scene.vectorCount() * kFeatures, (2u * 24u + 25u + 1u) * 7u);
  EXPECT_EQ(scene.egoPolyline, 3u);

  // Lane boundaries: 1.75 m either side of the centre, timestamp 0, over the region only.
  EXPECT_NEAR(scene.polylines[0].vectors.front()[1], 1.0 + 1.75, 1e-9);
  EXPECT_NEAR(scene.polylines[1].vectors.front()[1], 1.0 - 1.75, 1e-9);
  EXPECT_NEAR(scene.polylines[0].vectors.front()[0], -55.0, 1e-9);
  EXPECT_NEAR(scene.polylines[0].vectors.back()[2], 55.0, 1e-9);
  // The Co: one vector per step from its position at t_{k-1} to t_k, timestamp t_k.
  const auto& co = scene.polylines[2];
  for (std::size_t k = 1; k <= 25; ++k) {
    const auto& f = co.vectors[k - 1];
    EXPECT_DOUBLE_EQ(f[0], trace.vehicles[1].states[k - 1].x);
    EXPECT_DOUBLE_EQ(f[2], trace.vehicles[1].states[k].x);
    EXPECT_NEAR(f[6], 0.2 * static_cast<double>(k), 1e-12);
    EXPECT_EQ(f[4], 2.0);
    EXPECT_EQ(f[5], 2.0);
  }
  // The Ego: position, heading and speed in one vector; the target is its future.
  const auto& ego = scene.polylines[3].vectors[0];
  EXPECT_EQ(ego[4], 3.0);
  EXPECT_EQ(ego[6], 0.0);
  const auto state = scene.egoInitialState();
  EXPECT_NEAR(state.x, -50.0, 1e-12);
  EXPECT_NEAR(state.speed, 10.0, 1e-9);
  EXPECT_NEAR(state.heading, 0.0, 1e-12);
  ASSERT_EQ(scene.target.size(), 25u);
  EXPECT_TRUE(scene.target.back().isApprox(trace.ego().states[25].position()));
}

TEST(Vectorize, EgoHeadingSurvivesStandstill) {
  const auto vector = egoInitialVector({3.0, 4.0, 1.0, 0.0, 0.0}, 0.2, 0);
  VectorizedScene scene;
  scene.step = 0.2;
  scene.polylines.push_back({ObjectType::Ego, {vector}, {1}});
  const auto state = scene.egoInitialState();
  EXPECT_NEAR(state.heading, 1.0, 1e-9);
  EXPECT_EQ(state.speed, 0.0);
}

TEST(Vectorize, HistoryAndMasks) {
  Trace trace = followingTrace();
  trace.vehicles[1].valid[10] = 0;  // the Co is out of range at one instant
  VehicleTrack absent = trace.vehicles[1];
  std::fill(absent.valid.begin(), absent.valid.end(), 0);
  trace.vehicles.push_back(absent);  // never in range: left out
  const auto scene = buildScene("map", trace, 5, {});
  ASSERT_EQ(scene.polylines.size(), 2u);  // Co + Ego
  const auto& co = scene.polylines[0];
  EXPECT_NEAR(co.vectors.front()[6], -0.8, 1e-12);  // history: first vector ends at t = -0.8 s
  EXPECT_EQ(co.valid[9], 0);   // vectors touching instant 10 are masked
  EXPECT_EQ(co.valid[10], 0);
  EXPECT_EQ(co.valid[8], 1);
  const auto& ego = scene.polylines[1];
  EXPECT_EQ(ego.vectors.size(), 6u);  // 5 history vectors + the initial vector
  EXPECT_EQ(ego.vectors.back()[6], 0.0);
  EXPECT_EQ(scene.target.size(), 20u);
}

TEST(LaneIndex, ReturnsOnlyVectorsWithinTheRadiusAsRunsOfThePool) {
  std::vector<LaneGeometry> lanes = {straightLane(0.0, 200.0, 0.0, 2, 3.5), straightLane(0.0, 200.0, 50.0, 2, 3.5)};
  lanes[1].id = "other";
  const LaneIndex index(lanes, 5.0);
  EXPECT_EQ(index.boundaries(), 4u);
  EXPECT_EQ(index.vectors(), 160u);
  const auto polylines = index.query({100.0, 0.0}, 20.0);
  ASSERT_EQ(polylines.size(), 2u);  // both boundaries of the near lane, none of the far one
  for (const auto& polyline : polylines) {
    EXPECT_GE(polyline.vectors.size(), 8u);
    ASSERT_GE(polyline.sharedStart, 0);
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      const auto& f = polyline.vectors[v];
      const Vec2 a(f[0], f[1]);
      const Vec2 b(f[2], f[3]);
      EXPECT_LE(std::min((a - Vec2(100, 0)).norm(), (b - Vec2(100, 0)).norm()), 20.0 + 5.0);
      EXPECT_EQ(index.pool()[static_cast<std::size_t>(polyline.sharedStart) + v], f);
      if (v > 0) {
        EXPECT_DOUBLE_EQ(polyline.vectors[v - 1][2], f[0]);  // consecutive
      }
    }
  }
  EXPECT_TRUE(index.query({100.0, 200.0}, 20.0).empty());
}

TEST(SceneTrace, RebuildsTheTraceTheSceneCameFromAndTheEgosLane) {
  const Trace trace = followingTrace();
  LaneGeometry lane = straightLane(-55.0, 55.0, 1.0, 25, 3.5);
  LaneGeometry other_lane = straightLane(-55.0, 55.0, 4.5, 25, 3.5);
  const auto scene = buildScene("acc", trace, 0, regionLanePolylines({other_lane, lane}, -55.0, 55.0));

  const auto rebuilt = sceneTrace(scene, scene.target);  // sizes travel with the scene
  ASSERT_EQ(rebuilt.vehicles.size(), 2u);
  EXPECT_EQ(rebuilt.step, 0.2);
  const auto& ego = rebuilt.vehicles[0];
  const auto& co = rebuilt.vehicles[1];
  EXPECT_EQ(ego.role, VehicleRole::Ego);
  EXPECT_EQ(ego.length, 4.5);
  EXPECT_EQ(ego.width, 1.8);
  EXPECT_EQ(co.length, 5.5);
  EXPECT_EQ(co.width, 2.0);
  ASSERT_EQ(ego.states.size(), 26u);
  ASSERT_EQ(co.states.size(), 26u);
  for (std::size_t k = 0; k < 26; ++k) {
    EXPECT_TRUE(ego.states[k].position().isApprox(trace.vehicles[0].states[k].position(), 1e-9)) << k;
    EXPECT_NEAR(ego.states[k].speed, 10.0, 1e-9) << k;
    EXPECT_NEAR(ego.states[k].accel, 0.0, 1e-9) << k;
    EXPECT_TRUE(co.validAt(k)) << k;
    EXPECT_TRUE(co.states[k].position().isApprox(trace.vehicles[1].states[k].position(), 1e-9)) << k;
    EXPECT_NEAR(co.states[k].speed, 8.0, 1e-9) << k;
  }

  // A prediction replaces the Ego's future; the Co stays as recorded.
  Polyline stopped(25, scene.egoInitialState().position());
  const auto stopping = sceneTrace(scene, stopped);
  EXPECT_NEAR(stopping.vehicles[0].states[1].accel, -10.0 / 0.1, 1e-9);
  EXPECT_TRUE(stopping.vehicles[1].states[25].position().isApprox(trace.vehicles[1].states[25].position(), 1e-9));

  // The Ego's lane: the midline of the boundary pair nearest to it (y = 1, not 4.5).
  const auto centre = egoLaneCentre(scene);
  ASSERT_EQ(centre.size(), 25u);
  for (const auto& point : centre) EXPECT_NEAR(point.y(), 1.0, 1e-9);
  EXPECT_NEAR(centre.front().x(), -55.0, 1e-9);
}

TEST(SceneTrace, MaskedCoInstantsStayInvalid) {
  Trace trace = followingTrace();
  trace.vehicles[1].valid[10] = 0;
  const auto scene = buildScene("acc", trace, 0, {});
  const auto rebuilt = sceneTrace(scene, scene.target);
  const auto& co = rebuilt.vehicles[1];
  EXPECT_FALSE(co.validAt(10));
  EXPECT_TRUE(co.validAt(9));
  EXPECT_TRUE(co.validAt(11));
  EXPECT_TRUE(egoLaneCentre(scene).empty());
}

// Zoomed drawings (the comparison report's worst scenarios) keep every line inside the
// picture: lanes far from the vehicles are clipped, not drawn over the legend.
TEST(SceneSvg, FocusZoomsToTheVehiclesAndClipsTheLanes) {
  const Trace trace = followingTrace();  // vehicles between x = -50 and +10 m
  const auto scene = buildScene("acc", trace, 0, regionLanePolylines({straightLane(-400.0, 400.0, 1.0, 25, 3.5)}, -400.0, 400.0));
  const auto whole = renderSceneSvg(scene, {}, "whole", 600);
  const auto focused = renderSceneSvg(scene, {}, "focused", 600, "simulated future", /*focus_margin_m=*/5.0);
  auto extent = [](const std::string& svg) {
    // x coordinates of the lane lines, in pixels
    const std::regex points(R"re(points="([-0-9.]+),[-0-9.]+ ([-0-9.]+),[-0-9.]+ " fill="none" stroke="#9a9a9a")re");
    double lo = 1e9;
    double hi = -1e9;
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), points); it != std::sregex_iterator(); ++it) {
      for (int g : {1, 2}) {
        lo = std::min(lo, std::stod((*it)[g]));
        hi = std::max(hi, std::stod((*it)[g]));
      }
    }
    return std::pair{lo, hi};
  };
  const auto [whole_lo, whole_hi] = extent(whole);
  const auto [focus_lo, focus_hi] = extent(focused);
  ASSERT_LT(focus_lo, focus_hi);
  EXPECT_GE(focus_lo, 0.0);
  EXPECT_LE(focus_hi, 600.0);
  // 800 m of road in the whole drawing, ~70 m in the focused one: a lane vector of
  // 33 m spans ~20 px in the first and ~200 px in the second.
  auto longest = [](const std::string& svg) {
    const std::regex lane(R"re(points="([-0-9.]+),[-0-9.]+ ([-0-9.]+),[-0-9.]+ " fill="none" stroke="#9a9a9a")re");
    double result = 0.0;
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), lane); it != std::sregex_iterator(); ++it) {
      result = std::max(result, std::abs(std::stod((*it)[2]) - std::stod((*it)[1])));
    }
    return result;
  };
  EXPECT_LT(longest(whole), 30.0);
  EXPECT_GT(longest(focused), 150.0);
  EXPECT_LT(whole_lo, 100.0);
  EXPECT_GT(whole_hi, 500.0);
}
