#pragma once
// Predicting the Ego's future from vectorized scenes: a trained VectorNet (any decoder)
// or a predictor that needs no training (constant velocity, constant acceleration).
// All of them plug in wherever a model is used (predict, evaluate, compare, experiment).
// Free of libtorch.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/core/trace.hpp"
#include "vsd/model/intervals.hpp"
#include "vsd/model/options.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::model {

/// Nominal probabilities of the predicted position regions (evaluate reports their coverage).
inline constexpr std::array<double, 2> kCoverageLevels = {0.5, 0.9};

/// Conformal radii of the predicted position regions, fitted on held-out scenes (README
/// "Calibration"): per scene label ("" pooled over all labels) and future step, the
/// squared Mahalanobis radius r2 of each kCoverageLevels level, so that the region
/// {r : r' S^-1 r <= r2} of the predicted covariance S holds the true position of that
/// share of held-out scenes. Uncalibrated: the chi-square quantiles -2 ln(1 - level).
struct PositionRegions {
  std::map<std::string, std::vector<std::array<double, kCoverageLevels.size()>>> byLabel;
  std::size_t scenes = 0;  ///< held-out scenes they were fitted on
  /// The label's own radii, else the pooled ones, else nullptr (chi-square quantiles).
  const std::vector<std::array<double, kCoverageLevels.size()>>* find(const std::string& label) const;
};

/// The squared Mahalanobis radius of a 2-D Gaussian's central region of probability `level`.
double gaussianRegionRadius2(double level);

/// Metadata stored with a model (for predictors without a file: what they are).
struct ModelInfo {
  VectorNetConfig config;      ///< for cv/ca: decoder "cv"/"ca", horizon/step 0 (they adapt to the data)
  int featureVersion = vector::kFeatureVersion;
  std::string datasetSchema;
  std::string mix;
  std::uint64_t seed = 0;
  int epoch = 0;
  double validationAde = 0.0;
  std::vector<std::string> labels;  ///< labels it was trained on
  /// Kinds of road users (core/road_user.hpp names: "car", "truck", ...) in the scenes it was
  /// trained and calibrated on, sorted; empty in model files written before it was recorded.
  std::vector<std::string> roadUsers;
  std::string toolVersion;
  bool trained = true;              ///< false for cv/ca
  /// Calibration fitted after training (decoder option `calibrate`); empty otherwise.
  PositionRegions positionRegions;
  IntervalCalibration metricIntervals;
};

/// One future of the Ego, t_1 .. t_F, in the scene's frame.
struct Trajectory {
  Polyline positions;  ///< m, the Ego's centre
  /// The Ego's states at t_1 .. t_F (positions, heading, speed, acceleration over the step
  /// before: (v_k - v_{k-1}) / dt) when the predictor models the motion (kinematic decoder,
  /// cv, ca); empty for position-only decoders, whose speeds and accelerations the metric
  /// code reconstructs from positions.
  std::vector<VehicleState> states;
};

/// What a predictor says about one scene.
struct Prediction {
  Trajectory mostLikely;             ///< the mode (the mean controls' rollout for the kinematic decoder)
  std::vector<Trajectory> samples;   ///< S draws from the predictive distribution (empty if deterministic)
  /// Per step, the predictive covariance of the position (m², scene frame); empty if deterministic.
  std::vector<Eigen::Matrix2d> positionCovariance;
  /// Per step, the squared Mahalanobis radius of the region of each kCoverageLevels level
  /// (PositionRegions; chi-square quantiles for an uncalibrated model); empty if deterministic.
  std::vector<std::array<double, kCoverageLevels.size()>> regionRadius2;
  bool probabilistic() const { return !positionCovariance.empty(); }
};

/// Metrics of one predicted future (e.g. pipeline::metricsOfFuture bound to a metric set).
using FutureMetrics = std::function<std::vector<double>(const vector::VectorizedScene&, const Trajectory&)>;

/// A metric set bound for predicted futures: the names and how to compute them (in that order).
struct MetricBinding {
  std::vector<std::string> names;
  FutureMetrics compute;
};

struct PredictOptions {
  int samples = 0;          ///< futures to draw per scene (0: the most likely one only); 0 .. 100000
  std::uint64_t seed = 1;   ///< sampling seed: a scene's draws depend on (seed, the scene's identity) only
  /// Throws ConfigError naming --samples.
  void validate() const;
};

/// A model ready to predict: a model file, or "cv" / "ca" (README "Predictors without training").
class Predictor {
 public:
  /// Loads a model file, or builds the constant-velocity ("cv") or constant-acceleration
  /// ("ca") predictor. Throws ModelError naming the file for a missing, corrupt or foreign
  /// file, one written for another feature schema or of a decoder `decoders` does not know
  /// (a model trained with a decoder of one's own loads with the registry it was trained with).
  explicit Predictor(const std::filesystem::path& model, int threads = 2,
                     std::shared_ptr<const DecoderRegistry> decoders = builtinDecoders());
  Predictor(const Predictor&) = delete;
  Predictor& operator=(const Predictor&) = delete;
  ~Predictor();

  /// True for the names of the predictors without training ("cv", "ca").
  static bool isBuiltin(const std::filesystem::path& model);

  const ModelInfo& info() const;
  /// "offsets", "kinematic", ..., "cv", "ca".
  const std::string& name() const;
  bool probabilistic() const;
  /// True when its trajectories carry states (heading, speed, acceleration): Trajectory::states.
  bool predictsMotion() const;
  /// Refuses (ModelError) data whose step or horizon differs from the model's (cv/ca accept any).
  void checkCompatible(const vector::DatasetHeader& header, const std::string& what) const;
  /// Most likely Ego positions t_1 .. t_F in each scene's frame (batched, no gradients).
  std::vector<Polyline> predict(const std::vector<vector::VectorizedScene>& scenes) const;
  /// Most likely future, S samples and the position covariance per scene.
  /// Throws ConfigError for invalid options; DatasetError for non-finite features.
  std::vector<Prediction> predictDistribution(const std::vector<vector::VectorizedScene>& scenes,
                                              const PredictOptions& options) const;

  /// How a backend predicts (internal; implemented in the model module).
  class Backend;

 private:
  std::unique_ptr<Backend> backend_;
};

}  // namespace vsd::model
