#pragma once
// Scenes as padded tensors with masks (internal to the model module: includes libtorch).
//
// Built once per dataset; a batch is then an index_select along the sample dimension.
// Per vector the network sees 8 features: start and end point in the Ego's initial
// frame divided by coordinateScale, a one-hot object type (lane, vehicle, Ego) and the
// timestamp divided by the horizon. polyline_id is not a feature: it is an index, and
// feeding it would make the output depend on the order of polylines.

#include <torch/torch.h>

#include <vector>

#include "vsd/model/model.hpp"

namespace vsd::model {

inline constexpr int kInputFeatures = 8;

/// The Ego's polyline is kept apart from the others: it is short (1 vector without
/// history) while lanes and vehicles have ~25, so padding it with them would waste a
/// quarter of the work on paper-sized scenes. The network treats both alike.
struct SceneTensors {
  torch::Tensor features;      ///< [N, P, V, 8] float32, the polylines other than the Ego's (zero where masked)
  torch::Tensor vectorMask;    ///< [N, P, V] bool: real, valid vector
  torch::Tensor polylineMask;  ///< [N, P] bool: real polyline with at least one valid vector
  torch::Tensor egoFeatures;   ///< [N, 1, W, 8] float32, the Ego's polyline (W = its longest)
  torch::Tensor egoMask;       ///< [N, 1, W] bool
  torch::Tensor egoStep;       ///< [N, 2] float32: the Ego's initial vector in its frame (m per step)
  torch::Tensor targets;       ///< [N, F, 2] float32, Ego frame, metres
  torch::Tensor targetMask;    ///< [N, F] bool
  std::vector<Vec2> origins;   ///< Ego initial positions (scene frame)
  std::vector<double> headings;  ///< Ego initial headings (rad)

  std::int64_t size() const { return features.defined() ? features.size(0) : 0; }
  /// The samples at `indices` (for batches).
  SceneTensors select(const torch::Tensor& indices) const;
};

/// Converts scenes (all with the config's horizon). Throws DatasetError naming the
/// sample if a valid vector or target holds NaN/Inf.
SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config);
/// The same for scenes[first, last).
SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config,
                          std::size_t first, std::size_t last);

/// Ego-frame positions [F, 2] (metres) of one sample back into its scene frame.
Polyline toSceneFrame(const torch::Tensor& positions, const Vec2& origin, double heading);

/// Mean (over valid steps) Euclidean distance per sample [N] and final distance [N].
std::pair<torch::Tensor, torch::Tensor> displacement(const torch::Tensor& predicted, const torch::Tensor& targets,
                                                     const torch::Tensor& mask);

}  // namespace vsd::model
