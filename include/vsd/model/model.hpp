#pragma once
// VectorNet (Gao et al. 2020) for predicting the Ego's future from a vectorized
// scene, trained on datasets mixed from different functional scenarios and maps.
// This header is free of libtorch so that other modules can include it.
//
// Architecture (see README "VectorNet"):
//   subgraph: L layers of Linear -> LayerNorm -> ReLU per vector, max-pool over the
//             polyline's valid vectors, pooled feature concatenated to every vector;
//             polyline feature = max-pool of the last layer, L2-normalised (hidden wide);
//   global:   one self-attention layer over the polylines (padding masked), queried
//             by the Ego's polyline;
//   decoder:  MLP on [global Ego feature, Ego polyline feature] -> F per-step
//             offsets (m), summed into positions.
// Inputs are expressed in the Ego's initial frame (translated to its position,
// rotated by its heading); predictions are returned in the scene's frame.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/vector/dataset.hpp"
#include "vsd/vector/scene.hpp"

namespace vsd::model {

/// Architecture hyper-parameters (stored in the model file).
struct VectorNetConfig {
  int hidden = 64;           ///< width of the subgraph layers and of polyline features
  int subgraphLayers = 3;
  int globalWidth = 128;     ///< width of the attention's queries, keys and values
  int heads = 1;             ///< attention heads (globalWidth must be divisible by heads)
  int decoderHidden = 256;
  int horizon = 0;           ///< predicted steps (>= 1); no default: from the training data's header
  double step = 0.0;         ///< s between predicted positions (> 0); no default, like horizon
  double coordinateScale = 10.0;  ///< m: ego-frame coordinates are divided by this before the network

  /// Throws ConfigError naming the field and the constraint (architecture and time base).
  void validate() const;
  /// The architecture alone: the time base comes from the data, checked once it is known.
  void validateArchitecture() const;
};

/// How many samples of each label to train on, e.g. "acc=2000,lk=2000,acc_lk=200".
struct Mix {
  std::vector<std::pair<std::string, std::size_t>> counts;
  /// Throws ConfigError for malformed text, counts < 0 or a label named twice; "" is empty.
  static Mix parse(const std::string& text);
  std::size_t total() const;
  std::string str() const;
};

struct TrainOptions {
  std::vector<std::filesystem::path> data;  ///< dataset files or run folders
  Mix mix;                                  ///< empty: every sample of every file
  std::filesystem::path output;             ///< model file (.pt); the best epoch by validation ADE
  VectorNetConfig config;
  std::uint64_t seed = 1;
  int threads = 2;                          ///< libtorch intra-op threads
  int steps = 6000;                         ///< optimizer steps: the learning-rate schedule's length
  int patience = 40;                        ///< epochs without a better validation ADE before stopping
  int batchSize = 64;
  double learningRate = 2e-3;               ///< peak (after a 200-step warm-up; cosine decay to 2 % by `steps`)
  double weightDecay = 1e-4;
  double validationFraction = 0.1;          ///< the paper's 90 % / 10 % split
  bool resume = false;                      ///< continue from <output>.last if it exists
  /// Throws ConfigError naming the flag and the constraint.
  void validate() const;
};

struct EpochRecord {
  int epoch = 0;
  int plannedEpochs = 0;         ///< epochs of the whole schedule
  double trainLoss = 0.0;        ///< mean displacement over the training samples (m)
  double validationAde = 0.0;    ///< m
  double validationFde = 0.0;    ///< m
  double learningRate = 0.0;      ///< at the epoch's last step
  double samplesPerSecond = 0.0;
  double seconds = 0.0;
  bool best = false;
};

struct TrainSummary {
  std::filesystem::path output;
  std::map<std::string, std::size_t> trainSamples;       ///< per label
  std::map<std::string, std::size_t> validationSamples;  ///< per label
  std::vector<EpochRecord> epochs;
  int plannedEpochs = 0;          ///< epochs the step budget amounts to
  int bestEpoch = 0;
  double bestValidationAde = 0.0;
  double seconds = 0.0;
  double samplesPerSecond = 0.0;  ///< training throughput (forward + backward)
  std::string stopReason;         ///< "early stopping", "max epochs", ...
  std::string report() const;
};

/// Trains VectorNet; prints one line per epoch through `on_epoch` (if given).
/// Throws ConfigError for an empty mix or a count larger than the data holds,
/// DatasetError for non-finite features. The best checkpoint is written
/// atomically whenever the validation ADE improves, so an interrupted training
/// leaves the previous best model intact.
TrainSummary train(const TrainOptions& options, const std::function<void(const EpochRecord&)>& on_epoch = {});

/// Metadata stored with a model.
struct ModelInfo {
  VectorNetConfig config;
  int featureVersion = vector::kFeatureVersion;
  std::string datasetSchema;
  std::string mix;
  std::uint64_t seed = 0;
  int epoch = 0;
  double validationAde = 0.0;
  std::vector<std::string> labels;  ///< labels it was trained on
  std::string toolVersion;
};

/// A trained model, ready to predict.
class Predictor {
 public:
  /// Loads a model file. Throws ModelError naming the file for a missing, corrupt or
  /// foreign file, or one written for another feature schema.
  explicit Predictor(const std::filesystem::path& model, int threads = 2);
  Predictor(const Predictor&) = delete;
  Predictor& operator=(const Predictor&) = delete;
  ~Predictor();

  const ModelInfo& info() const;
  /// Refuses (ModelError) a dataset whose step or horizon differs from the model's.
  void checkCompatible(const vector::DatasetHeader& header, const std::string& what) const;
  /// Predicted Ego positions t_1 .. t_F in each scene's frame (batched, no gradients).
  std::vector<Polyline> predict(const std::vector<vector::VectorizedScene>& scenes) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// ADE/FDE of predictions against the scenes' targets.
struct LabelErrors {
  std::size_t samples = 0;
  double ade = 0.0;  ///< m, mean over samples of the mean displacement over valid steps
  double fde = 0.0;  ///< m, mean displacement at the last valid step
};

/// Displacement errors of one prediction (mean and final over valid target steps).
LabelErrors displacementErrors(const Polyline& prediction, const vector::VectorizedScene& scene);

struct Evaluation {
  std::map<std::string, LabelErrors> perLabel;
  LabelErrors overall;
  double predictionSeconds = 0.0;
  std::string table() const;
  /// label,samples,ade,fde rows (overall last).
  void writeCsv(const std::filesystem::path& path) const;
};

/// Predicts every sample of the datasets and averages the errors per label.
Evaluation evaluate(const Predictor& predictor, const std::vector<std::filesystem::path>& data);

/// Predicts every sample of one dataset and writes `vsd-predictions/1` (README).
std::size_t writePredictions(const Predictor& predictor, const std::filesystem::path& model_file,
                             const std::filesystem::path& dataset, const std::filesystem::path& output);

}  // namespace vsd::model
