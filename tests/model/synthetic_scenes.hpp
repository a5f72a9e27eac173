#pragma once
// Synthetic scenes for the model tests: like the paper's ACC (one lane, a leader, the
// Ego), everything a function of the sample index, so a model can learn it.

#include <cmath>
#include <filesystem>
#include <string>

#include "vsd/model/model.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/vectorize.hpp"

namespace vsd::test {

namespace fs = std::filesystem;

/// A scene like the paper's ACC: one lane, a leader, the Ego. Everything is a function of
/// (speed, gap, leader speed, heading, position), so a model can learn it.
inline vector::VectorizedScene syntheticScene(std::uint64_t i, const std::string& label = "acc") {
  const double speed = 8.0 + static_cast<double>(i % 9);
  const double leader_speed = speed - 2.0 + static_cast<double>(i % 5);
  const double heading = 0.3 * std::sin(static_cast<double>(i));
  const Vec2 origin(100.0 * static_cast<double>(i % 7), -40.0 * static_cast<double>(i % 3));
  const Vec2 u = headingVector(heading);
  Trace trace;
  trace.step = 0.2;
  VehicleTrack ego;
  ego.length = 5.0;
  ego.width = 1.8;
  VehicleTrack leader;
  leader.length = 4.5;
  leader.width = 1.8;
  double ego_speed = speed;
  Vec2 p = origin;
  for (int k = 0; k < 26; ++k) {
    const double t = 0.2 * k;
    const Vec2 lead = origin + (20.0 + leader_speed * t) * u;
    ego.states.push_back({p.x(), p.y(), heading, ego_speed, 0.0});
    leader.states.push_back({lead.x(), lead.y(), heading, leader_speed, 0.0});
    ego.valid.push_back(1);
    leader.valid.push_back(1);
    ego_speed = std::max(0.0, ego_speed + 0.2 * 0.5 * (leader_speed - ego_speed));
    p += 0.2 * ego_speed * u;
  }
  trace.vehicles = {ego, leader};
  LaneGeometry lane;
  lane.id = "l";
  lane.width = 3.5;
  lane.centre = {origin - 60.0 * u, origin + 120.0 * u};
  auto scene = vector::buildScene(label, trace, 0, vector::regionLanePolylines({lane}, -1e9, 1e9));
  scene.sample = i;
  return scene;
}

inline fs::path writeDataset(const fs::path& path, std::size_t count, const std::string& label = "acc",
                      int horizon = 25) {
  vector::DatasetHeader header;
  header.step = 0.2;
  header.horizon = horizon;
  vector::DatasetWriter writer(path, header);
  for (std::size_t i = 0; i < count; ++i) {
    auto scene = syntheticScene(i, label);
    scene.target.resize(static_cast<std::size_t>(horizon));
    scene.targetValid.resize(static_cast<std::size_t>(horizon));
    writer.append(scene);
  }
  writer.close();
  return path;
}

inline model::TrainOptions tinyTraining(const fs::path& data, const fs::path& out) {
  model::TrainOptions options;
  options.data = {data};
  options.output = out;
  options.config.hidden = 16;
  options.config.globalWidth = 16;
  options.config.decoderHidden = 32;
  options.steps = 60;
  options.batchSize = 8;
  options.seed = 5;
  return options;
}

}  // namespace vsd::test
