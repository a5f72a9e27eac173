#include "checkpoint.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

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

Model loadModel(const fs::path& path, ModelInfo& info) {
  torch::serialize::InputArchive archive;
  info = readModelInfo(path, archive);
  Model model = Model::create(info.config);
  try {
    model.network->load(archive);
  } catch (const c10::Error& error) {
    throw ModelError(fmt::format("{}: parameters do not match the described architecture: {}", path.string(),
                                 error.what_without_backtrace()));
  }
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

std::string loadCheckpoint(const fs::path& path, Model& model, torch::optim::Optimizer& optimizer) {
  torch::serialize::InputArchive archive;
  readModelInfo(path, archive);
  c10::IValue state;
  if (!archive.try_read(kStateKey, state) || !state.isString()) {
    throw ModelError(fmt::format("{}: not a training checkpoint (no training state)", path.string()));
  }
  try {
    model.network->load(archive);
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
