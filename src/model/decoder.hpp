#pragma once
// Decoders (internal to the model module: includes libtorch).
//
// The network ends in an MLP whose last layer has as many outputs as the decoder asks
// for (outputWidth); the decoder turns them into the Ego's future: its most likely
// positions and, depending on the decoder, speeds and accelerations, a position
// covariance per step and a way to draw samples. It also defines the training loss.
// Adding a decoder: one source file with its class and a function returning its
// DecoderEntry, one line in decoder_registry.cpp (or, outside the model module, one
// DecoderRegistry::add() call on the registry the model is trained and loaded with;
// docs/design.md).
//
// Everything here is in the model's frame (README "Representations"): metres, radians,
// the Ego starting at `EgoStart`.

#include <torch/torch.h>

#include <functional>
#include <memory>
#include <vector>

#include "vsd/model/options.hpp"

namespace vsd::model {

/// The Ego's initial state in the model's frame, per sample of a batch.
struct EgoStart {
  torch::Tensor position;  ///< [B, 2] m
  torch::Tensor heading;   ///< [B] rad
  torch::Tensor speed;     ///< [B] m/s
  EgoStart select(const torch::Tensor& indices) const;
};

/// A decoded batch. Tensors a decoder does not produce stay undefined.
struct Decoded {
  torch::Tensor positions;   ///< [B, F, 2] m: the most likely future
  torch::Tensor headings;    ///< [B, F] rad
  torch::Tensor speeds;      ///< [B, F] m/s
  torch::Tensor accels;      ///< [B, F] m/s^2: (v_k - v_{k-1}) / dt
  torch::Tensor covariance;  ///< [B, F, 2, 2] m^2: predictive covariance of each position
  /// Decoder-specific parameters of the distribution (what sample() needs).
  std::vector<torch::Tensor> parameters;
};

/// Futures drawn from a decoded distribution: [B, S, F(, 2)]; no covariance.
using Sampled = Decoded;

class Decoder {
 public:
  virtual ~Decoder() = default;
  /// Raw network outputs this decoder interprets (per sample).
  virtual std::int64_t outputWidth() const = 0;
  /// raw [B, outputWidth] -> the distribution of the future.
  virtual Decoded decode(const torch::Tensor& raw, const EgoStart& start) const = 0;
  /// Scalar training loss of a batch: targets [B, F, 2] (model frame), mask [B, F] (valid steps).
  virtual torch::Tensor loss(const Decoded& decoded, const torch::Tensor& targets, const torch::Tensor& mask) const = 0;
  /// Standard-normal numbers one sampled future needs; 0 for deterministic decoders.
  virtual std::int64_t noiseWidth() const { return 0; }
  /// Futures for noise [B, S, noiseWidth()] (only called when noiseWidth() > 0).
  virtual Sampled sample(const Decoded& decoded, const EgoStart& start, const torch::Tensor& noise) const;
};

/// A registry entry (DecoderRegistry, vsd/model/options.hpp): the public description and how
/// to build the decoder.
struct DecoderEntry {
  DecoderInfo info;
  /// Builds the decoder for a validated configuration (horizon, step and options set).
  std::function<std::unique_ptr<Decoder>(const VectorNetConfig&)> create;
};

/// The decoder of a validated configuration, from the configuration's own registry.
std::unique_ptr<Decoder> makeDecoder(const VectorNetConfig& config);

/// Mean (over valid steps) Euclidean distance per sample [N] and final distance [N].
std::pair<torch::Tensor, torch::Tensor> displacement(const torch::Tensor& predicted, const torch::Tensor& targets,
                                                     const torch::Tensor& mask);
/// The ADE of a batch: mean over samples of the mean displacement over valid steps.
torch::Tensor adeLoss(const torch::Tensor& predicted, const torch::Tensor& targets, const torch::Tensor& mask);

/// Per-step 2-D Gaussian negative log-likelihood [B, F] (nats) of targets [B, F, 2] under
/// means [B, F, 2] and covariances [B, F, 2, 2].
torch::Tensor gaussianNll(const torch::Tensor& means, const torch::Tensor& covariance, const torch::Tensor& targets);

}  // namespace vsd::model
