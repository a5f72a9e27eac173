#pragma once
// Model files: the network's parameters and a JSON description (architecture,
// feature schema, training provenance) in one torch archive, written atomically.
// Training checkpoints (<model>.last) add the optimizer state for --resume.

#include <torch/torch.h>

#include <filesystem>
#include <memory>
#include <string>

#include "network.hpp"
#include "vsd/model/predictor.hpp"

namespace vsd::model {

// Reading a description needs the registry of the decoder it names (its options' defaults,
// the options older model formats lack): the loader's, handed on into the configuration.
using Decoders = std::shared_ptr<const DecoderRegistry>;

std::string infoToJson(const ModelInfo& info);
ModelInfo infoFromJson(const std::string& text, const std::filesystem::path& file, const Decoders& decoders);

/// Writes a model file (temporary name, then rename).
void saveModel(const std::filesystem::path& path, const Model& model, const ModelInfo& info);

/// Reads a model file's description without building the network. Throws ModelError.
ModelInfo readModelInfo(const std::filesystem::path& path, torch::serialize::InputArchive& archive,
                        const Decoders& decoders);

/// Loads a model file into a new model (network + decoder). Throws ModelError naming the
/// file for a missing, corrupt or foreign file, another feature schema or an unknown decoder.
Model loadModel(const std::filesystem::path& path, ModelInfo& info, const Decoders& decoders);

/// Training checkpoint: network, optimizer and the training loop's state (JSON).
void saveCheckpoint(const std::filesystem::path& path, const Model& model, torch::optim::Optimizer& optimizer,
                    const ModelInfo& info, const std::string& state_json);
/// The training loop's state JSON of a checkpoint, without loading it. Throws ModelError.
std::string readCheckpointState(const std::filesystem::path& path, const Decoders& decoders);
/// Restores a checkpoint into `network` and `optimizer` (its description read with the
/// model's decoder registry); returns the state JSON.
std::string loadCheckpoint(const std::filesystem::path& path, Model& model, torch::optim::Optimizer& optimizer);

}  // namespace vsd::model
