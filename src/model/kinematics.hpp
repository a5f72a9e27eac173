#pragma once
// The kinematic vehicle model of the simulated Ego (sim/vehicle_model.hpp), in libtorch
// and differentiable, for whole batches of control sequences (internal to the model module).
//
// Over step k (dt), from speed v_k, heading psi_k, position p_k with controls a_k (m/s^2)
// and curvature kappa_k (1/m):
//   v_{k+1} = max(0, v_k + a_k dt)        (no reversing)
//   s_k     = (v_k + v_{k+1}) dt / 2       (trapezoid; v_k^2 / (2 |a_k|) if it stops within the step)
//   p_{k+1} = p_k + s_k (cos m_k, sin m_k), m_k = psi_k + kappa_k s_k / 2
//   psi_{k+1} = psi_k + kappa_k s_k
// The same update as the simulator's, without its heading disturbance: a rollout of the
// controls a simulated Ego applied reproduces its positions exactly.
//
// Heading control (rolloutHeadings): instead of a curvature, each step has its own heading
// chi_k (in the frame's coordinates, e.g. relative to the lane in the lane frame), and the
// Ego moves straight along it: p_{k+1} = p_k + s_k (cos chi_k, sin chi_k), psi_{k+1} = chi_k.
// The lateral position is then one integration away from the controls instead of two,
// like a lane-keeping Ego that follows the lane's polyline step by step.

#include <torch/torch.h>

namespace vsd::model {

/// Physical limits of the controls; controls are clamped to them.
struct ControlLimits {
  double maxAccel = 4.0;       ///< m/s^2
  double maxDecel = 9.0;       ///< m/s^2 (> 0)
  double maxCurvature = 0.25;  ///< 1/m
};

/// Rollout of control sequences. Leading dimensions L (e.g. [B] or [B, S]) are shared by
/// the start state and the controls.
struct Rollout {
  torch::Tensor positions;   ///< [L..., F, 2]  p_1 .. p_F
  torch::Tensor headings;    ///< [L..., F]     psi_1 .. psi_F
  torch::Tensor speeds;      ///< [L..., F]     v_1 .. v_F
  torch::Tensor accels;      ///< [L..., F]     (v_{k+1} - v_k) / dt
  torch::Tensor distances;   ///< [L..., F]     s_0 .. s_{F-1}
  torch::Tensor midHeadings;  ///< [L..., F]    m_0 .. m_{F-1}
  torch::Tensor stops;       ///< [L..., F]     1 where the Ego comes to (or stays at) a standstill within the step
  torch::Tensor controlAccel;      ///< [L..., F] a_k as applied
  torch::Tensor controlCurvature;  ///< [L..., F] kappa_k as applied (undefined for heading control)
  torch::Tensor controlHeading;    ///< [L..., F] chi_k as applied (heading control only)
  torch::Tensor initialSpeed;      ///< [L...]    v_0
};

/// position [L..., 2], heading [L...], speed [L...], accel/curvature [L..., F].
Rollout rollout(const torch::Tensor& position, const torch::Tensor& heading, const torch::Tensor& speed,
                const torch::Tensor& accel, const torch::Tensor& curvature, double dt);

/// The same with a heading chi_k per step instead of a curvature: heading [L..., F] rad.
Rollout rolloutHeadings(const torch::Tensor& position, const torch::Tensor& speed, const torch::Tensor& accel,
                        const torch::Tensor& heading, double dt);

/// Sensitivities of the positions to the controls, the exact linearisation of the update
/// above about a rollout of batch [B]:
///   accel[b, k, j, :]     = d p_{k+1} / d a_j
///   curvature[b, k, j, :] = d p_{k+1} / d kappa_j      (zero for j > k); d p_{k+1} / d chi_j
///                           for a heading-control rollout
/// A speed change moves the Ego along (ds) and turns it (kappa ds); a standstill passes no
/// speed change on (the one-sided case of starting again is taken as 0).
struct Sensitivities {
  torch::Tensor accel;      ///< [B, F, F, 2] m / (m/s^2)
  torch::Tensor curvature;  ///< [B, F, F, 2] m / (1/m), or m / rad for heading control
};
Sensitivities sensitivities(const Rollout& rollout, double dt);

}  // namespace vsd::model
