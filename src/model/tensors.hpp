#pragma once
// Scenes as padded tensors with masks (internal to the model module: includes libtorch).
//
// Built once per dataset; a batch is then an index_select along the sample dimension.
// Per vector the network sees 8 features: start and end point in the model's frame
// (frames.hpp) divided by coordinateScale, a one-hot object type (lane, vehicle, Ego) and
// the timestamp divided by the horizon. polyline_id is not a feature: it is an index, and
// feeding it would make the output depend on the order of polylines.

#include <torch/torch.h>

#include <memory>
#include <vector>

#include "decoder.hpp"
#include "frames.hpp"
#include "vsd/model/options.hpp"

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
  EgoStart start;              ///< the Ego's initial state in the model's frame
  torch::Tensor targets;       ///< [N, F, 2] float32, model frame, metres
  torch::Tensor targetMask;    ///< [N, F] bool
  /// Per scene, its model frame (shared: a batch selects from them).
  std::vector<std::shared_ptr<const SceneFrame>> frames;

  std::int64_t size() const { return features.defined() ? features.size(0) : 0; }
  /// The samples at `indices` (for batches; frames are not carried over).
  SceneTensors select(const torch::Tensor& indices) const;
};

/// Converts scenes[first, last) (all with the config's horizon) into the config's frame.
/// Throws DatasetError naming the sample if a valid vector or target holds NaN/Inf.
SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config,
                          std::size_t first, std::size_t last);
/// All scenes.
SceneTensors buildTensors(const std::vector<vector::VectorizedScene>& scenes, const VectorNetConfig& config);

}  // namespace vsd::model
