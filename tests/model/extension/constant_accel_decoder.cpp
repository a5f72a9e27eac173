// A test-only decoder: a constant acceleration along the Ego's initial heading.
#include "constant_accel_decoder.hpp"

#include <memory>

namespace vsd::test {

namespace {

class ConstantAccelDecoder final : public model::Decoder {
 public:
  ConstantAccelDecoder(std::int64_t horizon, double step) : horizon_(horizon), step_(step) {}

  std::int64_t outputWidth() const override { return 1; }

  model::Decoded decode(const torch::Tensor& raw, const model::EgoStart& start) const override {
    const auto t = torch::arange(1, horizon_ + 1, raw.options()) * step_;                 // [F]
    const auto accel = raw.select(1, 0).unsqueeze(1);                                      // [B, 1]
    const auto distance = start.speed.unsqueeze(1) * t + 0.5 * accel * t * t;             // [B, F]
    const auto direction = torch::stack({torch::cos(start.heading), torch::sin(start.heading)}, 1);  // [B, 2]
    model::Decoded decoded;
    decoded.positions = start.position.unsqueeze(1) + distance.unsqueeze(2) * direction.unsqueeze(1);
    return decoded;
  }

  torch::Tensor loss(const model::Decoded& decoded, const torch::Tensor& targets,
                     const torch::Tensor& mask) const override {
    return model::adeLoss(decoded.positions, targets, mask);
  }

 private:
  std::int64_t horizon_;
  double step_;
};

}  // namespace

model::DecoderEntry constantAccelDecoderEntry() {
  model::DecoderEntry entry;
  entry.info.name = "constant_accel";
  entry.info.description = "one acceleration per scene along the initial heading (test-only)";
  entry.create = [](const model::VectorNetConfig& config) -> std::unique_ptr<model::Decoder> {
    return std::make_unique<ConstantAccelDecoder>(config.horizon, config.step);
  };
  return entry;
}

}  // namespace vsd::test
