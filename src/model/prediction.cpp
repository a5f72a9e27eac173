#include <fmt/format.h>

#include <chrono>
#include <fstream>

#include "checkpoint.hpp"
#include "network.hpp"
#include "tensors.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/model/model.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {
// Scenes per forward pass: large enough to keep the matrix products efficient, small
// enough that activations (~6 MB) stay below glibc's mmap threshold and are recycled
// instead of being mapped and zeroed by the kernel for every operation.
constexpr std::int64_t kPredictBatch = 512;
constexpr std::size_t kReadChunk = 4096;
}  // namespace

struct Predictor::Impl {
  fs::path path;
  ModelInfo info;
  mutable VectorNet network{nullptr};
};

Predictor::Predictor(const fs::path& model, int threads) : impl_(std::make_unique<Impl>()) {
  if (threads < 1 || threads > 256) {
    throw ConfigError::field("command line", "--threads", std::to_string(threads), "1 .. 256");
  }
  configureThreads(threads);
  impl_->path = model;
  impl_->network = loadModel(model, impl_->info);
}

Predictor::~Predictor() = default;

const ModelInfo& Predictor::info() const { return impl_->info; }

void Predictor::checkCompatible(const vector::DatasetHeader& header, const std::string& what) const {
  const auto& config = impl_->info.config;
  if (header.horizon != config.horizon || std::abs(header.step - config.step) > 1e-9) {
    throw ModelError(fmt::format("{}: {} steps of {} s, but the model {} predicts {} steps of {} s", what,
                                 header.horizon, header.step, impl_->path.string(), config.horizon, config.step));
  }
}

std::vector<Polyline> Predictor::predict(const std::vector<vector::VectorizedScene>& scenes) const {
  std::vector<Polyline> result;
  result.reserve(scenes.size());
  c10::InferenceMode inference;
  impl_->network->eval();
  for (std::size_t first = 0; first < scenes.size(); first += static_cast<std::size_t>(kPredictBatch)) {
    const std::size_t last = std::min(scenes.size(), first + static_cast<std::size_t>(kPredictBatch));
    const auto tensors = buildTensors(scenes, impl_->info.config, first, last);
    const auto positions = impl_->network->positions(tensors);
    for (std::int64_t i = 0; i < positions.size(0); ++i) {
      result.push_back(toSceneFrame(positions[i], tensors.origins[static_cast<std::size_t>(i)],
                                    tensors.headings[static_cast<std::size_t>(i)]));
    }
  }
  return result;
}

LabelErrors displacementErrors(const Polyline& prediction, const vector::VectorizedScene& scene) {
  LabelErrors errors;
  double sum = 0.0;
  std::size_t valid = 0;
  for (std::size_t k = 0; k < scene.target.size() && k < prediction.size(); ++k) {
    if (!scene.targetValid[k]) continue;
    const double distance = (prediction[k] - scene.target[k]).norm();
    sum += distance;
    errors.fde = distance;
    ++valid;
  }
  errors.samples = valid > 0 ? 1 : 0;
  errors.ade = valid > 0 ? sum / static_cast<double>(valid) : 0.0;
  return errors;
}

namespace {

/// Reads a dataset in chunks and hands (scene, prediction) pairs to `visit`.
template <typename Visit>
void predictDataset(const Predictor& predictor, const vector::DatasetReader& reader, double& prediction_seconds,
                    Visit&& visit) {
  predictor.checkCompatible(reader.header(), reader.path().string());
  // An ADE over nothing would print as 0.000 m: nothing to predict is an error.
  if (reader.size() == 0) throw DatasetError(fmt::format("{}: the dataset holds no sample", reader.path().string()));
  for (std::size_t first = 0; first < reader.size(); first += kReadChunk) {
    throwIfInterrupted();
    std::vector<vector::VectorizedScene> scenes;
    for (std::size_t i = first; i < std::min(reader.size(), first + kReadChunk); ++i) scenes.push_back(reader.scene(i));
    const auto start = std::chrono::steady_clock::now();
    const auto predictions = predictor.predict(scenes);
    prediction_seconds += secondsSince(start);
    for (std::size_t i = 0; i < scenes.size(); ++i) visit(first + i, scenes[i], predictions[i]);
  }
}

void accumulate(LabelErrors& total, const LabelErrors& one) {
  if (one.samples == 0) return;
  const auto n = static_cast<double>(total.samples);
  total.ade = (total.ade * n + one.ade) / (n + 1.0);
  total.fde = (total.fde * n + one.fde) / (n + 1.0);
  ++total.samples;
}

}  // namespace

Evaluation evaluate(const Predictor& predictor, const std::vector<fs::path>& data) {
  if (data.empty()) throw ConfigError("--data: no dataset given");
  Evaluation evaluation;
  for (const auto& path : data) {
    const vector::DatasetReader reader(vector::resolveDatasetPath(path));
    predictDataset(predictor, reader, evaluation.predictionSeconds,
                   [&](std::size_t, const vector::VectorizedScene& scene, const Polyline& prediction) {
                     const auto errors = displacementErrors(prediction, scene);
                     accumulate(evaluation.perLabel[scene.label], errors);
                     accumulate(evaluation.overall, errors);
                   });
  }
  if (evaluation.overall.samples == 0) {
    throw DatasetError(fmt::format("no sample of {} has a valid target step: nothing to evaluate",
                                   data.size() == 1 ? data.front().string() : "the datasets"));
  }
  return evaluation;
}

std::string Evaluation::table() const {
  std::string text = fmt::format("  {:<20} {:>9} {:>9} {:>9}\n", "functional scenario", "samples", "ADE [m]", "FDE [m]");
  for (const auto& [label, errors] : perLabel) {
    text += fmt::format("  {:<20} {:>9} {:>9.3f} {:>9.3f}\n", label, errors.samples, errors.ade, errors.fde);
  }
  text += fmt::format("  {:<20} {:>9} {:>9.3f} {:>9.3f}\n", "all", overall.samples, overall.ade, overall.fde);
  if (predictionSeconds > 0.0) {
    text += fmt::format("  prediction: {:.0f} scenes/s\n", static_cast<double>(overall.samples) / predictionSeconds);
  }
  return text;
}

void Evaluation::writeCsv(const fs::path& path) const {
  AtomicOutput output(path);
  {
    std::ofstream stream(output.tempPath());
    CsvWriter csv(stream);
    csv.writeRow({"label", "samples", "ade_m", "fde_m"});
    for (const auto& [label, errors] : perLabel) {
      csv.writeRow({label, std::to_string(errors.samples), formatNumber(errors.ade), formatNumber(errors.fde)});
    }
    csv.writeRow({"all", std::to_string(overall.samples), formatNumber(overall.ade), formatNumber(overall.fde)});
    if (!stream) throw IoError(path.string() + ": write failed");
  }
  output.commit();
}

std::size_t writePredictions(const Predictor& predictor, const fs::path& model_file, const fs::path& dataset,
                             const fs::path& output_path) {
  requireFileOutputPath(output_path, "--out");
  const fs::path dataset_file = vector::resolveDatasetPath(dataset);
  const vector::DatasetReader reader(dataset_file);
  const auto horizon = static_cast<hsize_t>(reader.header().horizon);
  if (!output_path.parent_path().empty()) ensureDirectory(output_path.parent_path());
  AtomicOutput output(output_path);
  h5::silenceErrorStack();
  std::size_t count = 0;
  double seconds = 0.0;
  try {
    H5::H5File file(output.tempPath().string(), H5F_ACC_TRUNC);
    H5::Group root = file.openGroup("/");
    h5::writeAttribute(root, "schema", std::string("vsd-predictions/1"));
    h5::writeAttribute(root, "model", model_file.string());
    h5::writeAttribute(root, "model_sha256", sha256OfFile(model_file));
    h5::writeAttribute(root, "dataset", dataset_file.string());
    h5::writeAttribute(root, "dataset_sha256", sha256OfFile(dataset_file));
    h5::writeAttribute(root, "step", reader.header().step);
    h5::writeAttribute(root, "horizon", static_cast<std::int64_t>(horizon));
    h5::writeAttribute(root, "tool_version", toolVersion());
    h5::writeStrings(root, "labels", reader.labels());
    h5::Appendable<std::int64_t> row(root, "dataset_row", {}, 4096, 4);
    h5::Appendable<std::int64_t> sample_index(root, "sample_index", {}, 4096, 4);
    h5::Appendable<std::int32_t> label(root, "sample_label", {}, 4096, 4);
    h5::Appendable<double> predictions(root, "predictions", {horizon, 2}, 1024, 1);
    h5::Appendable<double> targets(root, "targets", {horizon, 2}, 1024, 1);
    h5::Appendable<std::uint8_t> target_valid(root, "target_valid", {horizon}, 1024, 1);
    h5::Appendable<double> ade(root, "ade", {}, 4096, 1);
    h5::Appendable<double> fde(root, "fde", {}, 4096, 1);
    std::map<std::string, std::int32_t> label_index;
    for (std::size_t l = 0; l < reader.labels().size(); ++l) label_index[reader.labels()[l]] = static_cast<std::int32_t>(l);
    predictDataset(predictor, reader, seconds,
                   [&](std::size_t i, const vector::VectorizedScene& scene, const Polyline& prediction) {
                     row.push(static_cast<std::int64_t>(i));
                     sample_index.push(static_cast<std::int64_t>(scene.sample));
                     label.push(label_index[scene.label]);
                     for (std::size_t k = 0; k < prediction.size(); ++k) {
                       predictions.push({prediction[k].x(), prediction[k].y()});
                       targets.push({scene.target[k].x(), scene.target[k].y()});
                       target_valid.push(scene.targetValid[k]);
                     }
                     const auto errors = displacementErrors(prediction, scene);
                     ade.push(errors.ade);
                     fde.push(errors.fde);
                     if (++count % 4096 == 0) h5::flushAll(row, sample_index, label, predictions, targets, target_valid, ade, fde);
                   });
    h5::flushAll(row, sample_index, label, predictions, targets, target_valid, ade, fde);
    file.close();
  } catch (const H5::Exception& error) {
    throw IoError(fmt::format("{}: cannot write predictions: {}", output_path.string(), h5::errorCause(error)));
  }
  output.commit();
  return count;
}

}  // namespace vsd::model
