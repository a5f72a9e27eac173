#pragma once
// The VectorNet module (internal to the model module: includes libtorch).

#include <torch/torch.h>

#include "decoder.hpp"
#include "tensors.hpp"
#include "vsd/model/model.hpp"

namespace vsd::model {

/// One subgraph layer: Linear -> LayerNorm -> ReLU on every vector's input, where the
/// input of layers after the first is [node feature, max over the polyline's nodes]
/// (VectorNet's concatenation). The pooled half is the same for all nodes of a
/// polyline, so Linear([e, p]) = e W_node^T + p W_pool^T + b is evaluated with the
/// pooled product once per polyline and broadcast, instead of materialising the
/// concatenation: identical result, half the work.
class SubgraphLayerImpl : public torch::nn::Module {
 public:
  /// `pooled_input` 0 for the first layer (no pooled half).
  SubgraphLayerImpl(int node_input, int pooled_input, int hidden);
  /// nodes [B, P, V, node_input], pooled [B, P, pooled_input] or undefined, mask [B, P, V] (float 0/1)
  /// -> (nodes [B, P, V, hidden], pooled [B, P, hidden])
  std::pair<torch::Tensor, torch::Tensor> forward(const torch::Tensor& nodes, const torch::Tensor& pooled,
                                                  const torch::Tensor& mask);

 private:
  torch::nn::Linear node_{nullptr};
  torch::nn::Linear pool_{nullptr};
  torch::nn::LayerNorm norm_{nullptr};
};
TORCH_MODULE(SubgraphLayer);

/// Encoder (subgraph + global attention) and the decoder's MLP. The MLP is registered as
/// "decoder" whatever the decoder is, so model files of every decoder share parameter names.
class VectorNetImpl : public torch::nn::Module {
 public:
  /// `output_width`: raw outputs the decoder interprets (Decoder::outputWidth()).
  VectorNetImpl(const VectorNetConfig& config, std::int64_t output_width);

  /// Raw decoder inputs [B, output_width] for a batch of scenes.
  torch::Tensor forward(const SceneTensors& scenes);

 private:
  /// Subgraph of polylines [B, P, V, 8] -> L2-normalised polyline features [B, P, H].
  torch::Tensor encodePolylines(const torch::Tensor& features, const torch::Tensor& mask);

  VectorNetConfig config_;
  torch::nn::ModuleList subgraph_;
  torch::nn::Linear query_{nullptr};
  torch::nn::Linear key_{nullptr};
  torch::nn::Linear value_{nullptr};
  torch::nn::Sequential decoder_{nullptr};
};
TORCH_MODULE(VectorNet);

/// A network and the decoder that reads its output.
struct Model {
  VectorNetConfig config;
  std::unique_ptr<Decoder> decoder;
  VectorNet network{nullptr};

  /// A new, randomly initialised model of a validated configuration (horizon and step set).
  static Model create(const VectorNetConfig& config);
  Decoded decode(const SceneTensors& scenes) { return decoder->decode(network->forward(scenes), scenes.start); }
};

/// Max over the vectors (dim 2) of non-negative node features where `mask` (float 0/1,
/// [B, P, V]) is 1; 0 for polylines without a valid vector. Multiplying by the mask
/// is exact here because every node feature is a ReLU output (>= 0).
torch::Tensor maskedMax(const torch::Tensor& nodes, const torch::Tensor& mask);

/// x W^T + b with the rows split over libtorch's intra-op threads, each calling the
/// (single-threaded) BLAS on its part. Without autograd only: used for inference,
/// where it makes the subgraph's node-wise products use both cores.
torch::Tensor rowParallelLinear(const torch::nn::Linear& linear, const torch::Tensor& x);

/// Makes libtorch use `threads` intra-op threads and OpenBLAS run single-threaded
/// inside them (two thread pools on two cores otherwise fight: ~2x slower training).
void configureThreads(int threads);

}  // namespace vsd::model
