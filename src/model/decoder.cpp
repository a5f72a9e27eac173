#include "decoder.hpp"

#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/core/geometry.hpp"

namespace vsd::model {

EgoStart EgoStart::select(const torch::Tensor& indices) const {
  return {position.index_select(0, indices), heading.index_select(0, indices), speed.index_select(0, indices)};
}

Sampled Decoder::sample(const Decoded&, const EgoStart&, const torch::Tensor&) const {
  throw ModelError("this decoder is deterministic: it has no samples to draw");
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

torch::Tensor adeLoss(const torch::Tensor& predicted, const torch::Tensor& targets, const torch::Tensor& mask) {
  return displacement(predicted, targets, mask).first.mean();
}

torch::Tensor gaussianNll(const torch::Tensor& means, const torch::Tensor& covariance, const torch::Tensor& targets) {
  const auto r = targets - means;
  const auto rx = r.select(-1, 0);
  const auto ry = r.select(-1, 1);
  const auto sxx = covariance.select(-1, 0).select(-1, 0);
  const auto sxy = covariance.select(-1, 0).select(-1, 1);
  const auto syy = covariance.select(-1, 1).select(-1, 1);
  const auto determinant = sxx * syy - sxy * sxy;
  const auto quadratic = (syy * rx * rx - 2.0 * sxy * rx * ry + sxx * ry * ry) / determinant;
  return 0.5 * quadratic + 0.5 * determinant.log() + std::log(2.0 * kPi);
}

}  // namespace vsd::model
