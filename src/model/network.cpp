#include "network.hpp"

#include <cmath>
#include <limits>

#include "tensors.hpp"
#include "vsd/core/threads.hpp"

namespace vsd::model {

torch::Tensor maskedMax(const torch::Tensor& nodes, const torch::Tensor& mask) {
  return (nodes * mask.unsqueeze(-1)).amax(/*dim=*/2);
}

void configureThreads(int threads) {
  at::set_num_threads(threads);
  setBlasThreads(1);
}

torch::Tensor rowParallelLinear(const torch::nn::Linear& linear, const torch::Tensor& x) {
  const auto flat = x.reshape({-1, x.size(-1)});
  auto out = torch::empty({flat.size(0), linear->weight.size(0)}, x.options());
  const auto weight = linear->weight.t();
  at::parallel_for(0, flat.size(0), /*grain_size=*/2048, [&](std::int64_t begin, std::int64_t end) {
    auto rows = out.slice(0, begin, end);
    if (linear->bias.defined()) {
      at::addmm_out(rows, linear->bias, flat.slice(0, begin, end), weight);
    } else {
      at::mm_out(rows, flat.slice(0, begin, end), weight);
    }
  });
  auto shape = x.sizes().vec();
  shape.back() = linear->weight.size(0);
  return out.view(shape);
}

SubgraphLayerImpl::SubgraphLayerImpl(int node_input, int pooled_input, int hidden) {
  node_ = register_module("node", torch::nn::Linear(node_input, hidden));
  if (pooled_input > 0) {
    pool_ = register_module("pool", torch::nn::Linear(torch::nn::LinearOptions(pooled_input, hidden).bias(false)));
  }
  norm_ = register_module("norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({hidden})));
}

std::pair<torch::Tensor, torch::Tensor> SubgraphLayerImpl::forward(const torch::Tensor& nodes,
                                                                   const torch::Tensor& pooled,
                                                                   const torch::Tensor& mask) {
  const bool inference = !torch::GradMode::is_enabled();
  auto pre = inference ? rowParallelLinear(node_, nodes) : node_(nodes);  // [B, P, V, H]
  if (pool_) pre.add_(pool_(pooled).unsqueeze(2));
  auto encoded = norm_(pre).relu_();
  if (inference) {
    // Inference: zero the padded nodes in place (nothing reads them unmasked) and pool
    // without the temporary product; training needs the ReLU output unchanged for autograd.
    encoded.mul_(mask.unsqueeze(-1));
    return {encoded, encoded.amax(/*dim=*/2)};
  }
  return {encoded, maskedMax(encoded, mask)};
}

VectorNetImpl::VectorNetImpl(const VectorNetConfig& config, std::int64_t output_width) : config_(config) {
  subgraph_ = register_module("subgraph", torch::nn::ModuleList());
  for (int layer = 0; layer < config.subgraphLayers; ++layer) {
    subgraph_->push_back(SubgraphLayer(layer == 0 ? kInputFeatures : config.hidden, layer == 0 ? 0 : config.hidden,
                                       config.hidden));
  }
  const int polyline_width = config.hidden;
  query_ = register_module("query", torch::nn::Linear(polyline_width, config.globalWidth));
  key_ = register_module("key", torch::nn::Linear(polyline_width, config.globalWidth));
  value_ = register_module("value", torch::nn::Linear(polyline_width, config.globalWidth));
  decoder_ = register_module(
      "decoder",
      torch::nn::Sequential(torch::nn::Linear(config.globalWidth + polyline_width, config.decoderHidden),
                            torch::nn::LayerNorm(torch::nn::LayerNormOptions({config.decoderHidden})),
                            torch::nn::ReLU(),
                            torch::nn::Linear(config.decoderHidden, config.decoderHidden),
                            torch::nn::LayerNorm(torch::nn::LayerNormOptions({config.decoderHidden})),
                            torch::nn::ReLU(),
                            torch::nn::Linear(config.decoderHidden, output_width)));
}

torch::Tensor VectorNetImpl::encodePolylines(const torch::Tensor& features, const torch::Tensor& vector_mask) {
  // The max over the last layer's [node, pooled] features is [pooled, pooled]: the
  // pooled feature alone carries it.
  const auto mask = vector_mask.to(features.scalar_type());
  torch::Tensor nodes = features;
  torch::Tensor pooled;
  for (const auto& layer : *subgraph_) std::tie(nodes, pooled) = layer->as<SubgraphLayer>()->forward(nodes, pooled, mask);
  return torch::nn::functional::normalize(pooled,
                                          torch::nn::functional::NormalizeFuncOptions().p(2).dim(-1).eps(1e-6));
}

torch::Tensor VectorNetImpl::forward(const SceneTensors& scenes) {
  const auto others = encodePolylines(scenes.features, scenes.vectorMask);        // [B, P, H]
  const auto ego = encodePolylines(scenes.egoFeatures, scenes.egoMask).squeeze(1);  // [B, H]
  const auto batch = ego.size(0);
  // Global graph: self-attention over all polylines (the Ego's included). Only the
  // Ego's row is decoded, so only its query is computed (other rows cannot change it).
  const auto polylines = torch::cat({others, ego.unsqueeze(1)}, /*dim=*/1);        // [B, P + 1, H]
  const auto present = torch::cat({scenes.polylineMask, torch::ones({batch, 1}, torch::kBool)}, /*dim=*/1);
  const std::int64_t heads = config_.heads;
  const std::int64_t head_width = config_.globalWidth / heads;
  const auto q = query_(ego).view({batch, heads, 1, head_width});                                // [B, h, 1, d]
  const auto k = key_(polylines).view({batch, -1, heads, head_width}).transpose(1, 2);         // [B, h, P+1, d]
  const auto v = value_(polylines).view({batch, -1, heads, head_width}).transpose(1, 2);       // [B, h, P+1, d]
  auto scores = torch::matmul(q, k.transpose(-2, -1)) / std::sqrt(static_cast<double>(head_width));
  scores = scores.masked_fill(present.logical_not().view({batch, 1, 1, -1}), -std::numeric_limits<float>::infinity());
  const auto attended = torch::matmul(torch::softmax(scores, -1), v).reshape({batch, -1});    // [B, G]

  return decoder_->forward(torch::cat({attended, ego}, -1));
}

Model Model::create(const VectorNetConfig& config) {
  Model model;
  model.config = config;
  model.decoder = makeDecoder(config);
  model.network = VectorNet(config, model.decoder->outputWidth());
  return model;
}

}  // namespace vsd::model
