#pragma once
// Post-hoc calibration of a probabilistic decoder (internal to the model module): one
// factor on every predicted control variance, fitted on held-out scenes so that their
// true positions fall into the predicted 90 % regions 90 % of the time.

#include "network.hpp"
#include "tensors.hpp"

namespace vsd::model {

struct VarianceCalibration {
  double scale = 1.0;           ///< the fitted variance_scale
  double coverageBefore = 0.0;  ///< share of valid held-out positions inside their 90 % region
  double coverageAfter = 0.0;
};

/// Share of the valid target positions of `scenes` inside the model's 90 % regions.
double coverage90(Model& model, const SceneTensors& scenes);

/// Fits `variance_scale` of a model whose decoder has that option: the positions' squared
/// Mahalanobis distances scale with the control variances (up to the position noise
/// floor), so scale <- scale * q90(d^2) / chi2_2(0.9), repeated until it settles.
/// Leaves `model` with the fitted scale (its config and decoder). Throws ModelError if
/// the decoder predicts no covariance.
VarianceCalibration calibrateVariance(Model& model, const SceneTensors& scenes);

}  // namespace vsd::model
