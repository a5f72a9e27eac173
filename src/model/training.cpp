#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include "checkpoint.hpp"
#include "network.hpp"
#include "tensors.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/model/model.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {
void require(bool ok, const char* field, double value, const char* constraint) {
  if (!ok) throw ConfigError::field("model configuration", field, formatValue(value), constraint);
}
}  // namespace

void VectorNetConfig::validate() const {
  validateArchitecture();
  require(horizon >= 1 && horizon <= kMaxWindowSteps, "horizon", horizon,
          fmt::format("1 .. {} steps", kMaxWindowSteps).c_str());
  require(step >= kMinStep && step <= kMaxStep, "step", step, fmt::format("{} .. {} s", kMinStep, kMaxStep).c_str());
}

void VectorNetConfig::validateArchitecture() const {
  require(hidden >= 1 && hidden <= 4096, "hidden", hidden, "1 .. 4096");
  require(subgraphLayers >= 1 && subgraphLayers <= 16, "subgraph_layers", subgraphLayers, "1 .. 16");
  require(globalWidth >= 1 && globalWidth <= 4096, "global_width", globalWidth, "1 .. 4096");
  require(heads >= 1 && globalWidth % heads == 0, "heads", heads, "a divisor of global_width");
  require(decoderHidden >= 1 && decoderHidden <= 8192, "decoder_hidden", decoderHidden, "1 .. 8192");
  require(coordinateScale >= 1e-3 && coordinateScale <= 1e6, "coordinate_scale", coordinateScale, "1e-3 .. 1e6 m");
}

Mix Mix::parse(const std::string& text) {
  Mix mix;
  if (text.empty()) return mix;
  std::size_t start = 0;
  std::set<std::string> seen;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t equals = item.find('=');
    char* end = nullptr;
    const std::string count = equals == std::string::npos ? "" : item.substr(equals + 1);
    const long long value = std::strtoll(count.c_str(), &end, 10);
    if (equals == std::string::npos || equals == 0 || count.empty() || *end != '\0' || value < 0) {
      throw ConfigError::field("command line", "--mix", text, "label=count[,label=count...] with counts >= 0");
    }
    const std::string label = item.substr(0, equals);
    if (!seen.insert(label).second) {
      throw ConfigError::field("command line", "--mix", text, "each label at most once (" + label + " repeats)");
    }
    mix.counts.emplace_back(label, static_cast<std::size_t>(value));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return mix;
}

std::size_t Mix::total() const {
  std::size_t sum = 0;
  for (const auto& [label, count] : counts) sum += count;
  return sum;
}

std::string Mix::str() const {
  std::string text;
  for (const auto& [label, count] : counts) text += fmt::format("{}{}={}", text.empty() ? "" : ",", label, count);
  return text.empty() ? "all" : text;
}

void TrainOptions::validate() const {
  const std::string where = "command line";
  if (data.empty()) throw ConfigError("--data: no dataset given (dataset files or run folders)");
  if (output.empty()) throw ConfigError("--out: no model file given");
  requireFileOutputPath(output, "--out");
  if (threads < 1 || threads > 256) throw ConfigError::field(where, "--threads", std::to_string(threads), "1 .. 256");
  if (steps < 1 || steps > 100'000'000) throw ConfigError::field(where, "--steps", std::to_string(steps), "1 .. 100000000");
  if (patience < 1) throw ConfigError::field(where, "--patience", std::to_string(patience), ">= 1");
  if (batchSize < 1 || batchSize > 65536) throw ConfigError::field(where, "--batch", std::to_string(batchSize), "1 .. 65536");
  if (!(learningRate > 0.0 && learningRate <= 10.0)) {
    throw ConfigError::field(where, "--lr", formatValue(learningRate), "a rate in (0, 10]");
  }
  if (!(weightDecay >= 0.0 && weightDecay <= 10.0)) {
    throw ConfigError::field(where, "--weight-decay", formatValue(weightDecay), "0 .. 10");
  }
  if (!(validationFraction > 0.0 && validationFraction < 1.0)) {
    throw ConfigError::field(where, "--validation-fraction", formatValue(validationFraction), "in (0, 1)");
  }
  config.validateArchitecture();
}

namespace {

struct Selection {
  std::vector<vector::VectorizedScene> train;
  std::vector<vector::VectorizedScene> validation;
  std::map<std::string, std::size_t> trainCounts;
  std::map<std::string, std::size_t> validationCounts;
  vector::DatasetHeader header;
  std::vector<std::string> labels;
};

/// The mix's samples, split per label into training and validation sets.
Selection selectSamples(const TrainOptions& options) {
  vector::DatasetCollection data;
  for (const auto& path : options.data) data.add(path);
  Selection selection;
  selection.header = data.reader(0).header();
  for (std::size_t f = 1; f < data.files(); ++f) {
    const auto& header = data.reader(f).header();
    if (std::abs(header.step - selection.header.step) > 1e-9 || header.horizon != selection.header.horizon) {
      throw ConfigError(fmt::format("{} has step {} s / horizon {} steps, {} has {} s / {}: datasets of one training "
                                    "must share step and horizon",
                                    data.reader(f).path().string(), header.step, header.horizon,
                                    data.reader(0).path().string(), selection.header.step, selection.header.horizon));
    }
  }
  const auto available = data.labelCounts();
  std::vector<std::pair<std::string, std::size_t>> wanted = options.mix.counts;
  if (wanted.empty()) {
    for (const auto& [label, count] : available) wanted.emplace_back(label, count);
  }
  std::vector<std::string> present;
  for (const auto& [label, count] : available) present.push_back(fmt::format("{} ({})", label, count));
  std::size_t total = 0;
  for (const auto& [label, count] : wanted) {
    const auto it = available.find(label);
    if (count > 0 && it == available.end()) {
      throw ConfigError(fmt::format("--mix {}={}: no sample is labelled '{}' in the data (labels: {})", label, count,
                                    label, fmt::join(present, ", ")));
    }
    if (it != available.end() && count > it->second) {
      throw ConfigError(fmt::format("--mix {}={}: the data holds only {} samples labelled '{}'", label, count,
                                    it->second, label));
    }
    total += count;
  }
  if (total < 2) throw ConfigError(fmt::format("--mix {}: the mix is empty (at least 2 samples needed)", options.mix.str()));

  for (const auto& [label, count] : wanted) {
    if (count == 0) continue;
    selection.labels.push_back(label);
    const auto refs = data.withLabel(label);
    // Which samples of a label (and which of them validate) depends only on the seed and the label.
    Rng rng = Rng::derive(options.seed, std::hash<std::string>{}(label), RandomStream::DataSplit);
    const auto order = rng.permutation(refs.size());
    const auto validation = std::max<std::size_t>(
        1, static_cast<std::size_t>(std::lround(options.validationFraction * static_cast<double>(count))));
    for (std::size_t i = 0; i < count; ++i) {
      auto scene = data.scene(refs[order[i]]);
      if (i < validation) {
        selection.validation.push_back(std::move(scene));
        ++selection.validationCounts[label];
      } else {
        selection.train.push_back(std::move(scene));
        ++selection.trainCounts[label];
      }
    }
  }
  if (selection.train.empty()) throw ConfigError("--mix: no training samples left after the validation split");
  return selection;
}

/// Mean displacement of a batch as the loss (it is the ADE the model is judged by).
torch::Tensor adeLoss(const torch::Tensor& predicted, const SceneTensors& batch) {
  const auto [mean, final_distance] = displacement(predicted, batch.targets, batch.targetMask);
  return mean.mean();
}

struct ValidationResult {
  double ade = 0.0;
  double fde = 0.0;
};

ValidationResult validate(VectorNet& network, const SceneTensors& tensors, int batch_size) {
  torch::NoGradGuard no_grad;
  network->eval();
  double ade_sum = 0.0;
  double fde_sum = 0.0;
  for (std::int64_t first = 0; first < tensors.size(); first += batch_size) {
    const auto last = std::min<std::int64_t>(first + batch_size, tensors.size());
    const auto batch = tensors.select(torch::arange(first, last, torch::kInt64));
    const auto predicted = network->positions(batch);
    const auto [mean, final_distance] = displacement(predicted, batch.targets, batch.targetMask);
    ade_sum += mean.sum().item<double>();
    fde_sum += final_distance.sum().item<double>();
  }
  network->train();
  const auto n = static_cast<double>(std::max<std::int64_t>(tensors.size(), 1));
  return {ade_sum / n, fde_sum / n};
}

/// Linear warm-up over the first steps, then cosine decay to 2 % of the peak at the
/// last step. Defined per optimizer step, so a larger dataset trains fewer epochs of
/// more steps each, in the same time.
double learningRateAt(const TrainOptions& options, std::int64_t step) {
  const std::int64_t warmup = std::min<std::int64_t>(200, options.steps / 10 + 1);
  if (step < warmup) return options.learningRate * static_cast<double>(step + 1) / static_cast<double>(warmup);
  const double progress = static_cast<double>(step - warmup) / static_cast<double>(std::max<std::int64_t>(1, options.steps - warmup));
  return options.learningRate * (0.02 + 0.98 * 0.5 * (1.0 + std::cos(kPi * std::min(progress, 1.0))));
}

nlohmann::json recordToJson(const EpochRecord& r) {
  return {{"epoch", r.epoch}, {"planned_epochs", r.plannedEpochs}, {"train_loss", r.trainLoss}, {"validation_ade", r.validationAde},
          {"validation_fde", r.validationFde}, {"learning_rate", r.learningRate},
          {"samples_per_second", r.samplesPerSecond}, {"seconds", r.seconds}, {"best", r.best}};
}

EpochRecord recordFromJson(const nlohmann::json& j) {
  EpochRecord r;
  r.epoch = j.at("epoch");
  r.plannedEpochs = j.value("planned_epochs", 0);
  r.trainLoss = j.at("train_loss");
  r.validationAde = j.at("validation_ade");
  r.validationFde = j.at("validation_fde");
  r.learningRate = j.at("learning_rate");
  r.samplesPerSecond = j.at("samples_per_second");
  r.seconds = j.at("seconds");
  r.best = j.at("best");
  return r;
}

/// What a resumed training must share with the interrupted one to repeat it
/// exactly: the data (each file's SHA-256), the mix, the seed, the schedule and
/// the architecture. (Threads are left out: they change results only in the last bits.)
nlohmann::json resumeKey(const TrainOptions& options, const VectorNetConfig& config) {
  ModelInfo architecture;
  architecture.config = config;
  nlohmann::json data = nlohmann::json::array();
  for (const auto& path : options.data) {
    const fs::path file = vector::resolveDatasetPath(path);
    data.push_back({{"file", file.string()}, {"sha256", sha256OfFile(file)}});
  }
  return {{"data", data},
          {"mix", options.mix.str()},
          {"seed", options.seed},
          {"steps", options.steps},
          {"patience", options.patience},
          {"batch", options.batchSize},
          {"lr", options.learningRate},
          {"weight_decay", options.weightDecay},
          {"validation_fraction", options.validationFraction},
          {"architecture", nlohmann::json::parse(infoToJson(architecture))["config"]}};
}

/// Throws ConfigError naming the first setting in which the checkpoint differs.
void checkResumeKey(const nlohmann::json& state, const nlohmann::json& current, const fs::path& checkpoint) {
  if (!state.contains("resume_key")) {
    throw ConfigError(fmt::format("--resume: {} does not record what it was trained on (written by an older "
                                  "vsd-sumo); start without --resume",
                                  checkpoint.string()));
  }
  const auto& saved = state.at("resume_key");
  std::vector<std::string> saved_sha;
  std::vector<std::string> current_sha;
  for (const auto& entry : saved.at("data")) saved_sha.push_back(entry.at("sha256"));
  for (const auto& entry : current.at("data")) current_sha.push_back(entry.at("sha256"));
  if (saved_sha != current_sha) {
    std::vector<std::string> files;
    for (const auto& entry : saved.at("data")) files.push_back(entry.at("file"));
    throw ConfigError(fmt::format("--resume: {} was trained on other data ({}, SHA-256 differs from --data now): "
                                  "start without --resume, or give the data it was trained on",
                                  checkpoint.string(), fmt::join(files, ", ")));
  }
  for (const auto& [key, value] : current.items()) {
    if (key == "data" || saved.value(key, nlohmann::json()) == value) continue;
    throw ConfigError(fmt::format("--resume: {} was trained with {} {}, this training has {}: give the same settings "
                                  "or start without --resume",
                                  checkpoint.string(), key, saved.value(key, nlohmann::json()).dump(), value.dump()));
  }
}

}  // namespace

TrainSummary train(const TrainOptions& options, const std::function<void(const EpochRecord&)>& on_epoch) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  configureThreads(options.threads);
  torch::manual_seed(options.seed);

  Selection selection = selectSamples(options);
  VectorNetConfig config = options.config;
  config.horizon = selection.header.horizon;
  config.step = selection.header.step;
  config.validate();
  const SceneTensors train_tensors = buildTensors(selection.train, config);
  const SceneTensors validation_tensors = buildTensors(selection.validation, config);
  selection.train.clear();
  selection.validation.clear();

  VectorNet network(config);
  torch::optim::AdamW optimizer(network->parameters(),
                                torch::optim::AdamWOptions(options.learningRate).weight_decay(options.weightDecay));

  ModelInfo info;
  info.config = config;
  info.datasetSchema = vector::kDatasetSchema;
  info.mix = options.mix.str();
  info.seed = options.seed;
  info.labels = selection.labels;
  info.toolVersion = toolVersion();

  TrainSummary summary;
  summary.output = options.output;
  summary.trainSamples = selection.trainCounts;
  summary.validationSamples = selection.validationCounts;
  if (!options.output.parent_path().empty()) ensureDirectory(options.output.parent_path());
  const fs::path last_checkpoint = options.output.string() + ".last";
  int first_epoch = 0;
  int since_best = 0;
  summary.bestValidationAde = std::numeric_limits<double>::infinity();
  const nlohmann::json resume_key = resumeKey(options, config);
  if (options.resume) {
    if (!fs::exists(last_checkpoint)) {
      throw ConfigError(fmt::format("--resume: no checkpoint {} to resume from", last_checkpoint.string()));
    }
    try {
      checkResumeKey(nlohmann::json::parse(readCheckpointState(last_checkpoint)), resume_key, last_checkpoint);
      const auto state = nlohmann::json::parse(loadCheckpoint(last_checkpoint, network, optimizer));
      first_epoch = state.at("next_epoch");
      since_best = state.at("since_best");
      summary.bestEpoch = state.at("best_epoch");
      summary.bestValidationAde = state.at("best_validation_ade");
      for (const auto& record : state.at("history")) summary.epochs.push_back(recordFromJson(record));
      if (summary.bestEpoch > 0 && !fs::exists(options.output)) {
        throw ConfigError(fmt::format("--resume: {} holds the state after epoch {}, but the best model of that "
                                      "training ({}) is gone; start without --resume",
                                      last_checkpoint.string(), first_epoch, options.output.string()));
      }
    } catch (const nlohmann::json::exception& error) {
      throw ModelError(fmt::format("{}: damaged training state: {}", last_checkpoint.string(), error.what()));
    }
    spdlog::info("resuming {} at epoch {} (best validation ADE {:.3f} m at epoch {})", options.output.string(),
                 first_epoch + 1, summary.bestValidationAde, summary.bestEpoch);
  }

  const std::int64_t n = train_tensors.size();
  const std::int64_t steps_per_epoch = (n + options.batchSize - 1) / options.batchSize;
  const int epochs = static_cast<int>((options.steps + steps_per_epoch - 1) / steps_per_epoch);
  summary.plannedEpochs = epochs;
  double trained_samples = 0.0;
  double training_seconds = 0.0;
  summary.stopReason = "end of the schedule";
  int next_epoch = first_epoch;
  auto last_saved = std::chrono::steady_clock::now();
  const auto save_last = [&] {
    nlohmann::json state = {{"resume_key", resume_key},
                            {"next_epoch", next_epoch},
                            {"since_best", since_best},
                            {"best_epoch", summary.bestEpoch},
                            {"best_validation_ade", summary.bestValidationAde},
                            {"history", nlohmann::json::array()}};
    for (const auto& past : summary.epochs) state["history"].push_back(recordToJson(past));
    saveCheckpoint(last_checkpoint, network, optimizer, info, state.dump());
  };
  try {
  for (int epoch = first_epoch; epoch < epochs; ++epoch) {
    const auto epoch_start = std::chrono::steady_clock::now();
    double learning_rate = 0.0;
    // The order of an epoch depends only on (seed, epoch): a resumed training repeats it.
    Rng rng = Rng::derive(options.seed, static_cast<std::uint64_t>(epoch), RandomStream::Training);
    const auto order = rng.permutation(static_cast<std::size_t>(n));
    const auto order_tensor = torch::tensor(std::vector<std::int64_t>(order.begin(), order.end()), torch::kInt64);
    double loss_sum = 0.0;
    network->train();
    for (std::int64_t first = 0; first < n; first += options.batchSize) {
      throwIfInterrupted();
      const auto last = std::min<std::int64_t>(first + options.batchSize, n);
      const auto batch = train_tensors.select(order_tensor.slice(0, first, last));
      learning_rate = learningRateAt(options, epoch * steps_per_epoch + first / options.batchSize);
      for (auto& group : optimizer.param_groups()) {
        static_cast<torch::optim::AdamWOptions&>(group.options()).lr(learning_rate);
      }
      optimizer.zero_grad();
      const auto predicted = network->positions(batch);
      const auto loss = adeLoss(predicted, batch);
      loss.backward();
      torch::nn::utils::clip_grad_norm_(network->parameters(), 5.0);
      optimizer.step();
      loss_sum += loss.item<double>() * static_cast<double>(last - first);
    }
    const double train_seconds = secondsSince(epoch_start);
    trained_samples += static_cast<double>(n);
    training_seconds += train_seconds;

    const auto result = validate(network, validation_tensors, 1024);
    EpochRecord record;
    record.epoch = epoch + 1;
    record.plannedEpochs = epochs;
    record.trainLoss = loss_sum / static_cast<double>(n);
    record.validationAde = result.ade;
    record.validationFde = result.fde;
    record.learningRate = learning_rate;
    record.samplesPerSecond = static_cast<double>(n) / train_seconds;
    if (!std::isfinite(record.trainLoss)) {
      throw ModelError(fmt::format("training diverged at epoch {} (loss {}); try a smaller --lr", record.epoch,
                                   record.trainLoss));
    }
    if (result.ade < summary.bestValidationAde) {
      summary.bestValidationAde = result.ade;
      summary.bestEpoch = record.epoch;
      since_best = 0;
      record.best = true;
      info.epoch = record.epoch;
      info.validationAde = result.ade;
      saveModel(options.output, network, info);  // atomic: an interruption keeps the previous best
    } else {
      ++since_best;
    }
    record.seconds = secondsSince(epoch_start);
    summary.epochs.push_back(record);
    next_epoch = epoch + 1;
    // The resume checkpoint costs a write: at most every 10 s (and when stopping).
    if (secondsSince(last_saved) >= 10.0 || next_epoch == epochs) {
      save_last();
      last_saved = std::chrono::steady_clock::now();
    }
    if (on_epoch) on_epoch(record);
    if (since_best >= options.patience) {
      summary.stopReason = fmt::format("early stopping (no better validation ADE for {} epochs)", options.patience);
      save_last();
      break;
    }
  }
  } catch (const InterruptedError&) {
    save_last();  // complete epochs so far; --resume continues after them
    throw;
  }
  if (summary.bestEpoch == 0) {
    // Nothing was written: exit 0 would promise a model file that does not exist.
    throw ModelError(fmt::format("no epoch reached a finite validation ADE (last: {}); no model written to {}",
                                 summary.epochs.empty() ? std::string("none") : formatValue(summary.epochs.back().validationAde),
                                 options.output.string()));
  }
  summary.seconds = secondsSince(start);
  summary.samplesPerSecond = training_seconds > 0.0 ? trained_samples / training_seconds : 0.0;
  return summary;
}

std::string TrainSummary::report() const {
  std::string text = fmt::format("trained VectorNet: best validation ADE {:.3f} m at epoch {} of {} ({}), {:.1f} s, "
                                 "{:.0f} training samples/s\n",
                                 bestValidationAde, bestEpoch, plannedEpochs, stopReason, seconds, samplesPerSecond);
  text += "  samples (train / validation):";
  for (const auto& [label, count] : trainSamples) {
    const auto it = validationSamples.find(label);
    text += fmt::format(" {} {}/{}", label, count, it == validationSamples.end() ? 0 : it->second);
  }
  text += fmt::format("\n  model: {}\n", output.string());
  return text;
}

}  // namespace vsd::model
