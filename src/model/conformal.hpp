#pragma once
// Split-conformal calibration of a probabilistic model on held-out scenes (internal to the
// model module; README "Calibration"): the radii of the predicted position regions and the
// widening of metric intervals over sampled futures, per scene label and pooled. Both are
// fitted on scenes the model was not trained on, so that new scenes exchangeable with them
// fall into the nominal share of their regions and intervals.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "vsd/model/predictor.hpp"

namespace vsd::model {

struct ConformalFit {
  PositionRegions positionRegions;
  IntervalCalibration metricIntervals;
  /// Share of held-out positions at 5 s (the last step) inside the Gaussian 90 % region before calibration.
  double gaussianCoverage90AtEnd = 0.0;
  std::string report() const;  ///< one line per calibrated metric (pooled)
};

/// Per held-out scene, the names of the metrics its dataset stores (scene.metrics).
using StoredMetricNames = std::vector<std::shared_ptr<const std::vector<std::string>>>;

/// Fits the position regions of `predictor` (probabilistic) on `held_out` (scenes with
/// recorded futures) and, when `metrics` is given, the intervals of each of its metrics.
/// A metric's reference is its stored value where the scene's dataset stores it (the
/// simulated run's metric, what `compare` checks against), else the metric of the recorded
/// future (the same code as the predictions', e.g. on map exports). `seed` seeds the
/// sampled futures.
ConformalFit fitConformal(const Predictor& predictor, const std::vector<vector::VectorizedScene>& held_out,
                          const StoredMetricNames& stored, const MetricBinding* metrics, std::uint64_t seed);

}  // namespace vsd::model
