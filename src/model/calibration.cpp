#include "calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "decoder.hpp"
#include "vsd/core/error.hpp"

namespace vsd::model {

namespace {

/// The 90 % quantile of the chi-square distribution with 2 degrees of freedom: -2 ln 0.1.
const double kChiSquare90 = -2.0 * std::log(0.1);
constexpr std::int64_t kBatch = 1024;

/// Squared Mahalanobis distances of every valid target position [n] under the decoded covariances.
torch::Tensor squaredDistances(Model& model, const SceneTensors& scenes) {
  torch::NoGradGuard no_grad;
  model.network->eval();
  std::vector<torch::Tensor> parts;
  for (std::int64_t first = 0; first < scenes.size(); first += kBatch) {
    const auto batch = scenes.select(torch::arange(first, std::min(first + kBatch, scenes.size()), torch::kInt64));
    const auto decoded = model.decode(batch);
    if (!decoded.covariance.defined()) {
      throw ModelError(fmt::format("decoder '{}' predicts no covariance: nothing to calibrate", model.config.decoder));
    }
    const auto r = (batch.targets - decoded.positions).to(torch::kFloat64);
    const auto c = decoded.covariance.to(torch::kFloat64);
    const auto a = c.select(-1, 0).select(-1, 0);
    const auto b = c.select(-1, 1).select(-1, 0);
    const auto d = c.select(-1, 1).select(-1, 1);
    const auto x = r.select(-1, 0);
    const auto y = r.select(-1, 1);
    const auto m2 = (d * x * x - 2.0 * b * x * y + a * y * y) / (a * d - b * b);
    parts.push_back(m2.masked_select(batch.targetMask));
  }
  return torch::cat(parts);
}

void setScale(Model& model, double scale) {
  model.config.decoderOptions["variance_scale"] = scale;
  model.decoder = makeDecoder(model.config);
}

}  // namespace

double coverage90(Model& model, const SceneTensors& scenes) {
  const auto m2 = squaredDistances(model, scenes);
  return m2.numel() == 0 ? 0.0 : (m2 <= kChiSquare90).to(torch::kFloat64).mean().item<double>();
}

VarianceCalibration calibrateVariance(Model& model, const SceneTensors& scenes) {
  VarianceCalibration result;
  double scale = model.config.decoderOption("variance_scale");
  for (int iteration = 0; iteration < 6; ++iteration) {
    const auto m2 = squaredDistances(model, scenes);
    if (m2.numel() == 0) break;
    if (iteration == 0) result.coverageBefore = (m2 <= kChiSquare90).to(torch::kFloat64).mean().item<double>();
    const double factor = m2.quantile(0.9).item<double>() / kChiSquare90;
    scale = std::clamp(scale * factor, 1e-3, 1e3);
    setScale(model, scale);
    if (std::abs(factor - 1.0) < 1e-3) break;
  }
  result.scale = scale;
  result.coverageAfter = coverage90(model, scenes);
  return result;
}

}  // namespace vsd::model
