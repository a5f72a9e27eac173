#include "checkpoint.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <unordered_map>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {
/// vsd-model/1: before decoders had names - always the offsets decoder with the
/// constant-velocity residual, in the Ego frame. vsd-model/2 names decoder, options, frame.
constexpr const char* kModelFormat = "vsd-model/2";
constexpr const char* kLegacyModelFormat = "vsd-model/1";
constexpr const char* kInfoKey = "vsd_model_info";
constexpr const char* kStateKey = "vsd_training_state";
constexpr const char* kOptimizerKey = "optimizer";
}  // namespace

std::string infoToJson(const ModelInfo& info) {
  const auto& c = info.config;
  nlohmann::json json = {
      {"format", kModelFormat},
      {"architecture", "VectorNet"},
      {"config",
       {{"hidden", c.hidden},
        {"subgraph_layers", c.subgraphLayers},
        {"global_width", c.globalWidth},
        {"heads", c.heads},
        {"decoder_hidden", c.decoderHidden},
        {"horizon", c.horizon},
        {"step", c.step},
        {"coordinate_scale", c.coordinateScale}}},
      {"decoder", {{"name", c.decoder}, {"options", c.decoderOptions}}},
      {"frame", c.frame},
      {"feature_version", info.featureVersion},
      {"dataset_schema", info.datasetSchema},
      {"mix", info.mix},
      {"seed", info.seed},
      {"epoch", info.epoch},
      {"validation_ade", info.validationAde},
      {"labels", info.labels},
      {"tool_version", info.toolVersion},
  };
  return json.dump();
}

namespace {

/// nlohmann would truncate 64.7 to 64 and wrap 1e300 silently: whole-number fields
/// of a description must be JSON integers.
void requireIntegers(const nlohmann::json& object, std::initializer_list<const char*> keys, const fs::path& file) {
  for (const char* key : keys) {
    const auto& value = object.at(key);
    if (!value.is_number_integer()) {
      throw ModelError(fmt::format("{}: model description: {}: got {}, expected a whole number", file.string(), key,
                                   value.dump()));
    }
  }
}

/// The description's architecture and time base against their documented bounds.
void checkDescription(const ModelInfo& info, const fs::path& file) {
  try {
    info.config.validate();
  } catch (const ConfigError& error) {
    throw ModelError(fmt::format("{}: {}", file.string(), error.what()));
  }
}

}  // namespace

ModelInfo infoFromJson(const std::string& text, const fs::path& file) {
  ModelInfo info;
  try {
    const auto json = nlohmann::json::parse(text);
    const std::string format = json.value("format", "");
    if (format != kModelFormat && format != kLegacyModelFormat) {
      throw ModelError(fmt::format("{}: model format '{}' is not supported (expected {} or {})", file.string(), format,
                                   kModelFormat, kLegacyModelFormat));
    }
    const auto& c = json.at("config");
    requireIntegers(c, {"hidden", "subgraph_layers", "global_width", "heads", "decoder_hidden", "horizon"}, file);
    requireIntegers(json, {"feature_version", "epoch"}, file);
    info.config.hidden = c.at("hidden");
    info.config.subgraphLayers = c.at("subgraph_layers");
    info.config.globalWidth = c.at("global_width");
    info.config.heads = c.at("heads");
    info.config.decoderHidden = c.at("decoder_hidden");
    info.config.horizon = c.at("horizon");
    info.config.step = c.at("step");
    info.config.coordinateScale = c.at("coordinate_scale");
    if (format == kLegacyModelFormat) {
      info.config.decoder = "offsets";
      info.config.decoderOptions = {{"residual", 1.0}};
      info.config.frame = "ego";
    } else {
      info.config.decoder = json.at("decoder").at("name");
      info.config.decoderOptions = json.at("decoder").at("options").get<std::map<std::string, double>>();
      info.config.frame = json.at("frame");
    }
    info.featureVersion = json.at("feature_version");
    info.datasetSchema = json.at("dataset_schema");
    info.mix = json.at("mix");
    info.seed = json.at("seed");
    info.epoch = json.at("epoch");
    info.validationAde = json.at("validation_ade");
    info.labels = json.at("labels").get<std::vector<std::string>>();
    info.toolVersion = json.at("tool_version");
  } catch (const nlohmann::json::exception& error) {
    throw ModelError(fmt::format("{}: damaged model description: {}", file.string(), error.what()));
  }
  checkDescription(info, file);
  return info;
}

namespace {

void writeArchive(torch::serialize::OutputArchive& archive, const fs::path& path) {
  AtomicOutput output(path);
  try {
    archive.save_to(output.tempPath().string());
  } catch (const c10::Error& error) {
    throw IoError(fmt::format("{}: cannot write model: {}", path.string(), error.what_without_backtrace()));
  }
  output.commit();
}

void openArchive(const fs::path& path, torch::serialize::InputArchive& archive) {
  if (!fs::exists(path)) throw ModelError(fmt::format("{}: model file does not exist", path.string()));
  try {
    archive.load_from(path.string());
  } catch (const c10::Error&) {
    throw ModelError(fmt::format("{}: not a vsd-sumo model file (corrupt, truncated or foreign)", path.string()));
  }
}

}  // namespace

void saveModel(const fs::path& path, const Model& model, const ModelInfo& info) {
  torch::serialize::OutputArchive archive;
  model.network->save(archive);
  archive.write(kInfoKey, c10::IValue(infoToJson(info)));
  writeArchive(archive, path);
}

ModelInfo readModelInfo(const fs::path& path, torch::serialize::InputArchive& archive) {
  openArchive(path, archive);
  c10::IValue value;
  if (!archive.try_read(kInfoKey, value) || !value.isString()) {
    throw ModelError(fmt::format("{}: a torch archive, but not a vsd-sumo model (no model description)", path.string()));
  }
  ModelInfo info = infoFromJson(value.toStringRef(), path);
  if (info.featureVersion != vector::kFeatureVersion) {
    throw ModelError(fmt::format("{}: the model was trained on feature schema v{}, this vsd-sumo uses v{}",
                                 path.string(), info.featureVersion, vector::kFeatureVersion));
  }
  try {
    info.config.validate();
  } catch (const ConfigError& error) {
    throw ModelError(fmt::format("{}: this vsd-sumo cannot use the model: {}", path.string(), error.what()));
  }
  if (info.config.horizon < 1 || !(info.config.step > 0.0)) {
    throw ModelError(fmt::format("{}: the model description has no horizon/step", path.string()));
  }
  return info;
}

namespace {

std::string describeShape(const torch::Tensor& tensor) {
  return fmt::format("[{}] {}", fmt::join(tensor.sizes(), ", "), c10::toString(tensor.scalar_type()));
}

/// Paths ("child.weight") of every tensor in an archive, the optimizer's state left out.
void collectTensorPaths(torch::serialize::InputArchive& archive, const std::string& prefix,
                        std::vector<std::string>& paths) {
  for (const auto& key : archive.keys()) {
    if (prefix.empty() && key == kOptimizerKey) continue;
    torch::Tensor tensor;
    torch::serialize::InputArchive child;
    if (archive.try_read(key, tensor)) {
      paths.push_back(prefix + key);
    } else if (archive.try_read(key, child)) {
      collectTensorPaths(child, prefix + key + ".", paths);
    }
  }
}

/// Loads the archive's tensors into `network` and checks each against the shape and
/// type the network's architecture gives it. torch's load takes whatever shape the
/// file holds; a mismatch would only surface as a libtorch error in the first
/// forward pass. Non-finite values are refused as well (they would predict NaN).
void loadParameters(VectorNet& network, torch::serialize::InputArchive& archive, const fs::path& file,
                    const std::string& what) {
  std::vector<std::pair<std::string, std::string>> expected;
  for (const auto& item : network->named_parameters()) expected.emplace_back(item.key(), describeShape(item.value()));
  for (const auto& item : network->named_buffers()) expected.emplace_back(item.key(), describeShape(item.value()));
  // Tensors the architecture has no place for (e.g. a fourth layer when the description
  // says three) would be ignored by load(): the description does not describe the file.
  std::vector<std::string> stored;
  collectTensorPaths(archive, "", stored);
  for (const auto& path : stored) {
    const bool known = std::any_of(expected.begin(), expected.end(), [&](const auto& e) { return e.first == path; });
    if (!known) {
      throw ModelError(fmt::format("{}: parameter '{}' in the file has no place in {}", file.string(), path, what));
    }
  }
  try {
    network->load(archive);
  } catch (const c10::Error& error) {
    throw ModelError(fmt::format("{}: parameters do not match {}: {}", file.string(), what,
                                 error.what_without_backtrace()));
  }
  std::unordered_map<std::string, torch::Tensor> loaded;
  for (const auto& item : network->named_parameters()) loaded.emplace(item.key(), item.value());
  for (const auto& item : network->named_buffers()) loaded.emplace(item.key(), item.value());
  for (const auto& [name, shape] : expected) {
    const torch::Tensor& tensor = loaded.at(name);
    if (describeShape(tensor) != shape) {
      throw ModelError(fmt::format("{}: parameter '{}' is {} in the file, {} needs {}", file.string(), name,
                                   describeShape(tensor), what, shape));
    }
    if (tensor.is_floating_point() && !torch::isfinite(tensor).all().item<bool>()) {
      throw ModelError(fmt::format("{}: parameter '{}' holds non-finite values (NaN or infinity)", file.string(), name));
    }
  }
}

std::string architectureOf(const VectorNetConfig& c) {
  return fmt::format("the described architecture (hidden {}, subgraph_layers {}, global_width {}, heads {}, "
                     "decoder_hidden {}, horizon {}, decoder {})",
                     c.hidden, c.subgraphLayers, c.globalWidth, c.heads, c.decoderHidden, c.horizon, c.decoder);
}

}  // namespace

Model loadModel(const fs::path& path, ModelInfo& info) {
  torch::serialize::InputArchive archive;
  info = readModelInfo(path, archive);
  Model model = Model::create(info.config);
  loadParameters(model.network, archive, path, architectureOf(info.config));
  model.network->eval();
  return model;
}

void saveCheckpoint(const fs::path& path, const Model& model, torch::optim::Optimizer& optimizer,
                    const ModelInfo& info, const std::string& state_json) {
  torch::serialize::OutputArchive archive;
  model.network->save(archive);
  torch::serialize::OutputArchive optimizer_archive;
  optimizer.save(optimizer_archive);
  archive.write(kOptimizerKey, optimizer_archive);
  archive.write(kInfoKey, c10::IValue(infoToJson(info)));
  archive.write(kStateKey, c10::IValue(state_json));
  writeArchive(archive, path);
}

std::string readCheckpointState(const fs::path& path) {
  torch::serialize::InputArchive archive;
  readModelInfo(path, archive);
  c10::IValue state;
  if (!archive.try_read(kStateKey, state) || !state.isString()) {
    throw ModelError(fmt::format("{}: not a training checkpoint (no training state)", path.string()));
  }
  return state.toStringRef();
}

std::string loadCheckpoint(const fs::path& path, Model& model, torch::optim::Optimizer& optimizer) {
  torch::serialize::InputArchive archive;
  readModelInfo(path, archive);
  c10::IValue state;
  if (!archive.try_read(kStateKey, state) || !state.isString()) {
    throw ModelError(fmt::format("{}: not a training checkpoint (no training state)", path.string()));
  }
  loadParameters(model.network, archive, path, "this training's architecture");
  try {
    torch::serialize::InputArchive optimizer_archive;
    archive.read(kOptimizerKey, optimizer_archive);
    optimizer.load(optimizer_archive);
  } catch (const c10::Error& error) {
    throw ModelError(fmt::format("{}: checkpoint does not match this training's architecture: {}", path.string(),
                                 error.what_without_backtrace()));
  }
  return state.toStringRef();
}

}  // namespace vsd::model
