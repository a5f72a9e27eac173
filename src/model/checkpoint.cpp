#include "checkpoint.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <unordered_map>

#include "vsd/core/error.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {
/// vsd-model/1: before decoders had names - always the offsets decoder with the
/// constant-velocity residual, in the Ego frame. vsd-model/2 names decoder, options, frame.
/// vsd-model/3: the kinematic decoder's heading_control defaults to 1; in /2 files, where it
/// did not exist, an absent heading_control means curvature control (0).
/// vsd-model/4: records the lane frame's smoothing (lane_smoothing); older files used 4 m.
constexpr const char* kModelFormat = "vsd-model/4";
constexpr const char* kModelFormatVersion3 = "vsd-model/3";
constexpr const char* kModelFormatVersion2 = "vsd-model/2";

/// Options a vsd-model/2 file lacks because its decoder gained them later, as that file's
/// decoder behaved (each decoder's registry entry says which and how).
/// (A decoder the registry lacks is refused afterwards, by the description's validation.)
void addOptionsOfModelFormat2(VectorNetConfig& config) {
  const auto& registry = config.decoderRegistry();
  if (!registry.contains(config.decoder)) return;
  const auto& decoder = registry.find(config.decoder, "model configuration");
  for (const auto& [name, value] : decoder.optionsBeforeModelFormat3) config.decoderOptions.emplace(name, value);
}
constexpr double kLaneSmoothingBeforeVersion4 = 4.0;  ///< m
constexpr const char* kLegacyModelFormat = "vsd-model/1";
constexpr const char* kInfoKey = "vsd_model_info";
constexpr const char* kStateKey = "vsd_training_state";
constexpr const char* kOptimizerKey = "optimizer";
}  // namespace

namespace {

nlohmann::json calibrationToJson(const ModelInfo& info) {
  nlohmann::json json = nlohmann::json::object();
  if (!info.positionRegions.byLabel.empty()) {
    auto& regions = json["position_regions"];
    regions["levels"] = kCoverageLevels;
    regions["scenes"] = info.positionRegions.scenes;
    for (const auto& [label, radii] : info.positionRegions.byLabel) regions["by_label"][label] = radii;
  }
  for (const auto& [label, metrics] : info.metricIntervals.byLabel) {
    for (const auto& [metric, widening] : metrics) {
      json["metric_intervals"][label][metric] = {{"levels", widening.levels},
                                                 {"raw_levels", widening.rawLevels},
                                                 {"widening", widening.widening},
                                                 {"floor", widening.floor},
                                                 {"scenes", widening.scenes}};
    }
  }
  return json;
}

bool allFinite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

/// Reads what calibrationToJson wrote; throws ModelError naming the file for anything else.
void calibrationFromJson(const nlohmann::json& json, ModelInfo& info, const fs::path& file) {
  const auto damaged = [&](const std::string& what) {
    return ModelError(fmt::format("{}: model description: calibration: {}", file.string(), what));
  };
  if (const auto regions = json.find("position_regions"); regions != json.end()) {
    if (regions->at("levels").get<std::vector<double>>() !=
        std::vector<double>(kCoverageLevels.begin(), kCoverageLevels.end())) {
      throw damaged("position_regions.levels: expected the levels 0.5, 0.9");
    }
    info.positionRegions.scenes = regions->at("scenes");
    for (const auto& [label, radii] : regions->at("by_label").items()) {
      auto steps = radii.get<std::vector<std::array<double, kCoverageLevels.size()>>>();
      if (steps.size() != static_cast<std::size_t>(info.config.horizon)) {
        throw damaged(fmt::format("position_regions '{}': {} steps, expected the horizon {}", label, steps.size(),
                                  info.config.horizon));
      }
      for (const auto& radius : steps) {
        if (!(radius[0] > 0.0 && radius[0] <= radius[1] && std::isfinite(radius[1]))) {
          throw damaged(fmt::format("position_regions '{}': radii {}, {}: expected 0 < r50 <= r90 < inf", label,
                                    radius[0], radius[1]));
        }
      }
      info.positionRegions.byLabel[label] = std::move(steps);
    }
  }
  if (const auto intervals = json.find("metric_intervals"); intervals != json.end()) {
    for (const auto& [label, metrics] : intervals->items()) {
      for (const auto& [metric, entry] : metrics.items()) {
        IntervalWidening widening;
        widening.levels = entry.at("levels").get<std::vector<double>>();
        widening.rawLevels = entry.at("raw_levels").get<std::vector<double>>();
        widening.widening = entry.at("widening").get<std::vector<double>>();
        widening.floor = entry.at("floor");
        widening.scenes = entry.at("scenes");
        const bool ascending = std::is_sorted(widening.levels.begin(), widening.levels.end()) &&
                               !widening.levels.empty() && widening.levels.front() > 0.0 && widening.levels.back() < 1.0;
        const auto& raw = widening.rawLevels;
        const auto& w = widening.widening;
        const bool raw_ok = raw.size() == widening.levels.size() && allFinite(raw) && std::is_sorted(raw.begin(), raw.end()) &&
                            !raw.empty() && raw.front() >= 0.0 && raw.back() <= 1.0;
        const bool widening_ok = w.size() == widening.levels.size() && allFinite(w) && std::is_sorted(w.begin(), w.end()) &&
                                 !w.empty() && w.front() >= 0.0;
        if (!ascending || !raw_ok || !widening_ok || !(widening.floor > 0.0)) {
          throw damaged(fmt::format("metric_intervals '{}' {}: expected ascending levels in (0, 1), as many "
                                    "non-decreasing raw levels in [0, 1] and widenings >= 0, and a positive floor",
                                    label, metric));
        }
        info.metricIntervals.byLabel[label][metric] = std::move(widening);
      }
    }
  }
}

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
        {"coordinate_scale", c.coordinateScale},
        {"lane_smoothing", c.laneSmoothing}}},
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
  if (!info.roadUsers.empty()) json["road_users"] = info.roadUsers;
  auto calibration = calibrationToJson(info);
  if (!calibration.empty()) json["calibration"] = std::move(calibration);
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

ModelInfo infoFromJson(const std::string& text, const fs::path& file, const Decoders& decoders) {
  ModelInfo info;
  info.config.decoders = decoders;
  try {
    const auto json = nlohmann::json::parse(text);
    const std::string format = json.value("format", "");
    if (format != kModelFormat && format != kModelFormatVersion3 && format != kModelFormatVersion2 &&
        format != kLegacyModelFormat) {
      throw ModelError(fmt::format("{}: model format '{}' is not supported (expected {}, {}, {} or {})", file.string(),
                                   format, kModelFormat, kModelFormatVersion3, kModelFormatVersion2,
                                   kLegacyModelFormat));
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
    info.config.laneSmoothing = format == kModelFormat ? c.at("lane_smoothing").get<double>() : kLaneSmoothingBeforeVersion4;
    if (format == kLegacyModelFormat) {
      info.config.decoder = "offsets";
      info.config.decoderOptions = {{"residual", 1.0}};
      info.config.frame = "ego";
    } else {
      info.config.decoder = json.at("decoder").at("name");
      info.config.decoderOptions = json.at("decoder").at("options").get<std::map<std::string, double>>();
      info.config.frame = json.at("frame");
      if (format == kModelFormatVersion2) addOptionsOfModelFormat2(info.config);
    }
    info.featureVersion = json.at("feature_version");
    info.datasetSchema = json.at("dataset_schema");
    info.mix = json.at("mix");
    info.seed = json.at("seed");
    info.epoch = json.at("epoch");
    info.validationAde = json.at("validation_ade");
    info.labels = json.at("labels").get<std::vector<std::string>>();
    info.toolVersion = json.at("tool_version");
    info.roadUsers = json.value("road_users", std::vector<std::string>{});
    for (const auto& kind : info.roadUsers) {
      if (!findRoadUserType(kind)) {
        throw ModelError(fmt::format("{}: damaged model description: road_users: '{}' is not a kind of road user ({})",
                                     file.string(), kind, roadUserTypeList()));
      }
    }
    if (const auto calibration = json.find("calibration"); calibration != json.end()) {
      calibrationFromJson(*calibration, info, file);
    }
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
    // Through a stream, not a file name: torch names the zip's entries after the file it
    // is given (".m.pt.<pid>.part/data.pkl"), which would make two identical trainings
    // differ in bytes; a stream's entries are "archive/...", whatever the process.
    std::ofstream stream(output.tempPath(), std::ios::binary | std::ios::trunc);
    if (!stream) throw IoError(fmt::format("{}: cannot open for writing", path.string()));
    archive.save_to(stream);
    stream.close();
    if (!stream) throw IoError(fmt::format("{}: write failed (disk full?)", path.string()));
  } catch (const c10::Error& error) {
    throw IoError(fmt::format("{}: cannot write model: {}", path.string(), error.what_without_backtrace()));
  }
  output.commit();
}

void openArchive(const fs::path& path, torch::serialize::InputArchive& archive) {
  if (!fs::exists(path)) throw ModelError(fmt::format("{}: model file does not exist", path.string()));
  if (!fs::is_regular_file(path)) {
    throw ModelError(fmt::format("{}: not a regular file (a device, FIFO or folder), expected a model file", path.string()));
  }
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

ModelInfo readModelInfo(const fs::path& path, torch::serialize::InputArchive& archive, const Decoders& decoders) {
  openArchive(path, archive);
  c10::IValue value;
  if (!archive.try_read(kInfoKey, value) || !value.isString()) {
    throw ModelError(fmt::format("{}: a torch archive, but not a vsd-sumo model (no model description)", path.string()));
  }
  ModelInfo info = infoFromJson(value.toStringRef(), path, decoders);
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

Model loadModel(const fs::path& path, ModelInfo& info, const Decoders& decoders) {
  torch::serialize::InputArchive archive;
  info = readModelInfo(path, archive, decoders);
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

std::string readCheckpointState(const fs::path& path, const Decoders& decoders) {
  torch::serialize::InputArchive archive;
  readModelInfo(path, archive, decoders);
  c10::IValue state;
  if (!archive.try_read(kStateKey, state) || !state.isString()) {
    throw ModelError(fmt::format("{}: not a training checkpoint (no training state)", path.string()));
  }
  return state.toStringRef();
}

std::string loadCheckpoint(const fs::path& path, Model& model, torch::optim::Optimizer& optimizer) {
  torch::serialize::InputArchive archive;
  readModelInfo(path, archive, model.config.decoders);
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
