#include "tensors.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vsd/core/error.hpp"

namespace vsd::model {

SceneTensors SceneTensors::select(const torch::Tensor& indices) const {
  SceneTensors batch;
  batch.features = features.index_select(0, indices);
  batch.vectorMask = vectorMask.index_select(0, indices);
  batch.polylineMask = polylineMask.index_select(0, indices);
  batch.egoFeatures = egoFeatures.index_select(0, indices);
  batch.egoMask = egoMask.index_select(0, indices);
  batch.start = start.select(indices);
  batch.targets = targets.index_select(0, indices);
  batch.targetMask = targetMask.index_select(0, indices);
  return batch;
}

namespace {

struct PaddedSizes {
  std::int64_t polylines = 1;   ///< non-Ego polylines
  std::int64_t vectors = 1;     ///< vectors of a non-Ego polyline
  std::int64_t egoVectors = 1;  ///< vectors of the Ego's polyline
};

PaddedSizes paddedSizes(const std::vector<vector::VectorizedScene>& scenes, std::size_t first, std::size_t last) {
  PaddedSizes sizes;
  for (std::size_t i = first; i < last; ++i) {
    const auto& scene = scenes[i];
    if (scene.egoPolyline >= scene.polylines.size()) {
      throw DatasetError(fmt::format("sample {} ({}): no Ego polyline", scene.sample, scene.label));
    }
    sizes.polylines = std::max<std::int64_t>(sizes.polylines, static_cast<std::int64_t>(scene.polylines.size()) - 1);
    for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
      const auto count = static_cast<std::int64_t>(scene.polylines[p].vectors.size());
      if (p == scene.egoPolyline) sizes.egoVectors = std::max(sizes.egoVectors, count);
      else sizes.vectors = std::max(sizes.vectors, count);
    }
  }
  return sizes;
}

SceneTensors allocate(std::int64_t n, const PaddedSizes& sizes, std::int64_t horizon) {
  SceneTensors tensors;
  tensors.features = torch::zeros({n, sizes.polylines, sizes.vectors, kInputFeatures});
  tensors.vectorMask = torch::zeros({n, sizes.polylines, sizes.vectors}, torch::kBool);
  tensors.polylineMask = torch::zeros({n, sizes.polylines}, torch::kBool);
  tensors.egoFeatures = torch::zeros({n, 1, sizes.egoVectors, kInputFeatures});
  tensors.egoMask = torch::zeros({n, 1, sizes.egoVectors}, torch::kBool);
  tensors.start = {torch::zeros({n, 2}), torch::zeros({n}), torch::zeros({n})};
  tensors.targets = torch::zeros({n, horizon, 2});
  tensors.targetMask = torch::zeros({n, horizon}, torch::kBool);
  return tensors;
}

/// Writes sample i of `tensors` from `scene` (in `frame`).
void fillScene(SceneTensors& tensors, std::int64_t i, const vector::VectorizedScene& scene, const SceneFrame& frame,
               const VectorNetConfig& config) {
  const double scale = 1.0 / config.coordinateScale;
  const double time_scale = 1.0 / (static_cast<double>(config.horizon) * config.step);
  auto features = tensors.features.accessor<float, 4>();
  auto vector_mask = tensors.vectorMask.accessor<bool, 3>();
  auto polyline_mask = tensors.polylineMask.accessor<bool, 2>();
  auto ego_features = tensors.egoFeatures.accessor<float, 4>();
  auto ego_mask = tensors.egoMask.accessor<bool, 3>();

  const auto ego = scene.egoInitialState();
  const Vec2 start = frame.toModel(ego.position());
  auto start_position = tensors.start.position.accessor<float, 2>();
  start_position[i][0] = static_cast<float>(start.x());
  start_position[i][1] = static_cast<float>(start.y());
  tensors.start.heading.accessor<float, 1>()[i] = static_cast<float>(frame.headingToModel(ego.position(), ego.heading));
  tensors.start.speed.accessor<float, 1>()[i] = static_cast<float>(ego.speed);

  std::int64_t slot = 0;  // position among the non-Ego polylines
  for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
    const auto& polyline = scene.polylines[p];
    const int type = static_cast<int>(polyline.type);
    const bool is_ego = p == scene.egoPolyline;
    auto polyline_features = is_ego ? ego_features[i][0] : features[i][slot];
    auto polyline_vector_mask = is_ego ? ego_mask[i][0] : vector_mask[i][slot];
    bool any = false;
    for (std::size_t v = 0; v < polyline.vectors.size(); ++v) {
      if (!polyline.valid[v]) continue;
      const auto& f = polyline.vectors[v];
      for (std::size_t k = 0; k < 4; ++k) {
        if (!std::isfinite(f[k]) || !std::isfinite(f[6])) {
          throw DatasetError(fmt::format("sample {} ({}, {}): polyline {} vector {} holds a non-finite value",
                                         scene.sample, scene.label, scene.provenance.source, p, v));
        }
      }
      const Vec2 from = frame.toModel({f[0], f[1]}) * scale;
      const Vec2 to = frame.toModel({f[2], f[3]}) * scale;
      auto feature = polyline_features[static_cast<std::int64_t>(v)];
      feature[0] = static_cast<float>(from.x());
      feature[1] = static_cast<float>(from.y());
      feature[2] = static_cast<float>(to.x());
      feature[3] = static_cast<float>(to.y());
      if (type >= 1 && type <= 3) feature[3 + type] = 1.0F;
      feature[7] = static_cast<float>(f[6] * time_scale);
      polyline_vector_mask[static_cast<std::int64_t>(v)] = true;
      any = true;
    }
    if (!is_ego) polyline_mask[i][slot++] = any;
  }
}

void fillTargets(SceneTensors& tensors, std::int64_t i, const vector::VectorizedScene& scene, const SceneFrame& frame) {
  auto targets = tensors.targets.accessor<float, 3>();
  auto target_mask = tensors.targetMask.accessor<bool, 2>();
  for (std::size_t k = 0; k < scene.target.size(); ++k) {
    if (!scene.targetValid[k]) continue;
    if (!scene.target[k].allFinite()) {
      throw DatasetError(fmt::format("sample {} ({}): target step {} is not finite", scene.sample, scene.label, k + 1));
    }
    const Vec2 local = frame.toModel(scene.target[k]);
    targets[i][static_cast<std::int64_t>(k)][0] = static_cast<float>(local.x());
    targets[i][static_cast<std::int64_t>(k)][1] = static_cast<float>(local.y());
    target_mask[i][static_cast<std::int64_t>(k)] = true;
  }
}

}  // namespace

SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config) {
  return buildTensors(scenes, config, 0, scenes.size());
}

SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config,
                          std::size_t first, std::size_t last) {
  if (config.horizon < 1 || !(config.step > 0.0)) {
    throw ModelError("model configuration without horizon/step (they come from the data or the model file)");
  }
  const auto n = static_cast<std::int64_t>(last - first);
  SceneTensors tensors = allocate(n, paddedSizes(scenes, first, last), config.horizon);
  for (std::int64_t i = 0; i < n; ++i) {
    const auto& scene = scenes[first + static_cast<std::size_t>(i)];
    if (static_cast<std::int64_t>(scene.target.size()) != config.horizon) {
      throw DatasetError(fmt::format("sample {} ({}) has {} target steps, the model predicts {}", scene.sample,
                                     scene.label, scene.target.size(), config.horizon));
    }
    std::shared_ptr<const SceneFrame> frame = makeFrame(config.frame, scene, config.laneSmoothing);
    fillScene(tensors, i, scene, *frame, config);
    fillTargets(tensors, i, scene, *frame);
    tensors.frames.push_back(std::move(frame));
  }
  return tensors;
}

}  // namespace vsd::model
