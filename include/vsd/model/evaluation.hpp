#pragma once
// How good predictions are: displacement errors for every predictor; for probabilistic
// ones also the negative log-likelihood of the true positions and how often the
// predicted 50 % / 90 % regions contain them (calibration). Free of libtorch.

#include <array>
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "vsd/model/predictor.hpp"

namespace vsd::model {

/// Where in the horizon evaluate reports NLL and coverage of positions: these shares of
/// the scenes' own horizon, rounded to whole steps (1 s, 3 s and 5 s of the paper's 5 s).
inline constexpr std::array<double, 3> kCalibrationShares = {0.2, 0.6, 1.0};
inline constexpr std::size_t kCalibrationPoints = kCalibrationShares.size();

/// The target step (t_1 is 0) of each calibration point in a horizon of `horizon_steps`
/// steps (>= 1): the share of the horizon rounded to whole steps, at least the first.
std::array<std::size_t, kCalibrationPoints> calibrationSteps(std::size_t horizon_steps);

/// Running sums of the errors of many predictions (means are read off with the accessors).
struct LabelErrors {
  std::size_t samples = 0;
  double ade = 0.0;  ///< m, mean over samples of the mean displacement over valid steps
  double fde = 0.0;  ///< m, mean displacement at the last valid step
  /// Probabilistic predictors only (`scored` = 0 otherwise): per-step 2-D Gaussian NLL
  /// of the true position (nats, mean over valid steps, then over samples).
  std::size_t scored = 0;
  double nll = 0.0;
  /// At each calibration point (calibrationSteps of the scene's horizon): scenes with a valid true position there, their mean
  /// NLL, and the share of them inside the predicted region of each kCoverageLevels level
  /// (the ellipse {r : r' S^-1 r <= r2} of the predictive covariance S, r2 = the
  /// prediction's regionRadius2: -2 ln(1 - level) unless the model is calibrated).
  std::array<std::size_t, kCalibrationPoints> countAt{};
  std::array<double, kCalibrationPoints> nllAt{};
  std::array<std::array<double, kCoverageLevels.size()>, kCalibrationPoints> coverageAt{};

  /// Adds one scene's errors (a scene without a valid step is not counted).
  void add(const LabelErrors& one);
};

/// Displacement errors of one prediction (mean and final over valid target steps).
LabelErrors displacementErrors(const Polyline& prediction, const vector::VectorizedScene& scene);
/// Displacement errors and, for a probabilistic prediction, NLL and coverage.
LabelErrors predictionErrors(const Prediction& prediction, const vector::VectorizedScene& scene);

struct Evaluation {
  std::string predictor;  ///< decoder or predictor name
  std::map<std::string, LabelErrors> perLabel;
  LabelErrors overall;
  /// s after t0 of each calibration point: calibrationSteps of the datasets' horizon.
  std::array<double, kCalibrationPoints> calibrationTimes{};
  double predictionSeconds = 0.0;
  std::string table() const;
  /// label,samples,ade_m,fde_m[,nll,nll_1s,...,coverage50_1s,...] rows (overall last).
  void writeCsv(const std::filesystem::path& path) const;
};

/// Predicts every sample of the datasets and averages the errors per label. The datasets
/// share one step and horizon (else DatasetError): the calibration points are theirs.
Evaluation evaluate(const Predictor& predictor, const std::vector<std::filesystem::path>& data);

}  // namespace vsd::model
