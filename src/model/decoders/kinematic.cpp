// `kinematic`: the network predicts the Ego's controls - a longitudinal acceleration and a
// path curvature per step - bounded to physical limits and integrated through the
// simulator's kinematic vehicle model (kinematics.hpp) from the Ego's initial position,
// heading and speed. Every prediction is drivable, and its speeds and accelerations are
// the model's own.
//
// Predictive distribution: the controls are Gaussian around the predicted ones - an
// independent deviation per step (sigma_a,k, sigma_kappa,k) plus one deviation shared by
// all steps of a future (sigma_a,bias, sigma_kappa,bias: a systematic "brakes harder",
// "cuts the curve"); all standard deviations are outputs of the network. Linearised
// through the vehicle model this gives a Gaussian per position (plus a floor of
// kPositionNoise for float32 storage of the targets), and the loss is its negative
// log-likelihood of the true positions. Samples draw the controls and roll them out
// exactly (clamped to the limits, no reversing).
//
// Options off by default (they leave the decoder's numerics as they were):
// `variance_scale` multiplies every control variance (the post-hoc calibration of
// `calibrate`, fitted on the validation split after training, calibration.hpp);
// `accel_weight` adds the mean absolute error between the predicted accelerations and
// those of the true positions; `amin_weight` the absolute error of their minima (a_min of
// the most likely future), so that a_min of a prediction is learnt directly.
#include "kinematic.hpp"

#include <cmath>

#include "../kinematics.hpp"
#include "vsd/core/geometry.hpp"

namespace vsd::model {

namespace {

constexpr double kAccelUnit = 1.0;        ///< m/s^2 per unit of network output
constexpr double kCurvatureUnit = 0.01;   ///< 1/m per unit of network output
constexpr double kHeadingUnit = 0.1;      ///< rad per unit of network output (heading control)
constexpr double kPositionNoise = 0.02;   ///< m, floor of every position's standard deviation

class KinematicDecoder final : public Decoder {
 public:
  KinematicDecoder(const VectorNetConfig& config)
      : horizon_(config.horizon),
        step_(config.step),
        limits_{config.decoderOption("max_accel"), config.decoderOption("max_decel"),
                config.decoderOption("max_curvature")},
        probabilistic_(config.decoderOption("nll") != 0.0),
        adeWeight_(config.decoderOption("ade_weight")),
        accelWeight_(config.decoderOption("accel_weight")),
        minAccelWeight_(config.decoderOption("amin_weight")),
        accelNllWeight_(config.decoderOption("accel_nll")),
        sigmaScale_(std::sqrt(config.decoderOption("variance_scale"))),
        headingControl_(config.decoderOption("heading_control") != 0.0),
        maxHeading_(config.decoderOption("max_heading")),
        lateralUnit_(headingControl_ ? kHeadingUnit : kCurvatureUnit) {}

  std::int64_t outputWidth() const override { return 4 * horizon_ + 2; }

  Decoded decode(const torch::Tensor& raw, const EgoStart& start) const override {
    const auto accel = boundAccel(raw.narrow(1, 0, horizon_) * kAccelUnit);
    const auto lateral = boundLateral(raw.narrow(1, horizon_, horizon_) * lateralUnit_);
    const auto path = roll(start, accel, lateral);
    Decoded decoded;
    decoded.positions = path.positions;
    decoded.headings = path.headings;
    decoded.speeds = path.speeds;
    decoded.accels = path.accels;
    if (!probabilistic_) {
      decoded.parameters = {start.position, start.speed};  // what accelError needs
      return decoded;
    }

    const auto sigma_accel = standardDeviation(raw.narrow(1, 2 * horizon_, horizon_), kAccelUnit * sigmaScale_);
    const auto sigma_lateral = standardDeviation(raw.narrow(1, 3 * horizon_, horizon_), lateralUnit_ * sigmaScale_);
    const auto sigma_accel_bias = standardDeviation(raw.select(1, 4 * horizon_), kAccelUnit * sigmaScale_);
    const auto sigma_lateral_bias = standardDeviation(raw.select(1, 4 * horizon_ + 1), lateralUnit_ * sigmaScale_);
    decoded.covariance = positionCovariance(path, sigma_accel, sigma_lateral, sigma_accel_bias, sigma_lateral_bias);
    decoded.parameters = {accel,           lateral,           sigma_accel, sigma_lateral, sigma_accel_bias,
                          sigma_lateral_bias, start.position, start.speed};
    return decoded;
  }

  torch::Tensor loss(const Decoded& decoded, const torch::Tensor& targets, const torch::Tensor& mask) const override {
    auto loss = positionLoss(decoded, targets, mask);
    if (accelWeight_ > 0.0 || minAccelWeight_ > 0.0 || accelNllWeight_ > 0.0) {
      const auto true_accels = trueAccels(decoded, targets);
      const auto weights = mask.to(torch::kFloat32).cumprod(1);  // steps after an invalid position are left out
      if (accelWeight_ > 0.0) loss = loss + accelWeight_ * accelError(decoded.accels, true_accels, weights);
      if (minAccelWeight_ > 0.0) loss = loss + minAccelWeight_ * minAccelError(decoded.accels, true_accels, weights);
      if (accelNllWeight_ > 0.0 && probabilistic_) {
        loss = loss + accelNllWeight_ * accelNll(decoded, true_accels, weights);
      }
    }
    return loss;
  }

  std::int64_t noiseWidth() const override { return probabilistic_ ? 2 * horizon_ + 2 : 0; }

  Sampled sample(const Decoded& decoded, const EgoStart& start, const torch::Tensor& noise) const override {
    const auto& p = decoded.parameters;  // accel, lateral control, their sigmas, the bias sigmas, the start
    const auto draws = noise.size(1);
    auto accel = p[0].unsqueeze(1) + p[2].unsqueeze(1) * noise.narrow(2, 0, horizon_) +
                 (p[4].unsqueeze(1) * noise.select(2, 2 * horizon_)).unsqueeze(-1);
    auto lateral = p[1].unsqueeze(1) + p[3].unsqueeze(1) * noise.narrow(2, horizon_, horizon_) +
                   (p[5].unsqueeze(1) * noise.select(2, 2 * horizon_ + 1)).unsqueeze(-1);
    accel = accel.clamp(-limits_.maxDecel, limits_.maxAccel);
    const double lateral_limit = headingControl_ ? maxHeading_ : limits_.maxCurvature;
    lateral = lateral.clamp(-lateral_limit, lateral_limit);
    const auto expand = [draws](const torch::Tensor& t) {
      auto sizes = t.sizes().vec();
      sizes.insert(sizes.begin() + 1, draws);
      return t.unsqueeze(1).expand(sizes);
    };
    const EgoStart expanded{expand(start.position), expand(start.heading), expand(start.speed)};
    const auto path = roll(expanded, accel, lateral);
    Sampled sampled;
    sampled.positions = path.positions;
    sampled.headings = path.headings;
    sampled.speeds = path.speeds;
    sampled.accels = path.accels;
    return sampled;
  }

 private:
  /// Identity near 0 (slope 1), saturating smoothly at -max_decel and +max_accel.
  torch::Tensor boundAccel(const torch::Tensor& raw) const {
    return torch::where(raw >= 0, limits_.maxAccel * torch::tanh(raw / limits_.maxAccel),
                        limits_.maxDecel * torch::tanh(raw / limits_.maxDecel));
  }
  /// The lateral control within its limit: curvature (1/m) or heading (rad).
  torch::Tensor boundLateral(const torch::Tensor& raw) const {
    const double limit = headingControl_ ? maxHeading_ : limits_.maxCurvature;
    return limit * torch::tanh(raw / limit);
  }
  Rollout roll(const EgoStart& start, const torch::Tensor& accel, const torch::Tensor& lateral) const {
    if (headingControl_) return rolloutHeadings(start.position, start.speed, accel, lateral, step_);
    return rollout(start.position, start.heading, start.speed, accel, lateral, step_);
  }
  /// Positive, about 0.3 units for a raw output of 0, never below 0.1 % of a unit.
  static torch::Tensor standardDeviation(const torch::Tensor& raw, double unit) {
    return unit * (torch::nn::functional::softplus(raw - 1.0) + 1e-3);
  }

  torch::Tensor positionCovariance(const Rollout& path, const torch::Tensor& sigma_accel,
                                   const torch::Tensor& sigma_lateral, const torch::Tensor& sigma_accel_bias,
                                   const torch::Tensor& sigma_lateral_bias) const {
    const auto sens = sensitivities(path, step_);
    const auto per_step_accel = sens.accel * sigma_accel.view({-1, 1, horizon_, 1});
    const auto per_step_curvature = sens.curvature * sigma_lateral.view({-1, 1, horizon_, 1});
    const auto bias_accel = sens.accel.sum(2) * sigma_accel_bias.view({-1, 1, 1});
    const auto bias_curvature = sens.curvature.sum(2) * sigma_lateral_bias.view({-1, 1, 1});
    auto covariance = torch::einsum("bkjx,bkjy->bkxy", {per_step_accel, per_step_accel}) +
                      torch::einsum("bkjx,bkjy->bkxy", {per_step_curvature, per_step_curvature}) +
                      bias_accel.unsqueeze(-1) * bias_accel.unsqueeze(-2) +
                      bias_curvature.unsqueeze(-1) * bias_curvature.unsqueeze(-2);
    return covariance + kPositionNoise * kPositionNoise * torch::eye(2, covariance.options());
  }

  /// The ADE (nll off) or the NLL of the true positions plus ade_weight times the ADE.
  torch::Tensor positionLoss(const Decoded& decoded, const torch::Tensor& targets, const torch::Tensor& mask) const {
    const auto ade = adeLoss(decoded.positions, targets, mask);
    if (!probabilistic_) return ade;
    const auto weights = mask.to(torch::kFloat32);
    const auto nll = gaussianNll(decoded.positions, decoded.covariance, targets);
    const auto per_sample = (nll * weights).sum(1) / weights.sum(1).clamp_min(1.0);
    return per_sample.mean() + adeWeight_ * ade;
  }

  /// The accelerations (m/s^2) of the true positions [B, F] under the same vehicle model:
  /// the distance of step k is the trapezoid s_k = (v_k + v_{k+1}) dt / 2, so
  /// v_{k+1} = 2 s_k / dt - v_k from the start speed and a_k = (v_{k+1} - v_k) / dt (exact
  /// for a simulated Ego; no reversing).
  torch::Tensor trueAccels(const Decoded& decoded, const torch::Tensor& targets) const {
    const auto& start_position = decoded.parameters.at(decoded.parameters.size() - 2);
    const auto& start_speed = decoded.parameters.back();
    const auto previous = torch::cat({start_position.unsqueeze(1), targets.narrow(1, 0, horizon_ - 1)}, 1);
    const auto distances = (targets - previous).norm(2, -1);  // [B, F]
    std::vector<torch::Tensor> accels;
    auto speed = start_speed;
    for (std::int64_t k = 0; k < horizon_; ++k) {
      const auto next = (2.0 * distances.select(1, k) / step_ - speed).clamp_min(0.0);
      accels.push_back((next - speed) / step_);
      speed = next;
    }
    return torch::stack(accels, 1);
  }

  /// Mean absolute difference (m/s^2) between the predicted and the true accelerations over
  /// the steps with weight 1.
  static torch::Tensor accelError(const torch::Tensor& predicted, const torch::Tensor& truth,
                                  const torch::Tensor& weights) {
    return ((predicted - truth).abs() * weights).sum() / weights.sum().clamp_min(1.0);
  }

  /// Mean (over the steps with weight 1) Gaussian NLL (nats) of the true accelerations under
  /// each step's marginal N(a_k, sigma_a,k^2 + sigma_a,bias^2): trains the acceleration
  /// noise that sampled futures (and so the spread of their a_min) are drawn with, which the
  /// positions alone barely constrain (they integrate it twice).
  static torch::Tensor accelNll(const Decoded& decoded, const torch::Tensor& truth, const torch::Tensor& weights) {
    const auto variance = decoded.parameters[2].pow(2) + decoded.parameters[4].pow(2).unsqueeze(1);
    const auto nll = 0.5 * ((truth - decoded.accels).pow(2) / variance + variance.log() + std::log(2.0 * kPi));
    return (nll * weights).sum() / weights.sum().clamp_min(1.0);
  }

  /// Mean over samples of |min_k predicted a_k - min_k true a_k| (m/s^2) over the steps with
  /// weight 1: the error of a_min itself, whose metric is the minimum of the predicted
  /// accelerations. Samples without a valid step are left out.
  static torch::Tensor minAccelError(const torch::Tensor& predicted, const torch::Tensor& truth,
                                     const torch::Tensor& weights) {
    constexpr double kNotAMinimum = 1e3;  // m/s^2, above any acceleration: masks invalid steps out of the min
    const auto outside = (1.0 - weights) * kNotAMinimum;
    const auto predicted_min = std::get<0>((predicted + outside).min(1));
    const auto true_min = std::get<0>((truth + outside).min(1));
    const auto scored = (weights.sum(1) > 0).to(torch::kFloat32);
    return ((predicted_min - true_min).abs() * scored).sum() / scored.sum().clamp_min(1.0);
  }

  std::int64_t horizon_;
  double step_;
  ControlLimits limits_;
  bool probabilistic_;
  double adeWeight_;
  double accelWeight_;
  double minAccelWeight_;
  double accelNllWeight_;
  double sigmaScale_;
  bool headingControl_;
  double maxHeading_;
  double lateralUnit_;  ///< network unit of the lateral control: 1/m or rad
};

}  // namespace

DecoderEntry kinematicDecoderEntry() {
  DecoderEntry entry;
  entry.info.name = "kinematic";
  entry.info.description =
      "per-step acceleration and curvature, bounded and integrated through the kinematic vehicle model; "
      "Gaussian controls (per step + per future) trained by the NLL of the positions";
  entry.info.probabilistic = true;
  entry.info.kinematic = true;
  entry.info.options = {
      {"max_accel", 4.0, 0.1, 20.0, "m/s^2, largest acceleration (the simulated Ego's limit)"},
      {"max_decel", 9.0, 0.1, 20.0, "m/s^2, largest deceleration (the simulated Ego's limit)"},
      {"max_curvature", 0.25, 0.001, 2.0, "1/m, largest path curvature (the simulated Ego's limit)"},
      {"heading_control", 1.0, 0.0, 1.0,
       "1: the lateral control is the heading of each step in the model's frame (relative to the lane in the lane "
       "frame) instead of a curvature: the lateral position is one integration from the controls, not two"},
      {"max_heading", 3.0, 0.01, 3.1,
       "rad, largest heading of a step in the model's frame (heading control; the lane frame needs far less)"},
      {"nll", 1.0, 0.0, 1.0, "1: predictive distribution trained by NLL; 0: most likely future only, trained on ADE"},
      {"ade_weight", 0.0, 0.0, 100.0, "weight of the ADE of the most likely future added to the NLL"},
      {"accel_weight", 0.0, 0.0, 100.0,
       "weight of the mean absolute error (m/s^2) of the predicted accelerations against those of the true positions"},
      {"amin_weight", 0.0, 0.0, 100.0,
       "weight of the mean absolute error (m/s^2) of the minimum predicted acceleration (the a_min metric of the most "
       "likely future) against that of the true positions"},
      {"accel_nll", 0.0, 0.0, 100.0,
       "weight of the NLL of the true accelerations under each step's predicted acceleration distribution (trains "
       "the acceleration noise of sampled futures, e.g. the spread of their a_min)"},
      {"calibrate", 0.0, 0.0, 1.0,
       "1: after training, fit variance_scale on the validation split (90 % of its positions in their 90 % regions)"},
      {"variance_scale", 1.0, 1e-3, 1e3, "multiplies every predicted control variance (written by calibrate)"},
  };
  // vsd-model/2 files were written before heading control existed: curvature control.
  entry.info.optionsBeforeModelFormat3 = {{"heading_control", 0.0}};
  entry.create = [](const VectorNetConfig& config) -> std::unique_ptr<Decoder> {
    return std::make_unique<KinematicDecoder>(config);
  };
  return entry;
}

}  // namespace vsd::model
