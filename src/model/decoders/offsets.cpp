// `offsets`: the paper-like decoder. The MLP predicts one displacement per step; the
// positions are their running sum from the Ego's start. With `residual` (the default, and
// what every model file written before decoders had names uses) the displacement of
// constant-velocity motion, v dt along the initial heading, is added to every predicted
// one, so the network learns only the deviation from constant velocity.
#include "offsets.hpp"

namespace vsd::model {

namespace {

class OffsetsDecoder final : public Decoder {
 public:
  OffsetsDecoder(int horizon, double step, bool residual) : horizon_(horizon), step_(step), residual_(residual) {}

  std::int64_t outputWidth() const override { return 2 * horizon_; }

  Decoded decode(const torch::Tensor& raw, const EgoStart& start) const override {
    auto offsets = raw.view({-1, horizon_, 2});
    if (residual_) {
      const auto constant_velocity =
          torch::stack({start.heading.cos(), start.heading.sin()}, -1) * (start.speed * step_).unsqueeze(-1);
      offsets = offsets + constant_velocity.unsqueeze(1);
    }
    Decoded decoded;
    decoded.positions = offsets.cumsum(1) + start.position.unsqueeze(1);
    return decoded;
  }

  torch::Tensor loss(const Decoded& decoded, const torch::Tensor& targets, const torch::Tensor& mask) const override {
    return adeLoss(decoded.positions, targets, mask);  // the ADE the model is judged by
  }

 private:
  std::int64_t horizon_;
  double step_;
  bool residual_;
};

}  // namespace

DecoderEntry offsetsDecoderEntry() {
  DecoderEntry entry;
  entry.info.name = "offsets";
  entry.info.description = "one displacement per step, summed into positions (the paper-like baseline); trained on ADE";
  entry.info.options = {{"residual", 1.0, 0.0, 1.0,
                         "1: predict deviations from constant-velocity motion (v dt along the initial heading); "
                         "0: predict the displacements themselves"}};
  entry.create = [](const VectorNetConfig& config) -> std::unique_ptr<Decoder> {
    return std::make_unique<OffsetsDecoder>(config.horizon, config.step, config.decoderOption("residual") != 0.0);
  };
  return entry;
}

}  // namespace vsd::model
