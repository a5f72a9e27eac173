#include "kinematics.hpp"

#include <vector>

namespace vsd::model {

namespace {

/// Speeds after each step, the distance covered in it and whether it stops in it (the
/// only sequential part).
struct SpeedProfile {
  torch::Tensor speeds;
  torch::Tensor distances;
  torch::Tensor stops;
};

SpeedProfile integrateSpeeds(const torch::Tensor& speed, const torch::Tensor& accel, double dt) {
  const auto steps = accel.size(-1);
  std::vector<torch::Tensor> speeds;
  std::vector<torch::Tensor> distances;
  std::vector<torch::Tensor> stopped;
  torch::Tensor v = speed;
  for (std::int64_t k = 0; k < steps; ++k) {
    const auto a = accel.select(-1, k);
    const auto next = v + a * dt;
    const auto stops = next < 0;
    // It stops within the step only while braking (a < 0); elsewhere a dummy -1 keeps the
    // unused branch (and its gradient) finite.
    const auto braking = torch::where(stops, a, torch::full_like(a, -1.0));
    const auto stopping_distance = v * v / (-2.0 * braking);
    distances.push_back(torch::where(stops, stopping_distance, (v + next) * (0.5 * dt)));
    stopped.push_back(stops);
    v = next.clamp_min(0.0);
    speeds.push_back(v);
  }
  return {torch::stack(speeds, -1), torch::stack(distances, -1), torch::stack(stopped, -1).to(speed.scalar_type())};
}

}  // namespace

namespace {

/// The longitudinal part every rollout shares: speeds, distances, stops, accelerations.
Rollout longitudinal(const torch::Tensor& speed, const torch::Tensor& accel, double dt) {
  Rollout result;
  auto profile = integrateSpeeds(speed, accel, dt);
  result.speeds = profile.speeds;
  result.distances = profile.distances;
  result.stops = profile.stops;
  result.controlAccel = accel;
  result.initialSpeed = speed;
  const auto previous = torch::cat({speed.unsqueeze(-1), result.speeds.narrow(-1, 0, result.speeds.size(-1) - 1)}, -1);
  result.accels = (result.speeds - previous) / dt;
  return result;
}

/// Positions from the distances and mid-step headings: p_{k+1} = p_k + s_k (cos m_k, sin m_k).
void integratePositions(Rollout& path, const torch::Tensor& position) {
  const auto steps = torch::stack({path.distances * path.midHeadings.cos(), path.distances * path.midHeadings.sin()}, -1);
  path.positions = position.unsqueeze(-2) + steps.cumsum(-2);
}

}  // namespace

Rollout rollout(const torch::Tensor& position, const torch::Tensor& heading, const torch::Tensor& speed,
                const torch::Tensor& accel, const torch::Tensor& curvature, double dt) {
  Rollout result = longitudinal(speed, accel, dt);
  result.controlCurvature = curvature;
  const auto turn = curvature * result.distances;
  result.headings = heading.unsqueeze(-1) + turn.cumsum(-1);
  result.midHeadings = result.headings - 0.5 * turn;
  integratePositions(result, position);
  return result;
}

Rollout rolloutHeadings(const torch::Tensor& position, const torch::Tensor& speed, const torch::Tensor& accel,
                        const torch::Tensor& heading, double dt) {
  Rollout result = longitudinal(speed, accel, dt);
  result.controlHeading = heading;
  result.headings = heading;
  result.midHeadings = heading;
  integratePositions(result, position);
  return result;
}

namespace {

/// d p_{k+1} / d c_j for a control c from how it changes every step's distance
/// (distance[b, i, j] = d s_i / d c_j) and mid-step heading (mid_heading[b, i, j] =
/// d m_i / d c_j):
///   d p_{k+1} = sum_{i <= k} (d s_i u_i + s_i d m_i J u_i),  u_i = (cos m_i, sin m_i).
torch::Tensor positionSensitivity(const Rollout& path, const torch::Tensor& distance, const torch::Tensor& mid_heading) {
  const auto u = torch::stack({path.midHeadings.cos(), path.midHeadings.sin()}, -1).unsqueeze(2);  // [B, F, 1, 2]
  const auto ju = torch::stack({-path.midHeadings.sin(), path.midHeadings.cos()}, -1).unsqueeze(2);
  const auto per_step = distance.unsqueeze(-1) * u + (path.distances.unsqueeze(-1) * mid_heading).unsqueeze(-1) * ju;
  return per_step.cumsum(1);
}

/// d m_i / d c_j of a curvature rollout from the turns (turn[b, i, j] = d (kappa_i s_i) / d c_j):
/// the mid-step heading m_i moves by the turns of earlier steps plus half its own.
torch::Tensor midHeadingOfTurns(const torch::Tensor& turn) {
  const auto steps = turn.size(-1);
  const auto strictly_lower = torch::ones({steps, steps}, turn.options()).tril(-1);
  return torch::matmul(strictly_lower, turn) + 0.5 * turn;  // [B, F(i), F(j)]
}

}  // namespace

Sensitivities sensitivities(const Rollout& path, double dt) {
  const auto steps = path.distances.size(-1);
  const auto options = path.distances.options();
  const auto v = torch::cat({path.initialSpeed.unsqueeze(-1), path.speeds.narrow(-1, 0, steps - 1)}, -1);  // v_i
  const auto a = path.controlAccel;
  const auto stop = path.stops;
  const auto braking = torch::where(stop > 0, a, torch::full_like(a, -1.0));
  // Per step: d s_i / d v_i and d s_i / d a_i (trapezoid, or the stopping distance v^2 / 2|a|).
  const auto ds_dv = (1.0 - stop) * dt + stop * (-v / braking);
  const auto ds_da = (1.0 - stop) * (0.5 * dt * dt) + stop * (v * v / (2.0 * braking * braking));
  // d v_i / d a_j = dt for i > j unless the Ego stops in one of the steps j .. i-1.
  const auto stops_before = stop.cumsum(-1) - stop;  // N_i: stops in steps < i
  const auto unbroken = (stops_before.unsqueeze(-1) == stops_before.unsqueeze(-2)).to(options.dtype());  // [B, i, j]
  const auto later = torch::ones({steps, steps}, options).tril(-1);
  const auto distance_accel = ds_dv.unsqueeze(-1) * dt * unbroken * later + torch::diag_embed(ds_da);
  const auto no_change = torch::zeros_like(distance_accel);
  Sensitivities result;
  if (path.controlHeading.defined()) {
    // Headings are controls themselves: an acceleration only stretches the steps.
    result.accel = positionSensitivity(path, distance_accel, no_change);
    result.curvature = positionSensitivity(path, no_change, torch::diag_embed(torch::ones_like(path.distances)));
    return result;
  }
  const auto turn_accel = path.controlCurvature.unsqueeze(-1) * distance_accel;
  result.accel = positionSensitivity(path, distance_accel, midHeadingOfTurns(turn_accel));
  result.curvature = positionSensitivity(path, no_change, midHeadingOfTurns(torch::diag_embed(path.distances)));
  return result;
}

}  // namespace vsd::model
