// ADE/FDE of every predictor; NLL and coverage of positions for probabilistic ones.
#include <fmt/format.h>

#include <Eigen/LU>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>

#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/model/evaluation.hpp"

namespace fs = std::filesystem;

namespace vsd::model {

namespace {

constexpr std::size_t kReadChunk = 4096;

/// Adds `value` to a running mean over `count` earlier values.
void addToMean(double& mean, std::size_t count, double value) {
  mean += (value - mean) / static_cast<double>(count + 1);
}

struct GaussianScore {
  double nll = 0.0;          ///< nats
  double mahalanobis2 = 0.0;  ///< r' S^-1 r
};

GaussianScore scorePosition(const Vec2& truth, const Vec2& mean, const Eigen::Matrix2d& covariance) {
  const Vec2 r = truth - mean;
  const double determinant = covariance.determinant();
  GaussianScore score;
  score.mahalanobis2 = r.dot(covariance.inverse() * r);
  score.nll = 0.5 * score.mahalanobis2 + 0.5 * std::log(determinant) + std::log(2.0 * kPi);
  return score;
}

}  // namespace

std::array<std::size_t, kCalibrationPoints> calibrationSteps(std::size_t horizon_steps) {
  std::array<std::size_t, kCalibrationPoints> steps{};
  for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
    const long rounded = std::lround(kCalibrationShares[t] * static_cast<double>(horizon_steps));
    steps[t] = static_cast<std::size_t>(std::max(1L, rounded)) - 1;
  }
  return steps;
}

void LabelErrors::add(const LabelErrors& one) {
  if (one.samples == 0) return;
  addToMean(ade, samples, one.ade);
  addToMean(fde, samples, one.fde);
  ++samples;
  if (one.scored > 0) {
    addToMean(nll, scored, one.nll);
    ++scored;
  }
  for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
    if (one.countAt[t] == 0) continue;
    addToMean(nllAt[t], countAt[t], one.nllAt[t]);
    for (std::size_t l = 0; l < kCoverageLevels.size(); ++l) addToMean(coverageAt[t][l], countAt[t], one.coverageAt[t][l]);
    ++countAt[t];
  }
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

LabelErrors predictionErrors(const Prediction& prediction, const vector::VectorizedScene& scene) {
  LabelErrors errors = displacementErrors(prediction.mostLikely.positions, scene);
  if (errors.samples == 0 || !prediction.probabilistic()) return errors;
  const auto& mean = prediction.mostLikely.positions;
  double sum = 0.0;
  std::size_t valid = 0;
  for (std::size_t k = 0; k < scene.target.size() && k < mean.size(); ++k) {
    if (!scene.targetValid[k]) continue;
    sum += scorePosition(scene.target[k], mean[k], prediction.positionCovariance[k]).nll;
    ++valid;
  }
  errors.scored = 1;
  errors.nll = sum / static_cast<double>(valid);
  const auto steps = calibrationSteps(scene.target.size());
  for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
    const std::size_t k = steps[t];
    if (k >= mean.size() || !scene.targetValid[k]) continue;
    const auto score = scorePosition(scene.target[k], mean[k], prediction.positionCovariance[k]);
    errors.countAt[t] = 1;
    errors.nllAt[t] = score.nll;
    for (std::size_t l = 0; l < kCoverageLevels.size(); ++l) {
      // The region of level p: r' S^-1 r <= r2, the Gaussian's -2 ln(1 - p) unless calibrated.
      const double radius2 = k < prediction.regionRadius2.size() ? prediction.regionRadius2[k][l]
                                                                  : gaussianRegionRadius2(kCoverageLevels[l]);
      errors.coverageAt[t][l] = score.mahalanobis2 <= radius2 ? 1.0 : 0.0;
    }
  }
  return errors;
}

namespace {

/// s after t0 of each calibration point of a dataset's horizon.
std::array<double, kCalibrationPoints> calibrationTimes(const vector::DatasetHeader& header) {
  std::array<double, kCalibrationPoints> times{};
  const auto steps = calibrationSteps(static_cast<std::size_t>(header.horizon));
  for (std::size_t t = 0; t < kCalibrationPoints; ++t) times[t] = header.step * static_cast<double>(steps[t] + 1);
  return times;
}

/// One evaluation reports its calibration points at one set of times.
void requireSameTimeGrid(const vector::DatasetHeader& first, const vector::DatasetHeader& header, const std::string& file) {
  if (std::abs(header.step - first.step) > 1e-9 || header.horizon != first.horizon) {
    throw DatasetError(fmt::format("{}: step {} s and horizon {} steps, expected {} s and {} steps like the first dataset",
                                   file, header.step, header.horizon, first.step, first.horizon));
  }
}

}  // namespace

Evaluation evaluate(const Predictor& predictor, const std::vector<fs::path>& data) {
  if (data.empty()) throw ConfigError("--data: no dataset given");
  Evaluation evaluation;
  evaluation.predictor = predictor.name();
  std::optional<vector::DatasetHeader> first_header;
  for (const auto& given : data) {
    for (const auto& path : vector::datasetFiles(given)) {  // a sharded sweep: every shard
      const vector::DatasetReader reader(path);
      predictor.checkCompatible(reader.header(), reader.path().string());
      if (!first_header) {
        first_header = reader.header();
        evaluation.calibrationTimes = calibrationTimes(reader.header());
      } else {
        requireSameTimeGrid(*first_header, reader.header(), reader.path().string());
      }
      // An ADE over nothing would print as 0.000 m: nothing to predict is an error.
      if (reader.size() == 0) throw DatasetError(fmt::format("{}: the dataset holds no sample", reader.path().string()));
      for (std::size_t first = 0; first < reader.size(); first += kReadChunk) {
        throwIfInterrupted();
        std::vector<vector::VectorizedScene> scenes;
        for (std::size_t i = first; i < std::min(reader.size(), first + kReadChunk); ++i) scenes.push_back(reader.scene(i));
        const auto start = std::chrono::steady_clock::now();
        const auto predictions = predictor.predictDistribution(scenes, PredictOptions{});
        evaluation.predictionSeconds += secondsSince(start);
        for (std::size_t i = 0; i < scenes.size(); ++i) {
          const auto errors = predictionErrors(predictions[i], scenes[i]);
          evaluation.perLabel[scenes[i].label].add(errors);
          evaluation.overall.add(errors);
        }
      }
    }
  }
  if (evaluation.overall.samples == 0) {
    throw DatasetError(fmt::format("no sample of {} has a valid target step: nothing to evaluate",
                                   data.size() == 1 ? data.front().string() : "the datasets"));
  }
  return evaluation;
}

namespace {

std::string timeName(double seconds) { return fmt::format("{:g}s", seconds); }

std::string calibrationTable(const Evaluation& evaluation) {
  std::string text = fmt::format(
      "  positions: NLL [nats] and share inside the predicted {:.0f} % / {:.0f} % region\n  {:<20}",
      100.0 * kCoverageLevels[0], 100.0 * kCoverageLevels[1], "functional scenario");
  for (const double t : evaluation.calibrationTimes) text += fmt::format(" {:>22}", "at " + timeName(t));
  text += "\n";
  auto row = [&](const std::string& label, const LabelErrors& errors) {
    text += fmt::format("  {:<20}", label);
    for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
      if (errors.countAt[t] == 0) {
        text += fmt::format(" {:>22}", "-");
        continue;
      }
      text += fmt::format(" {:>8.2f} {:>6.2f} / {:>4.2f}", errors.nllAt[t], errors.coverageAt[t][0], errors.coverageAt[t][1]);
    }
    text += "\n";
  };
  for (const auto& [label, errors] : evaluation.perLabel) row(label, errors);
  row("all", evaluation.overall);
  return text;
}

}  // namespace

std::string Evaluation::table() const {
  const bool probabilistic = overall.scored > 0;
  std::string text = fmt::format("  {:<20} {:>9} {:>9} {:>9}{}\n", "functional scenario", "samples", "ADE [m]", "FDE [m]",
                                 probabilistic ? fmt::format(" {:>12}", "NLL [nats]") : "");
  auto row = [&](const std::string& label, const LabelErrors& errors) {
    text += fmt::format("  {:<20} {:>9} {:>9.3f} {:>9.3f}{}\n", label, errors.samples, errors.ade, errors.fde,
                        probabilistic ? fmt::format(" {:>12.3f}", errors.nll) : "");
  };
  for (const auto& [label, errors] : perLabel) row(label, errors);
  row("all", overall);
  if (probabilistic) text += calibrationTable(*this);
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
    std::vector<std::string> header = {"label", "samples", "ade_m", "fde_m", "nll"};
    for (const double t : calibrationTimes) header.push_back("nll_" + timeName(t));
    for (const double t : calibrationTimes) {
      for (const double level : kCoverageLevels) header.push_back(fmt::format("coverage{:.0f}_{}", 100.0 * level, timeName(t)));
    }
    csv.writeRow(header);
    auto row = [&](const std::string& label, const LabelErrors& errors) {
      std::vector<std::string> cells = {label, std::to_string(errors.samples), formatNumber(errors.ade),
                                        formatNumber(errors.fde), errors.scored > 0 ? formatNumber(errors.nll) : ""};
      for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
        cells.push_back(errors.countAt[t] > 0 ? formatNumber(errors.nllAt[t]) : "");
      }
      for (std::size_t t = 0; t < kCalibrationPoints; ++t) {
        for (std::size_t l = 0; l < kCoverageLevels.size(); ++l) {
          cells.push_back(errors.countAt[t] > 0 ? formatNumber(errors.coverageAt[t][l]) : "");
        }
      }
      csv.writeRow(cells);
    };
    for (const auto& [label, errors] : perLabel) row(label, errors);
    row("all", overall);
    if (!stream) throw IoError(path.string() + ": write failed");
  }
  output.commit();
}

}  // namespace vsd::model
