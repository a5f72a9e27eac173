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
//   decoder:  MLP on [global Ego feature, Ego polyline feature] -> the outputs of the
//             decoder chosen by name (DecoderRegistry: offsets, kinematic).
// Inputs are expressed in the model's frame (ego or lane, availableFrames());
// predictions are returned in the scene's frame.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "vsd/model/evaluation.hpp"
#include "vsd/model/intervals.hpp"
#include "vsd/model/options.hpp"
#include "vsd/model/predictor.hpp"

namespace vsd::model {

struct EpochRecord {
  int epoch = 0;
  int plannedEpochs = 0;         ///< epochs of the whole schedule
  double trainLoss = 0.0;        ///< the decoder's loss over the training samples (ADE in m, or NLL in nats)
  double validationAde = 0.0;    ///< m
  double validationFde = 0.0;    ///< m
  double validationNll = 0.0;    ///< nats per position (probabilistic decoders; NaN otherwise)
  double learningRate = 0.0;      ///< at the epoch's last step
  double samplesPerSecond = 0.0;
  double seconds = 0.0;
  bool best = false;
};

struct TrainSummary {
  std::filesystem::path output;
  std::string decoder;
  std::map<std::string, std::size_t> trainSamples;       ///< per label
  std::map<std::string, std::size_t> validationSamples;  ///< per label
  std::vector<EpochRecord> epochs;
  int plannedEpochs = 0;          ///< epochs the step budget amounts to
  int bestEpoch = 0;
  double bestValidationAde = 0.0;
  double seconds = 0.0;
  double samplesPerSecond = 0.0;  ///< training throughput (forward + backward)
  std::string stopReason;         ///< "early stopping", "max epochs", ...
  int rank = 0;                   ///< this process's rank in a distributed training (README "Distributed training")
  int ranks = 1;                  ///< processes training together (1: not distributed)
  double allreduceSeconds = 0.0;  ///< wall time the training steps spent in the gradient all-reduce
  double allreduceShare = 0.0;    ///< allreduceSeconds / the training steps' wall time (0 when not distributed)
  std::string report() const;
};

/// Trains VectorNet; prints one line per epoch through `on_epoch` (if given; rank 0 only).
/// Data-parallel over several processes when the environment names a world of more than one
/// rank (WORLD_SIZE/RANK/MASTER_ADDR/MASTER_PORT, or mpirun's; README "Distributed training"):
/// throws ConfigError when the rendezvous times out, the ranks disagree on the world size or
/// the options, or there are more ranks than --batch.
/// Throws ConfigError for an empty mix, a count larger than the data holds, an unknown
/// decoder or option; DatasetError for non-finite features; ModelError when the training
/// diverges (a non-finite loss or predicted variance: the message names the optimizer
/// step and the batch; the model file keeps the last good epoch). The best checkpoint is
/// written atomically whenever the validation ADE improves, so an interrupted training
/// leaves the previous best model intact.
TrainSummary train(const TrainOptions& options, const std::function<void(const EpochRecord&)>& on_epoch = {});

/// The metrics of every sampled future of a prediction, per metric: draws[m][s] for the
/// `count` metrics `metrics` returns (empty lists when the prediction has no samples).
std::vector<std::vector<double>> metricDraws(const vector::VectorizedScene& scene, const Prediction& prediction,
                                             const FutureMetrics& metrics, std::size_t count);

struct PredictionFileOptions {
  PredictOptions predict;            ///< samples per scene and their seed
  std::vector<std::string> metricNames;  ///< metrics written with intervals (empty: none)
  FutureMetrics metrics;             ///< computes them (required when metricNames is not empty)
};

/// Predicts every sample of one dataset and writes `vsd-predictions/3` (README). Returns
/// the number of samples.
std::size_t writePredictions(const Predictor& predictor, const std::filesystem::path& model_file,
                             const std::filesystem::path& dataset, const std::filesystem::path& output,
                             const PredictionFileOptions& options = {});

}  // namespace vsd::model
