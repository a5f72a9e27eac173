// `vsd-predictions/3`: what `vsd-sumo predict` writes (README "train / predict / evaluate").
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/hdf5.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/log.hpp"
#include "vsd/model/model.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {

constexpr std::size_t kReadChunk = 4096;
constexpr std::size_t kFlushEvery = 1024;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The columns of a predictions file; optional ones exist when the predictor provides them.
class PredictionColumns {
 public:
  PredictionColumns(H5::Group& root, hsize_t horizon, const Predictor& predictor, const PredictionFileOptions& options)
      : horizon_(horizon),
        draws_(predictor.probabilistic() ? static_cast<hsize_t>(options.predict.samples) : 0),
        metrics_(options.metricNames.size()),
        metricNames_(options.metricNames),
        calibration_(predictor.info().metricIntervals),
        row_(root, "dataset_row", {}, 4096, 4),
        sampleIndex_(root, "sample_index", {}, 4096, 4),
        label_(root, "sample_label", {}, 4096, 4),
        predictions_(root, "predictions", {horizon, 2}, 1024, 1),
        targets_(root, "targets", {horizon, 2}, 1024, 1),
        targetValid_(root, "target_valid", {horizon}, 1024, 1),
        ade_(root, "ade", {}, 4096, 1),
        fde_(root, "fde", {}, 4096, 1) {
    if (predictor.predictsMotion()) {
      kinematics_.emplace(Kinematics{{root, "predicted_heading", {horizon}, 1024, 1},
                                     {root, "predicted_speed", {horizon}, 1024, 1},
                                     {root, "predicted_accel", {horizon}, 1024, 1}});
    }
    if (predictor.probabilistic()) {
      covariance_.emplace(root, "position_covariance", std::vector<hsize_t>{horizon, 2, 2}, 512, 1);
      regionRadius2_.emplace(root, "position_region_radius2", std::vector<hsize_t>{horizon, kCoverageLevels.size()}, 512, 1);
    }
    if (draws_ > 0) {
      samples_.emplace(Samples{{root, "sample_positions", {draws_, horizon, 2}, 64, 1},
                               {root, "sample_speed", {draws_, horizon}, 64, 1},
                               {root, "sample_accel", {draws_, horizon}, 64, 1}});
    }
    if (metrics_ > 0) {
      h5::writeStrings(root, "metric_names", options.metricNames);
      metricColumns_.emplace(Metrics{{root, "metrics_predicted", {metrics_}, 1024, 1},
                                     {root, "metric_intervals", {metrics_, 5}, 1024, 1}});
    }
  }

  void push(std::size_t row, std::int32_t label, const vector::VectorizedScene& scene, const Prediction& prediction,
            const PredictionFileOptions& options) {
    row_.push(static_cast<std::int64_t>(row));
    sampleIndex_.push(static_cast<std::int64_t>(scene.sample));
    label_.push(label);
    const auto& most_likely = prediction.mostLikely;
    for (std::size_t k = 0; k < horizon_; ++k) {
      predictions_.push({most_likely.positions[k].x(), most_likely.positions[k].y()});
      targets_.push({scene.target[k].x(), scene.target[k].y()});
      targetValid_.push(scene.targetValid[k]);
    }
    const auto errors = displacementErrors(most_likely.positions, scene);
    ade_.push(errors.ade);
    fde_.push(errors.fde);
    if (kinematics_) pushStates(most_likely, &kinematics_->heading, kinematics_->speed, kinematics_->accel);
    if (covariance_) {
      for (const auto& c : prediction.positionCovariance) covariance_->push({c(0, 0), c(0, 1), c(1, 0), c(1, 1)});
      for (const auto& r : prediction.regionRadius2) regionRadius2_->push(r.begin(), r.end());
    }
    if (samples_) pushSamples(prediction);
    if (metricColumns_) pushMetrics(scene, prediction, options);
    if (++pushed_ % kFlushEvery == 0) flush();
  }

  void flush() {
    h5::flushAll(row_, sampleIndex_, label_, predictions_, targets_, targetValid_, ade_, fde_);
    if (kinematics_) h5::flushAll(kinematics_->heading, kinematics_->speed, kinematics_->accel);
    if (covariance_) h5::flushAll(*covariance_, *regionRadius2_);
    if (samples_) h5::flushAll(samples_->positions, samples_->speed, samples_->accel);
    if (metricColumns_) h5::flushAll(metricColumns_->predicted, metricColumns_->intervals);
  }

 private:
  struct Kinematics {
    h5::Appendable<double> heading, speed, accel;
  };
  struct Samples {
    h5::Appendable<float> positions, speed, accel;
  };
  struct Metrics {
    h5::Appendable<double> predicted, intervals;
  };

  template <typename T>
  void pushStates(const Trajectory& trajectory, h5::Appendable<T>* heading, h5::Appendable<T>& speed,
                  h5::Appendable<T>& accel) {
    for (const auto& state : trajectory.states) {
      if (heading != nullptr) heading->push(static_cast<T>(state.heading));
      speed.push(static_cast<T>(state.speed));
      accel.push(static_cast<T>(state.accel));
    }
  }

  void pushSamples(const Prediction& prediction) {
    for (hsize_t s = 0; s < draws_; ++s) {
      const auto& draw = prediction.samples[s];
      for (const auto& p : draw.positions) samples_->positions.push({static_cast<float>(p.x()), static_cast<float>(p.y())});
      pushStates<float>(draw, nullptr, samples_->speed, samples_->accel);
    }
  }

  void pushMetrics(const vector::VectorizedScene& scene, const Prediction& prediction, const PredictionFileOptions& options) {
    const auto point = options.metrics(scene, prediction.mostLikely);
    metricColumns_->predicted.push(point.begin(), point.end());
    const auto draws = metricDraws(scene, prediction, options.metrics, metrics_);
    for (std::size_t m = 0; m < metrics_; ++m) {
      if (draws[m].empty()) {
        metricColumns_->intervals.push({kNaN, kNaN, kNaN, kNaN, kNaN});
        continue;
      }
      const auto interval = intervalOf(draws[m], calibration_.find(scene.label, metricNames_[m]));
      metricColumns_->intervals.push({interval.p05, interval.p25, interval.median, interval.p75, interval.p95});
    }
  }

  hsize_t horizon_;
  hsize_t draws_;
  std::size_t metrics_;
  std::vector<std::string> metricNames_;
  const IntervalCalibration& calibration_;
  std::size_t pushed_ = 0;
  h5::Appendable<std::int64_t> row_, sampleIndex_;
  h5::Appendable<std::int32_t> label_;
  h5::Appendable<double> predictions_, targets_;
  h5::Appendable<std::uint8_t> targetValid_;
  h5::Appendable<double> ade_, fde_;
  std::optional<Kinematics> kinematics_;
  std::optional<h5::Appendable<double>> covariance_;
  std::optional<h5::Appendable<double>> regionRadius2_;
  std::optional<Samples> samples_;
  std::optional<Metrics> metricColumns_;
};

void writeHeader(H5::Group& root, const Predictor& predictor, const fs::path& model_file, const fs::path& dataset_file,
                 const vector::DatasetReader& reader, const PredictionFileOptions& options) {
  h5::writeAttribute(root, "schema", std::string("vsd-predictions/3"));
  h5::writeAttribute(root, "predictor", predictor.name());
  h5::writeAttribute(root, "model", model_file.string());
  h5::writeAttribute(root, "model_sha256", Predictor::isBuiltin(model_file) ? std::string() : sha256OfFile(model_file));
  h5::writeAttribute(root, "dataset", dataset_file.string());
  h5::writeAttribute(root, "dataset_sha256", sha256OfFile(dataset_file));
  h5::writeAttribute(root, "step", reader.header().step);
  h5::writeAttribute(root, "horizon", static_cast<std::int64_t>(reader.header().horizon));
  h5::writeAttribute(root, "samples", static_cast<std::int64_t>(predictor.probabilistic() ? options.predict.samples : 0));
  h5::writeAttribute(root, "sample_seed", static_cast<std::int64_t>(options.predict.seed));
  h5::writeAttribute(root, "tool_version", toolVersion());
  h5::writeStrings(root, "labels", reader.labels());
}

}  // namespace

std::vector<std::vector<double>> metricDraws(const vector::VectorizedScene& scene, const Prediction& prediction,
                                             const FutureMetrics& metrics, std::size_t count) {
  std::vector<std::vector<double>> draws(count);
  for (auto& column : draws) column.reserve(prediction.samples.size());
  for (const auto& future : prediction.samples) {
    const auto values = metrics(scene, future);
    for (std::size_t m = 0; m < count; ++m) draws[m].push_back(values.at(m));
  }
  return draws;
}

std::size_t writePredictions(const Predictor& predictor, const fs::path& model_file, const fs::path& dataset,
                             const fs::path& output_path, const PredictionFileOptions& options) {
  requireFileOutputPath(output_path, "--out");
  options.predict.validate();
  if (!options.metricNames.empty() && !options.metrics) throw Error("internal: metric names without a metric function");
  const fs::path dataset_file = vector::resolveDatasetPath(dataset);
  const vector::DatasetReader reader(dataset_file);
  predictor.checkCompatible(reader.header(), reader.path().string());
  if (reader.size() == 0) throw DatasetError(fmt::format("{}: the dataset holds no sample", reader.path().string()));
  if (options.predict.samples > 0 && !predictor.probabilistic()) {
    spdlog::warn("--samples {}: the {} predictor is deterministic; only its most likely future is written",
                 options.predict.samples, predictor.name());
  }
  if (!output_path.parent_path().empty()) ensureDirectory(output_path.parent_path());
  AtomicOutput output(output_path);
  h5::silenceErrorStack();
  std::size_t count = 0;
  try {
    H5::H5File file(output.tempPath().string(), H5F_ACC_TRUNC);
    H5::Group root = file.openGroup("/");
    writeHeader(root, predictor, model_file, dataset_file, reader, options);
    PredictionColumns columns(root, static_cast<hsize_t>(reader.header().horizon), predictor, options);
    std::map<std::string, std::int32_t> label_index;
    for (std::size_t l = 0; l < reader.labels().size(); ++l) label_index[reader.labels()[l]] = static_cast<std::int32_t>(l);
    for (std::size_t first = 0; first < reader.size(); first += kReadChunk) {
      throwIfInterrupted();
      std::vector<vector::VectorizedScene> scenes;
      for (std::size_t i = first; i < std::min(reader.size(), first + kReadChunk); ++i) scenes.push_back(reader.scene(i));
      const auto predictions = predictor.predictDistribution(scenes, options.predict);
      for (std::size_t i = 0; i < scenes.size(); ++i) {
        columns.push(first + i, label_index[scenes[i].label], scenes[i], predictions[i], options);
        ++count;
      }
    }
    columns.flush();
    file.close();
  } catch (const H5::Exception& error) {
    throw IoError(fmt::format("{}: cannot write predictions: {}", output_path.string(), h5::errorCause(error)));
  }
  output.commitUnlessInterrupted();
  return count;
}

}  // namespace vsd::model
