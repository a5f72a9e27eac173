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
  batch.egoStep = egoStep.index_select(0, indices);
  batch.targets = targets.index_select(0, indices);
  batch.targetMask = targetMask.index_select(0, indices);
  return batch;
}

SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config) {
  return buildTensors(scenes, config, 0, scenes.size());
}

SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& all_scenes, const VectorNetConfig& config,
                          std::size_t first, std::size_t last) {
  const auto n = static_cast<std::int64_t>(last - first);
  const auto scene_at = [&](std::int64_t i) -> const vector::VectorizedScene& {
    return all_scenes[first + static_cast<std::size_t>(i)];
  };
  std::int64_t max_polylines = 1;
  std::int64_t max_vectors = 1;
  std::int64_t max_ego_vectors = 1;
  for (std::int64_t i = 0; i < n; ++i) {
    const auto& scene = scene_at(i);
    if (scene.egoPolyline >= scene.polylines.size()) {
      throw DatasetError(fmt::format("sample {} ({}): no Ego polyline", scene.sample, scene.label));
    }
    max_polylines = std::max<std::int64_t>(max_polylines, static_cast<std::int64_t>(scene.polylines.size()) - 1);
    for (std::size_t p = 0; p < scene.polylines.size(); ++p) {
      const auto count = static_cast<std::int64_t>(scene.polylines[p].vectors.size());
      if (p == scene.egoPolyline) max_ego_vectors = std::max(max_ego_vectors, count);
      else max_vectors = std::max(max_vectors, count);
    }
  }
  const std::int64_t horizon = config.horizon;
  SceneTensors tensors;
  tensors.features = torch::zeros({n, max_polylines, max_vectors, kInputFeatures});
  tensors.vectorMask = torch::zeros({n, max_polylines, max_vectors}, torch::kBool);
  tensors.polylineMask = torch::zeros({n, max_polylines}, torch::kBool);
  tensors.egoFeatures = torch::zeros({n, 1, max_ego_vectors, kInputFeatures});
  tensors.egoMask = torch::zeros({n, 1, max_ego_vectors}, torch::kBool);
  tensors.egoStep = torch::zeros({n, 2});
  tensors.targets = torch::zeros({n, horizon, 2});
  tensors.targetMask = torch::zeros({n, horizon}, torch::kBool);
  auto features = tensors.features.accessor<float, 4>();
  auto vector_mask = tensors.vectorMask.accessor<bool, 3>();
  auto polyline_mask = tensors.polylineMask.accessor<bool, 2>();
  auto ego_features = tensors.egoFeatures.accessor<float, 4>();
  auto ego_mask = tensors.egoMask.accessor<bool, 3>();
  auto ego_step = tensors.egoStep.accessor<float, 2>();
  auto targets = tensors.targets.accessor<float, 3>();
  auto target_mask = tensors.targetMask.accessor<bool, 2>();
  const double scale = 1.0 / config.coordinateScale;
  const double time_scale = 1.0 / (static_cast<double>(config.horizon) * config.step);

  for (std::int64_t i = 0; i < n; ++i) {
    const auto& scene = scene_at(i);
    if (static_cast<std::int64_t>(scene.target.size()) != horizon) {
      throw DatasetError(fmt::format("sample {} ({}) has {} target steps, the model predicts {}", scene.sample,
                                     scene.label, scene.target.size(), horizon));
    }
    const auto ego = scene.egoInitialState();
    const Vec2 origin = ego.position();
    const double c = std::cos(ego.heading);
    const double s = std::sin(ego.heading);
    auto to_ego = [&](double x, double y) {  // translate, then rotate by -heading
      const double dx = x - origin.x();
      const double dy = y - origin.y();
      return Vec2(c * dx + s * dy, -s * dx + c * dy);
    };
    tensors.origins.push_back(origin);
    tensors.headings.push_back(ego.heading);

    // Constant-velocity step: along +x in the Ego frame, speed * dt long.
    ego_step[i][0] = static_cast<float>(ego.speed * scene.step);
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
        const Vec2 start = to_ego(f[0], f[1]) * scale;
        const Vec2 end = to_ego(f[2], f[3]) * scale;
        auto feature = polyline_features[static_cast<std::int64_t>(v)];
        feature[0] = static_cast<float>(start.x());
        feature[1] = static_cast<float>(start.y());
        feature[2] = static_cast<float>(end.x());
        feature[3] = static_cast<float>(end.y());
        if (type >= 1 && type <= 3) feature[3 + type] = 1.0F;
        feature[7] = static_cast<float>(f[6] * time_scale);
        polyline_vector_mask[static_cast<std::int64_t>(v)] = true;
        any = true;
      }
      if (!is_ego) polyline_mask[i][slot++] = any;
    }
    for (std::int64_t k = 0; k < horizon; ++k) {
      const auto& target = scene.target[static_cast<std::size_t>(k)];
      if (!scene.targetValid[static_cast<std::size_t>(k)]) continue;
      if (!target.allFinite()) {
        throw DatasetError(fmt::format("sample {} ({}): target step {} is not finite", scene.sample, scene.label, k + 1));
      }
      const Vec2 local = to_ego(target.x(), target.y());
      targets[i][k][0] = static_cast<float>(local.x());
      targets[i][k][1] = static_cast<float>(local.y());
      target_mask[i][k] = true;
    }
  }
  return tensors;
}

Polyline toSceneFrame(const torch::Tensor& positions, const Vec2& origin, double heading) {
  const auto accessor = positions.accessor<float, 2>();
  const double c = std::cos(heading);
  const double s = std::sin(heading);
  Polyline points;
  points.reserve(static_cast<std::size_t>(positions.size(0)));
  for (std::int64_t k = 0; k < positions.size(0); ++k) {
    const double x = accessor[k][0];
    const double y = accessor[k][1];
    points.emplace_back(origin.x() + c * x - s * y, origin.y() + s * x + c * y);
  }
  return points;
}

std::pair<torch::Tensor, torch::Tensor> displacement(const torch::Tensor& predicted, const torch::Tensor& targets,
                                                     const torch::Tensor& mask) {
  const auto distance = (predicted - targets).pow(2).sum(-1).clamp_min(1e-12).sqrt();  // [N, F]
  const auto weights = mask.to(torch::kFloat32);
  const auto counts = weights.sum(1).clamp_min(1.0);
  const auto mean = (distance * weights).sum(1) / counts;
  // Final: the last valid step of each sample.
  const auto steps = torch::arange(mask.size(1), torch::kInt64).unsqueeze(0).expand_as(mask);
  const auto last = torch::where(mask, steps, torch::full_like(steps, -1)).amax(1).clamp_min(0);
  const auto final_distance = distance.gather(1, last.unsqueeze(1)).squeeze(1);
  return {mean, final_distance};
}

}  // namespace vsd::model
