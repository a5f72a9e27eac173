// train / predict / evaluate: VectorNet on datasets.
#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/experiment/experiment.hpp"
#include "vsd/metrics/metrics.hpp"
#include "vsd/model/model.hpp"
#include "vsd/model/presets.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/vector/dataset.hpp"

namespace vsd::cli {

namespace {

std::string duration(double seconds) {
  if (seconds >= 3600.0) return fmt::format("{:.1f} h", seconds / 3600.0);
  if (seconds >= 60.0) return fmt::format("{:.1f} min", seconds / 60.0);
  return fmt::format("{:.0f} s", seconds);
}

/// With sampled futures, `predict` writes every metric that applies to the dataset's scenes
/// for the most likely future and as intervals over the draws: the metric code of simulated
/// runs, on the predictor's own states where it has them (README "vsd-predictions/3").
void bindPredictionMetrics(const std::filesystem::path& data, model::PredictionFileOptions& options) {
  if (options.predict.samples < 1) return;
  const auto binding = experiment::futureMetricBinding(data);
  options.metricNames = binding->names;
  options.metrics = binding->compute;
}

/// Labels as a model's subject (docs/output-policy.md): sorted, so that the order of a mix does not matter.
std::string labelSubject(std::vector<std::string> labels) {
  std::sort(labels.begin(), labels.end());
  return fmt::format("labels {}", fmt::join(labels, ", "));
}

/// The model file kind, whose subject is what the model trained on (read with libtorch).
const OutputKind& modelKind() {
  static const OutputKind kind = [] {
    OutputKind copy = output_kinds::modelFile();
    copy.identify = [](const std::filesystem::path& path) -> std::optional<std::string> {
      if (!output_kinds::modelFile().identify(path)) return std::nullopt;
      try {
        return labelSubject(model::Predictor(path, 1).info().labels);
      } catch (const std::exception&) {
        return std::string();  // a model file of ours that this version cannot read: no subject
      }
    };
    return copy;
  }();
  return kind;
}

/// The labels a training of `options` learns: the mix's, or every label of the data.
std::string trainingSubject(const model::TrainOptions& options) {
  std::vector<std::string> labels;
  for (const auto& [label, count] : options.mix.counts) {
    if (count > 0) labels.push_back(label);
  }
  if (labels.empty()) {
    vector::DatasetCollection data;
    for (const auto& path : options.data) data.add(path);
    for (const auto& [label, count] : data.labelCounts()) labels.push_back(label);
  }
  return labelSubject(labels);
}

/// (flag, path) of every input, for the output policy (an output may not be one of them).
std::vector<std::pair<std::string, std::filesystem::path>> inputsOf(
    const std::string& flag, const std::vector<std::filesystem::path>& paths) {
  std::vector<std::pair<std::string, std::filesystem::path>> inputs;
  for (const auto& path : paths) {
    inputs.emplace_back(flag, path);
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) inputs.emplace_back(flag, vector::resolveDatasetPath(path));
  }
  return inputs;
}

/// "offsets, kinematic" for help texts: the decoders of the registry the training is handed.
std::string decoderNames(const model::DecoderRegistry& decoders) {
  std::vector<std::string> names;
  for (const auto& info : decoders.available()) names.push_back(info.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

/// "recommended, paper" for help texts.
std::string presetNames() {
  std::vector<std::string> names;
  for (const auto& preset : model::modelPresets()) names.push_back(preset.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

}  // namespace

void addTrainCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<model::TrainOptions>();
  auto mix = std::make_shared<std::string>();
  auto decoder_options = std::make_shared<std::vector<std::string>>();
  CLI::App* command = app.add_subcommand("train", "Train VectorNet on datasets mixed from functional scenarios and maps");
  command->add_option("-d,--data", options->data, "Dataset files or run folders")->required();
  command->add_option("--mix", *mix, "Samples per label, e.g. acc=2000,lk=2000,acc_lk=200 (default: all)");
  command->add_option("-o,--out", options->output, "Model file to write (the best epoch)")->required();
  auto force = std::make_shared<bool>(false);
  command->add_flag("--force", *force, "Replace a model file trained on other labels (docs/output-policy.md)");
  addNumber(command, "-s,--seed", options->seed, "Seed (sample choice, split, initialisation, order)")
      ->capture_default_str();
  addNumber(command, "--threads", options->threads, "libtorch threads")->capture_default_str();
  addNumber(command, "--steps", options->steps, "Optimizer steps (length of the learning-rate schedule)")
      ->capture_default_str();
  addNumber(command, "--patience", options->patience, "Stop after this many epochs without improvement")
      ->capture_default_str();
  addNumber(command, "--minibatch", options->batchSize, "Training minibatch size (scenes per optimizer step; was --batch)")->capture_default_str();
  addNumber(command, "--lr", options->learningRate, "Peak learning rate (AdamW)")->capture_default_str();
  addNumber(command, "--weight-decay", options->weightDecay, "AdamW weight decay")->capture_default_str();
  addNumber(command, "--validation-fraction", options->validationFraction, "Share of each label for validation")
      ->capture_default_str();
  addNumber(command, "--hidden", options->config.hidden, "Subgraph width")->capture_default_str();
  addNumber(command, "--layers", options->config.subgraphLayers, "Subgraph layers")->capture_default_str();
  addNumber(command, "--global-width", options->config.globalWidth, "Attention width")->capture_default_str();
  addNumber(command, "--heads", options->config.heads, "Attention heads")->capture_default_str();
  addNumber(command, "--decoder-hidden", options->config.decoderHidden, "Decoder width")->capture_default_str();
  auto* decoder = command->add_option("--decoder", options->config.decoder,
                                      "Decoder: " + decoderNames(options->config.decoderRegistry()))
                      ->capture_default_str();
  command->add_option("--decoder-option", *decoder_options,
                      "A decoder option name=value (repeatable; docs/models.md \"Decoders\" lists them)");
  auto* frame = command->add_option("--frame", options->config.frame, "Model frame: ego or lane")->capture_default_str();
  auto preset = std::make_shared<std::string>();
  command->add_option("--preset", *preset, "A named configuration: decoder, frame and decoder options (" +
                                               presetNames() + "; docs/models.md \"Presets\"); --decoder-option adds to it")
      ->excludes(decoder)
      ->excludes(frame);
  addNumber(command, "--lane-smoothing", options->config.laneSmoothing,
            "m: half-width of the lane frame's smoothing of its reference line")
      ->capture_default_str();
  command->add_flag("--resume", options->resume, "Continue an interrupted training from <out>.last");
  command->add_option("--init-from", options->initialModel,
                      "Fine-tune: start from this model's weights (same architecture, decoder, frame) instead of fresh "
                      "ones");
  command->callback([=, &context] {
    context.action = [=] {
      options->mix = model::Mix::parse(*mix);
      auto inputs = inputsOf("--data", options->data);
      inputs.emplace_back("--init-from", options->initialModel);
      checkOutput({options->output, &modelKind(), trainingSubject(*options), *force, "--out", "--force", inputs});
      const auto given_options = model::parseDecoderOptions(*decoder_options);
      if (preset->empty()) {
        options->config.decoderRegistry().find(options->config.decoder, "--decoder");
        options->config.decoderOptions = given_options;
      } else {
        model::applyPreset(model::findModelPreset(*preset, "--preset"), given_options, options->config);
      }
      experiment::bindCalibrationMetrics(*options);  // `calibrate` also calibrates metric intervals
      const auto summary = model::train(*options, [&](const model::EpochRecord& record) {
        const int planned = record.plannedEpochs;
        const std::string nll =
            std::isnan(record.validationNll) ? "" : fmt::format(", NLL {:.3f}", record.validationNll);
        fmt::print("epoch {:>3}/{}: train loss {:.3f}, validation ADE {:.3f} m (FDE {:.3f} m{}), lr {:.2e}, "
                   "{:.0f} samples/s, {:.1f} s{}, at most {} left\n",
                   record.epoch, planned, record.trainLoss, record.validationAde, record.validationFde, nll,
                   record.learningRate, record.samplesPerSecond, record.seconds, record.best ? " *best*" : "",
                   duration(record.seconds * (planned - record.epoch)));
        std::fflush(stdout);
      });
      if (summary.rank == 0) fmt::print("{}", summary.report());  // the other ranks of a distributed training are silent
      return 0;
    };
  });
}

void addPredictCommand(CLI::App& app, CommandContext& context) {
  auto model_file = std::make_shared<std::filesystem::path>();
  auto data = std::make_shared<std::filesystem::path>();
  auto out = std::make_shared<std::filesystem::path>();
  auto threads = std::make_shared<int>(2);
  auto file_options = std::make_shared<model::PredictionFileOptions>();
  CLI::App* command = app.add_subcommand("predict", "Predict the Ego of every sample of a dataset (vsd-predictions/3)");
  command->add_option("-m,--model", *model_file, "Model file, or cv / ca (no training)")->required();
  command->add_option("-d,--data", *data, "Dataset file or run folder")->required();
  command->add_option("-o,--out", *out, "Predictions file (.h5)")->required();
  auto force = std::make_shared<bool>(false);
  command->add_flag("--force", *force,
                    "Replace a predictions file of another model or dataset (docs/output-policy.md)");
  CLI::Option* samples = addNumber(command, "--futures", file_options->predict.samples,
                                    "Futures to draw per scene from a probabilistic model, >= 1 (without it: "
                                    "the most likely future only; was --samples)");
  addNumber(command, "--future-seed", file_options->predict.seed, "Seed of the drawn futures (was --sample-seed)")
      ->capture_default_str();
  addNumber(command, "--threads", *threads, "libtorch threads")->capture_default_str();
  command->callback([=, &context] {
    context.action = [=] {
      if (samples->count() > 0 && file_options->predict.samples < 1) {  // 0 would silently draw nothing
        throw ConfigError::field("command line", "--futures", std::to_string(file_options->predict.samples),
                                 ">= 1 futures per scene (leave it out for the most likely future only)");
      }
      file_options->predict.validate();
      auto inputs = inputsOf("--data", {*data});
      inputs.emplace_back("--model", *model_file);
      // As the predictions file records them: the model as given, the dataset file it read.
      const std::string subject =
          fmt::format("{} on {}", model_file->string(), vector::resolveDatasetPath(*data).string());
      checkOutput({*out, &output_kinds::predictionsFile(), subject, *force, "--out", "--force", inputs});
      const model::Predictor predictor(*model_file, *threads);
      auto with_metrics = *file_options;
      if (predictor.probabilistic()) bindPredictionMetrics(*data, with_metrics);
      const auto count = model::writePredictions(predictor, *model_file, *data, *out, with_metrics);
      fmt::print("predicted {} samples of {} with {} -> {}\n", count, data->string(), model_file->string(),
                 out->string());
      return 0;
    };
  });
}

void addEvaluateCommand(CLI::App& app, CommandContext& context) {
  auto model_file = std::make_shared<std::filesystem::path>();
  auto data = std::make_shared<std::vector<std::filesystem::path>>();
  auto csv = std::make_shared<std::filesystem::path>();
  auto threads = std::make_shared<int>(2);
  CLI::App* command = app.add_subcommand("evaluate", "ADE/FDE (and NLL and calibration) of a model per functional scenario");
  command->add_option("-m,--model", *model_file, "Model file, or cv / ca (no training)")->required();
  command->add_option("-d,--data", *data, "Dataset files or run folders")->required();
  command->add_option("--csv", *csv, "Also write the table as CSV");
  addNumber(command, "--threads", *threads, "libtorch threads")->capture_default_str();
  command->callback([=, &context] {
    context.action = [=] {
      if (!csv->empty()) {
        static const OutputKind kEvaluationTable = textFileKind("evaluation table", "label,samples,ade_m");
        auto inputs = inputsOf("--data", *data);
        inputs.emplace_back("--model", *model_file);
        checkOutput({*csv, &kEvaluationTable, "", false, "--csv", "--force", inputs});
        requireFileOutputPath(*csv, "--csv");
      }
      const model::Predictor predictor(*model_file, *threads);
      const auto evaluation = model::evaluate(predictor, *data);
      if (predictor.info().trained) {
        fmt::print("{} ({} decoder, trained on {}, validation ADE {:.3f} m):\n{}", model_file->string(),
                   predictor.name(), predictor.info().mix, predictor.info().validationAde, evaluation.table());
      } else {
        fmt::print("{} (no training):\n{}", predictor.name(), evaluation.table());
      }
      if (!csv->empty()) evaluation.writeCsv(*csv);
      return 0;
    };
  });
}

}  // namespace vsd::cli
