#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <limits>
#include <memory>
#include <mutex>
#include <set>

#include "calibration.hpp"
#include "checkpoint.hpp"
#include "conformal.hpp"
#include "distributed.hpp"
#include "network.hpp"
#include "tensors.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/core/random.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/model/model.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {

/// Largest L2 norm of the whole gradient per optimizer step (one- and many-rank steps
/// alike): keeps an early step on a badly scaled scene from throwing the weights off.
constexpr double kGradientClipNorm = 5.0;

struct Selection {
  std::vector<vector::VectorizedScene> train;
  std::vector<vector::VectorizedScene> validation;
  /// Per validation scene, the names of its stored (simulated) metrics: its file's header's.
  std::vector<std::shared_ptr<const std::vector<std::string>>> validationMetricNames;
  std::map<std::string, std::size_t> trainCounts;
  std::map<std::string, std::size_t> validationCounts;
  vector::DatasetHeader header;
  std::vector<std::string> labels;
  std::set<std::string> roadUsers;  ///< kinds of the road users in the selected scenes
};

/// Records the kinds of road users in `scene` (what `deviations` refuses others than).
void addRoadUsers(const vector::VectorizedScene& scene, std::set<std::string>& kinds) {
  for (const auto& polyline : scene.polylines) {
    if (polyline.type != vector::ObjectType::LaneBoundary) kinds.insert(roadUserKind(polyline.roadUser).name);
  }
}

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

  std::vector<std::shared_ptr<const std::vector<std::string>>> metric_names;
  for (std::size_t f = 0; f < data.files(); ++f) {
    metric_names.push_back(std::make_shared<const std::vector<std::string>>(data.reader(f).header().metricNames));
  }
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
      addRoadUsers(scene, selection.roadUsers);
      if (i < validation) {
        selection.validation.push_back(std::move(scene));
        selection.validationMetricNames.push_back(metric_names[refs[order[i]].file]);
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

struct ValidationResult {
  double ade = 0.0;
  double fde = 0.0;
  double nll = std::numeric_limits<double>::quiet_NaN();  ///< nats per valid position (probabilistic decoders)
};

ValidationResult validate(Model& model, const SceneTensors& tensors, int batch_size) {
  torch::NoGradGuard no_grad;
  model.network->eval();
  double ade_sum = 0.0;
  double fde_sum = 0.0;
  double nll_sum = 0.0;
  double nll_count = 0.0;
  for (std::int64_t first = 0; first < tensors.size(); first += batch_size) {
    const auto last = std::min<std::int64_t>(first + batch_size, tensors.size());
    const auto batch = tensors.select(torch::arange(first, last, torch::kInt64));
    const auto decoded = model.decode(batch);
    const auto [mean, final_distance] = displacement(decoded.positions, batch.targets, batch.targetMask);
    ade_sum += mean.sum().item<double>();
    fde_sum += final_distance.sum().item<double>();
    if (decoded.covariance.defined()) {
      const auto weights = batch.targetMask.to(torch::kFloat32);
      nll_sum += (gaussianNll(decoded.positions, decoded.covariance, batch.targets) * weights).sum().item<double>();
      nll_count += weights.sum().item<double>();
    }
  }
  model.network->train();
  const auto n = static_cast<double>(std::max<std::int64_t>(tensors.size(), 1));
  ValidationResult result{ade_sum / n, fde_sum / n};
  if (nll_count > 0.0) result.nll = nll_sum / nll_count;
  return result;
}

/// The configuration a training writes: step and horizon of the data, every decoder
/// option explicit (a later change of a default does not change what a model file means).
VectorNetConfig trainedConfig(const TrainOptions& options, const vector::DatasetHeader& header) {
  VectorNetConfig config = options.config;
  config.horizon = header.horizon;
  config.step = header.step;
  for (const auto& option : config.decoderRegistry().find(config.decoder, "--decoder").options) {
    config.decoderOptions[option.name] = config.decoderOption(option.name);
  }
  config.validate();
  return config;
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

/// The error a diverged training stops with: where it happened and what was kept.
ModelError divergence(const TrainOptions& options, const TrainSummary& summary, std::int64_t step, int epoch,
                      std::int64_t batch, std::int64_t batches, bool has_variance) {
  const std::string kept =
      summary.bestEpoch > 0
          ? fmt::format("{} keeps the last good model (epoch {}, validation ADE {:.3f} m)", options.output.string(),
                        summary.bestEpoch, summary.bestValidationAde)
          : fmt::format("no model was written to {}", options.output.string());
  return ModelError(fmt::format("training diverged at optimizer step {} (epoch {}, batch {} of {}): the {} is not finite; "
                                "{}; try a smaller --lr",
                                step, epoch, batch, batches, has_variance ? "predicted variance or the loss" : "loss",
                                kept));
}

nlohmann::json recordToJson(const EpochRecord& r) {
  return {{"epoch", r.epoch}, {"planned_epochs", r.plannedEpochs}, {"train_loss", r.trainLoss}, {"validation_ade", r.validationAde},
          {"validation_fde", r.validationFde}, {"validation_nll", std::isnan(r.validationNll) ? nlohmann::json() : nlohmann::json(r.validationNll)},
          {"learning_rate", r.learningRate},
          {"samples_per_second", r.samplesPerSecond}, {"seconds", r.seconds}, {"best", r.best}};
}

EpochRecord recordFromJson(const nlohmann::json& j) {
  EpochRecord r;
  r.epoch = j.at("epoch");
  r.plannedEpochs = j.value("planned_epochs", 0);
  r.trainLoss = j.at("train_loss");
  r.validationAde = j.at("validation_ade");
  r.validationFde = j.at("validation_fde");
  const auto nll = j.find("validation_nll");
  r.validationNll = nll == j.end() || nll->is_null() ? std::numeric_limits<double>::quiet_NaN() : nll->get<double>();
  r.learningRate = j.at("learning_rate");
  r.samplesPerSecond = j.at("samples_per_second");
  r.seconds = j.at("seconds");
  r.best = j.at("best");
  return r;
}

/// The model file's "config" part of `config` as JSON: widths, horizon, step, coordinate scale
/// and lane smoothing (not the decoder or the frame).
nlohmann::json configJson(const VectorNetConfig& config) {
  ModelInfo architecture;
  architecture.config = config;
  return nlohmann::json::parse(infoToJson(architecture))["config"];
}

/// What a resumed training must share with the interrupted one to repeat it
/// exactly: the data (each file's SHA-256), the mix, the seed, the schedule and
/// the architecture. (Threads are left out: they change results only in the last bits; the
/// learning rate too: a user may change it on resume, and doing so cannot mix up data.)
nlohmann::json resumeKey(const TrainOptions& options, const VectorNetConfig& config) {
  nlohmann::json data = nlohmann::json::array();
  for (const auto& path : options.data) {
    for (const auto& file : vector::datasetFiles(path)) {  // a sharded sweep: every shard
      data.push_back({{"file", file.string()}, {"sha256", sha256OfFile(file)}});
    }
  }
  return {{"data", data},
          {"mix", options.mix.str()},
          {"seed", options.seed},
          {"steps", options.steps},
          {"patience", options.patience},
          {"batch", options.batchSize},
          {"weight_decay", options.weightDecay},
          {"validation_fraction", options.validationFraction},
          {"architecture", configJson(config)}};
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

namespace {

/// One training run: the data as tensors, the model, the optimizer and the bookkeeping
/// that lets an interrupted run resume exactly.
/// A new model initialised from `seed`. Initialisation draws from libtorch's process-wide
/// generator: the lock makes seeding and drawing one step, so trainings running side by side
/// in one process (the experiment's `training.parallel`) each get the parameters of their
/// own seed, as a training alone does.
Model createSeeded(const VectorNetConfig& config, std::uint64_t seed) {
  static std::mutex initialisation;
  const std::lock_guard<std::mutex> lock(initialisation);
  torch::manual_seed(seed);
  return Model::create(config);
}

/// The weights a training starts from: fresh ones from the seed, or (fine-tuning) those of
/// options.initialModel, whose configuration must be this training's.
Model startingModel(const TrainOptions& options, const VectorNetConfig& config) {
  if (options.initialModel.empty()) return createSeeded(config, options.seed);
  ModelInfo info;
  Model model = loadModel(options.initialModel, info, config.decoders);
  auto wanted = configJson(config);
  auto found = configJson(info.config);
  for (auto* json : {&wanted, &found}) {  // configJson holds the architecture; add what the weights mean
    const auto& c = json == &wanted ? config : info.config;
    (*json)["decoder"] = c.decoder;
    (*json)["decoder_options"] = c.decoderOptions;
    (*json)["frame"] = c.frame;
  }
  for (const auto& [key, value] : wanted.items()) {
    if (found.value(key, nlohmann::json()) == value) continue;
    throw ConfigError(fmt::format("--init-from: {} has {} {}, this training {}: fine-tuning needs the same "
                                  "architecture, decoder, frame, step and horizon",
                                  options.initialModel.string(), key, found.value(key, nlohmann::json()).dump(),
                                  value.dump()));
  }
  model.network->train();
  return model;
}

class Trainer {
 public:
  /// `parallel`: the other ranks of a distributed training (nullptr: this process alone).
  Trainer(const TrainOptions& options, DataParallel* parallel)
      : options_(options),
        parallel_(parallel),
        selection_(selectSamples(options)),
        config_(trainedConfig(options, selection_.header)),
        train_(buildTensors(selection_.train, config_)),
        validation_(buildTensors(selection_.validation, config_)),
        model_(startingModel(options, config_)),
        optimizer_(model_.network->parameters(),
                   torch::optim::AdamWOptions(options.learningRate).weight_decay(options.weightDecay)),
        lastCheckpoint_(options.output.string() + ".last"),
        resumeKey_(resumeKey(options, config_)) {
    selection_.train.clear();
    if (!calibrates()) selection_.validation.clear();  // calibrate() predicts the scenes themselves
    info_.config = config_;
    info_.datasetSchema = vector::kDatasetSchema;
    info_.mix = options.mix.str();
    info_.seed = options.seed;
    info_.labels = selection_.labels;
    info_.roadUsers.assign(selection_.roadUsers.begin(), selection_.roadUsers.end());
    info_.toolVersion = toolVersion();
    summary_.output = options.output;
    summary_.decoder = config_.decoder;
    summary_.trainSamples = selection_.trainCounts;
    summary_.validationSamples = selection_.validationCounts;
    summary_.bestValidationAde = std::numeric_limits<double>::infinity();
    summary_.stopReason = "end of the schedule";
    stepsPerEpoch_ = (train_.size() + options.batchSize - 1) / options.batchSize;
    summary_.plannedEpochs = static_cast<int>((options.steps + stepsPerEpoch_ - 1) / stepsPerEpoch_);
    if (!options.output.parent_path().empty() && writes()) ensureDirectory(options.output.parent_path());
    if (parallel_ != nullptr) joinRanks();
  }

  TrainSummary run(const std::function<void(const EpochRecord&)>& on_epoch) {
    if (options_.resume) resume();
    auto last_saved = std::chrono::steady_clock::now();
    try {
      for (int epoch = nextEpoch_; epoch < summary_.plannedEpochs; ++epoch) {
        EpochRecord record = trainEpoch(epoch);
        validateEpoch(record);
        summary_.epochs.push_back(record);
        nextEpoch_ = epoch + 1;
        // The resume checkpoint costs a write: at most every 10 s (and when stopping).
        if (secondsSince(last_saved) >= 10.0 || nextEpoch_ == summary_.plannedEpochs) {
          saveLast();
          last_saved = std::chrono::steady_clock::now();
        }
        if (on_epoch && writes()) on_epoch(record);
        if (sinceBest_ >= options_.patience) {
          summary_.stopReason = fmt::format("early stopping (no better validation ADE for {} epochs)", options_.patience);
          saveLast();
          break;
        }
      }
    } catch (const InterruptedError&) {
      saveLast();  // complete epochs so far; --resume continues after them
      throw;
    }
    if (writes() && summary_.bestEpoch == 0) {
      // Nothing was written: exit 0 would promise a model file that does not exist.
      throw ModelError(fmt::format("no epoch reached a finite validation ADE (last: {}); no model written to {}",
                                   summary_.epochs.empty() ? std::string("none")
                                                           : formatValue(summary_.epochs.back().validationAde),
                                   options_.output.string()));
    }
    if (writes() && calibrates()) calibrate();  // rank 0 alone: it holds the validation split and writes the model file
    if (writes()) {
      // A finished training leaves nothing to resume: its state (megabytes) would only be a leftover.
      std::error_code ignored;
      fs::remove(lastCheckpoint_, ignored);
    }
    summary_.seconds = secondsSince(start_);
    summary_.samplesPerSecond = trainingSeconds_ > 0.0 ? trainedSamples_ / trainingSeconds_ : 0.0;
    summary_.allreduceShare = trainingSeconds_ > 0.0 ? summary_.allreduceSeconds / trainingSeconds_ : 0.0;
    return summary_;
  }

 private:
  void resume() {
    if (parallel_ != nullptr) requireCheckpointOnEveryRank();
    if (!fs::exists(lastCheckpoint_)) {
      throw ConfigError(fmt::format("--resume: no checkpoint {} to resume from", lastCheckpoint_.string()));
    }
    try {
      checkResumeKey(nlohmann::json::parse(readCheckpointState(lastCheckpoint_, model_.config.decoders)), resumeKey_, lastCheckpoint_);
      const auto state = nlohmann::json::parse(loadCheckpoint(lastCheckpoint_, model_, optimizer_));
      nextEpoch_ = state.at("next_epoch");
      sinceBest_ = state.at("since_best");
      summary_.bestEpoch = state.at("best_epoch");
      summary_.bestValidationAde = state.at("best_validation_ade");
      for (const auto& record : state.at("history")) summary_.epochs.push_back(recordFromJson(record));
    } catch (const nlohmann::json::exception& error) {
      throw ModelError(fmt::format("{}: damaged training state: {}", lastCheckpoint_.string(), error.what()));
    }
    if (summary_.bestEpoch > 0 && !fs::exists(options_.output)) {
      throw ConfigError(fmt::format("--resume: {} holds the state after epoch {}, but the best model of that "
                                    "training ({}) is gone; start without --resume",
                                    lastCheckpoint_.string(), nextEpoch_, options_.output.string()));
    }
    spdlog::info("resuming {} at epoch {} (best validation ADE {:.3f} m at epoch {})", options_.output.string(),
                 nextEpoch_ + 1, summary_.bestValidationAde, summary_.bestEpoch);
  }

  /// One pass over the training samples in the order of (seed, epoch).
  EpochRecord trainEpoch(int epoch) {
    const auto epoch_start = std::chrono::steady_clock::now();
    const std::int64_t n = train_.size();
    // The order of an epoch depends only on (seed, epoch): a resumed training repeats it.
    Rng rng = Rng::derive(options_.seed, static_cast<std::uint64_t>(epoch), RandomStream::Training);
    const auto order = rng.permutation(static_cast<std::size_t>(n));
    const auto order_tensor = torch::tensor(std::vector<std::int64_t>(order.begin(), order.end()), torch::kInt64);
    EpochRecord record;
    record.epoch = epoch + 1;
    record.plannedEpochs = summary_.plannedEpochs;
    double loss_sum = 0.0;
    model_.network->train();
    const double communication_before = parallel_ != nullptr ? parallel_->communicationSeconds() : 0.0;
    for (std::int64_t first = 0; first < n; first += options_.batchSize) {
      if (parallel_ == nullptr) throwIfInterrupted();  // ranks stop together, at a step's all-reduce
      const auto last = std::min<std::int64_t>(first + options_.batchSize, n);
      const std::int64_t batch_index = first / options_.batchSize;
      record.learningRate = learningRateAt(options_, epoch * stepsPerEpoch_ + batch_index);
      const auto indices = order_tensor.slice(0, first, last);
      loss_sum += (parallel_ != nullptr ? parallelStep(indices, record.learningRate, epoch, batch_index)
                                        : optimizerStep(train_.select(indices), record.learningRate, epoch,
                                                        batch_index)) *
                  static_cast<double>(last - first);
    }
    const double seconds = secondsSince(epoch_start);
    if (parallel_ != nullptr) summary_.allreduceSeconds += parallel_->communicationSeconds() - communication_before;
    trainedSamples_ += static_cast<double>(n);
    trainingSeconds_ += seconds;
    record.trainLoss = loss_sum / static_cast<double>(n);
    record.samplesPerSecond = static_cast<double>(n) / seconds;
    record.seconds = seconds;
    return record;
  }

  /// Returns the batch's loss. A non-finite loss or predicted variance stops the training
  /// before the optimizer takes it in: the model file and <out>.last keep their last good state.
  double optimizerStep(const SceneTensors& batch, double learning_rate, int epoch, std::int64_t batch_index) {
    setLearningRate(learning_rate);
    optimizer_.zero_grad();
    const auto decoded = model_.decode(batch);
    const auto loss = model_.decoder->loss(decoded, batch.targets, batch.targetMask);
    const double value = loss.item<double>();
    if (!std::isfinite(value) || (decoded.covariance.defined() && !decoded.covariance.isfinite().all().item<bool>())) {
      throw divergence(options_, summary_, epoch * stepsPerEpoch_ + batch_index + 1, epoch + 1, batch_index + 1,
                       stepsPerEpoch_, decoded.covariance.defined());
    }
    loss.backward();
    torch::nn::utils::clip_grad_norm_(model_.network->parameters(), kGradientClipNorm);
    optimizer_.step();
    return value;
  }

  /// The distributed form of optimizerStep: this rank's slice of the global batch `indices`;
  /// every rank takes the same step with the whole batch's gradient.
  double parallelStep(const torch::Tensor& indices, double learning_rate, int epoch, std::int64_t batch_index) {
    setLearningRate(learning_rate);
    optimizer_.zero_grad();
    const std::int64_t n = indices.size(0);
    const auto [first, last] = parallel_->slice(n);
    const auto step = globalStep(*parallel_, model_, train_.select(indices.slice(0, first, last)),
                                 static_cast<double>(last - first) / static_cast<double>(n));
    if (step.interrupted) throw InterruptedError(interruptSignal() != 0 ? interruptSignal() : SIGTERM);
    if (!std::isfinite(step.loss) || !step.varianceFinite) {
      throw divergence(options_, summary_, epoch * stepsPerEpoch_ + batch_index + 1, epoch + 1, batch_index + 1,
                       stepsPerEpoch_, !step.varianceFinite);
    }
    torch::nn::utils::clip_grad_norm_(model_.network->parameters(), kGradientClipNorm);
    optimizer_.step();
    return step.loss;
  }

  void setLearningRate(double learning_rate) {
    for (auto& group : optimizer_.param_groups()) {
      static_cast<torch::optim::AdamWOptions&>(group.options()).lr(learning_rate);
    }
  }

  /// Rank 0 (or the only process) writes the model file and the resume checkpoint.
  bool writes() const { return parallel_ == nullptr || parallel_->rank() == 0; }

  /// Ranks must train the same thing from the same start: same options and data (checked),
  /// the same initial parameters (rank 0's, whatever each rank's libtorch drew).
  void joinRanks() {
    const auto sum = [](const torch::Tensor& t) { return t.defined() ? t.sum().item<double>() : 0.0; };
    const std::string fingerprint =
        fmt::format("{}|{}|{}|{}|{}|{}|{}|{}|{}|{:a}|{:a}|{:a}", infoToJson(info_), options_.steps,
                    options_.batchSize, options_.learningRate, options_.weightDecay, options_.patience,
                    options_.validationFraction, train_.size(), validation_.size(), sum(train_.features),
                    sum(train_.targets), sum(validation_.targets));
    parallel_->requireSameOnEveryRank(fingerprint, "options or training data");
    torch::NoGradGuard no_grad;
    for (auto& parameter : model_.network->parameters()) parallel_->broadcastFromRankZero(parameter);
    summary_.rank = parallel_->rank();
    summary_.ranks = parallel_->size();
  }

  /// --resume on several ranks: every rank reads rank 0's checkpoint, so it must see it.
  void requireCheckpointOnEveryRank() {
    auto found = torch::tensor({fs::exists(lastCheckpoint_) ? 1 : 0}, torch::kInt64);
    parallel_->sum(found);
    if (found.item<std::int64_t>() == 0) {
      // No rank sees it: the training stopped (a rank died, an interruption) before its first checkpoint.
      throw ConfigError(fmt::format("--resume: no checkpoint {} to resume from (the training stopped before it wrote "
                                    "one): start without --resume",
                                    lastCheckpoint_.string()));
    }
    if (found.item<std::int64_t>() != parallel_->size()) {
      throw ConfigError(fmt::format("--resume: {} of {} ranks see no checkpoint {} (every rank reads rank 0's: keep "
                                    "the model's folder on a file system all ranks share)",
                                    parallel_->size() - found.item<std::int64_t>(), parallel_->size(),
                                    lastCheckpoint_.string()));
    }
  }

  /// Validation errors of the epoch (rank 0 computes them for all); the model file is
  /// replaced when the ADE improves.
  void validateEpoch(EpochRecord& record) {
    const auto epoch_start = std::chrono::steady_clock::now();
    ValidationResult result;
    if (writes()) result = validate(model_, validation_, 1024);
    if (parallel_ != nullptr) {
      auto shared = torch::tensor({result.ade, result.fde, result.nll}, torch::kFloat64);
      parallel_->broadcastFromRankZero(shared);
      result = {shared[0].item<double>(), shared[1].item<double>(), shared[2].item<double>()};
    }
    record.validationAde = result.ade;
    record.validationFde = result.fde;
    record.validationNll = result.nll;
    if (result.ade < summary_.bestValidationAde) {
      summary_.bestValidationAde = result.ade;
      summary_.bestEpoch = record.epoch;
      sinceBest_ = 0;
      record.best = true;
      info_.epoch = record.epoch;
      info_.validationAde = result.ade;
      if (writes()) saveModel(options_.output, model_, info_);  // atomic: an interruption keeps the previous best
    } else {
      ++sinceBest_;
    }
    record.seconds += secondsSince(epoch_start);
  }

  bool calibrates() const {
    return config_.decoderOptions.count("calibrate") != 0 && config_.decoderOption("calibrate") != 0.0;
  }

  /// The decoder option `calibrate`, on the validation split: fits the best model's
  /// variance_scale, then the conformal radii of its position regions and (when the
  /// options bind metrics) the widening of its metric intervals, and rewrites the model
  /// file with them (README "Calibration").
  void calibrate() {
    ModelInfo info;
    Model best = loadModel(options_.output, info, config_.decoders);
    const auto fitted = calibrateVariance(best, validation_);
    info.config = best.config;
    info.positionRegions = {};
    info.metricIntervals = {};
    saveModel(options_.output, best, info);
    spdlog::info("calibrated {}: variance scale {:.3f} fitted on the validation split, its positions inside their "
                 "90 % regions {:.1f} % -> {:.1f} %",
                 options_.output.string(), fitted.scale, 100.0 * fitted.coverageBefore, 100.0 * fitted.coverageAfter);
    const Predictor scaled(options_.output, options_.threads, config_.decoders);
    const auto conformal = fitConformal(scaled, selection_.validation, selection_.validationMetricNames,
                                        options_.metrics.get(), options_.seed);
    info.positionRegions = conformal.positionRegions;
    info.metricIntervals = conformal.metricIntervals;
    saveModel(options_.output, best, info);
    spdlog::info("calibrated {}: conformal position regions on {} validation scenes (5 s positions inside the Gaussian "
                 "90 % region before: {:.1f} %){}\n{}",
                 options_.output.string(), selection_.validation.size(), 100.0 * conformal.gaussianCoverage90AtEnd,
                 options_.metrics ? "; metric intervals:" : "; no metrics bound, metric intervals uncalibrated",
                 conformal.report());
  }

  void saveLast() {
    if (!writes()) return;
    nlohmann::json state = {{"resume_key", resumeKey_},
                            {"next_epoch", nextEpoch_},
                            {"since_best", sinceBest_},
                            {"best_epoch", summary_.bestEpoch},
                            {"best_validation_ade", summary_.bestValidationAde},
                            {"history", nlohmann::json::array()}};
    for (const auto& past : summary_.epochs) state["history"].push_back(recordToJson(past));
    saveCheckpoint(lastCheckpoint_, model_, optimizer_, info_, state.dump());
  }

  const TrainOptions& options_;
  DataParallel* parallel_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  Selection selection_;
  VectorNetConfig config_;
  SceneTensors train_;
  SceneTensors validation_;
  Model model_;
  torch::optim::AdamW optimizer_;
  fs::path lastCheckpoint_;
  nlohmann::json resumeKey_;  ///< what a --resume must share with this training
  ModelInfo info_;
  TrainSummary summary_;
  std::int64_t stepsPerEpoch_ = 1;
  int nextEpoch_ = 0;
  int sinceBest_ = 0;
  double trainedSamples_ = 0.0;
  double trainingSeconds_ = 0.0;
};

}  // namespace

TrainSummary train(const TrainOptions& options, const std::function<void(const EpochRecord&)>& on_epoch) {
  options.validate();
  configureThreads(options.threads);
  std::unique_ptr<DataParallel> parallel;
  if (const auto rendezvous = rendezvousFromEnvironment()) {
    if (rendezvous->size > options.batchSize) {
      throw ConfigError(fmt::format("--batch {}: a distributed training over {} ranks ({}) needs a global batch of "
                                    "at least {} samples (each rank trains its slice of every batch)",
                                    options.batchSize, rendezvous->size, rendezvous->source, rendezvous->size));
    }
    parallel = std::make_unique<DataParallel>(*rendezvous);
  }
  Trainer trainer(options, parallel.get());
  return trainer.run(on_epoch);
}

std::string TrainSummary::report() const {
  std::string text = fmt::format("trained VectorNet ({} decoder): best validation ADE {:.3f} m at epoch {} of {} ({}), "
                                 "{:.1f} s, {:.0f} training samples/s\n",
                                 decoder, bestValidationAde, bestEpoch, plannedEpochs, stopReason, seconds,
                                 samplesPerSecond);
  text += "  samples (train / validation):";
  for (const auto& [label, count] : trainSamples) {
    const auto it = validationSamples.find(label);
    text += fmt::format(" {} {}/{}", label, count, it == validationSamples.end() ? 0 : it->second);
  }
  text += fmt::format("\n  model: {}\n", output.string());
  if (ranks > 1) {
    text += fmt::format("  data-parallel over {} ranks: all-reduce {:.1f} s = {:.1f} % of the training steps' time\n",
                        ranks, allreduceSeconds, allreduceShare * 100.0);
  }
  return text;
}

}  // namespace vsd::model
