#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>

#include "vsd/baseline/baseline.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/metrics/metrics.hpp"

namespace vsd::baseline {

namespace {

/// One forest per target column. A multi-output forest picks every split by the summed
/// variance decrease of all outputs, so the metric with the largest variance decides for
/// all (measured on ACC: a_min MAE 0.42 m/s^2 fitted jointly with d_min, 0.27 alone).
std::vector<ExtraTrees> fitPerTarget(const ExtraTreesOptions& options, const Matrix& x, const Matrix& y) {
  std::vector<ExtraTrees> forests;
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    forests.emplace_back(options);
    forests.back().fit(x, y.col(c));
  }
  return forests;
}

Matrix predictPerTarget(const std::vector<ExtraTrees>& forests, const Matrix& x) {
  Matrix predicted(x.rows(), static_cast<Eigen::Index>(forests.size()));
  for (std::size_t c = 0; c < forests.size(); ++c) predicted.col(static_cast<Eigen::Index>(c)) = forests[c].predict(x);
  return predicted;
}

}  // namespace

namespace {

/// Predicted means (and, for probabilistic models, standard deviations) of the test rows.
struct Predicted {
  Matrix mean;
  Matrix std;  ///< empty for point predictors
};

Predicted fitExtraTrees(const BaselineOptions& options, const MetricTable& train, const MetricTable& test,
                        BaselineReport& report) {
  const auto start = std::chrono::steady_clock::now();
  const auto forests = fitPerTarget(options.extraTrees, train.inputs, train.targets);
  report.fitSeconds = secondsSince(start);
  const auto predict_start = std::chrono::steady_clock::now();
  Predicted predicted{predictPerTarget(forests, test.inputs), Matrix()};
  report.predictSeconds = secondsSince(predict_start);
  return predicted;
}

Predicted fitBnn(const BaselineOptions& options, const MetricTable& train, const MetricTable& test,
                 BaselineReport& report) {
  const auto start = std::chrono::steady_clock::now();
  BayesianNetwork bnn(options.bnn);
  bnn.fit(train.inputs, train.targets);
  report.fitSeconds = secondsSince(start);
  const auto predict_start = std::chrono::steady_clock::now();
  auto prediction = bnn.predict(test.inputs);
  report.predictSeconds = secondsSince(predict_start);
  return {std::move(prediction.mean), std::move(prediction.std)};
}

/// One entry per baseline model: its names, its title in reports and how it fits and predicts.
struct BaselineModelEntry {
  BaselineModel model;
  std::function<Predicted(const BaselineOptions&, const MetricTable&, const MetricTable&, BaselineReport&)> fitAndPredict;
};

const std::vector<BaselineModelEntry>& modelRegistry() {
  static const std::vector<BaselineModelEntry> kEntries = {
      {{"extra-trees", {"et"}, "extra trees"}, fitExtraTrees},
      {{"bnn", {}, "Bayesian neural network"}, fitBnn},
  };
  return kEntries;
}

const BaselineModelEntry& modelEntry(const std::string& name) {
  for (const auto& entry : modelRegistry()) {
    const auto& old = entry.model.oldNames;
    if (entry.model.name == name || std::find(old.begin(), old.end(), name) != old.end()) return entry;
  }
  std::vector<std::string> known;
  for (const auto& entry : modelRegistry()) known.push_back(entry.model.name);
  throw ConfigError::field("command line", "--model", name, fmt::format("{}", fmt::join(known, " or ")));
}

}  // namespace

std::vector<BaselineModel> baselineModels() {
  std::vector<BaselineModel> models;
  for (const auto& entry : modelRegistry()) models.push_back(entry.model);
  return models;
}

BaselineReport runBaseline(const BaselineOptions& options) {
  const auto& entry = modelEntry(options.model);
  if (!options.predictionsCsv.empty()) requireFileOutputPath(options.predictionsCsv, "--out");
  options.extraTrees.validate();
  options.bnn.validate();
  auto train = readMetricTable(options.train, options.targets, options.inputs);
  // The functional scenario first: another scenario's table also lacks the inputs, but
  // "another functional scenario" is what the user needs to hear.
  const auto test_scenario = functionalScenarioOf(options.test);
  if (test_scenario != train.functionalScenario) {
    throw DatasetError(fmt::format("{}: the test set is functional scenario '{}', the training set {} is '{}'",
                                   options.test.string(), test_scenario, train.path.string(), train.functionalScenario));
  }
  const auto test = readMetricTable(options.test, options.targets, train.inputNames);
  if (options.maxTrainRows > 0 && static_cast<std::size_t>(train.inputs.rows()) > options.maxTrainRows) {
    const auto n = static_cast<Eigen::Index>(options.maxTrainRows);
    train.inputs = Matrix(train.inputs.topRows(n));
    train.targets = Matrix(train.targets.topRows(n));
  }
  BaselineReport report;
  report.model = entry.model.name;
  report.modelTitle = entry.model.title;
  report.functionalScenario = train.functionalScenario;
  report.trainRows = static_cast<std::size_t>(train.inputs.rows());
  report.testRows = static_cast<std::size_t>(test.inputs.rows());
  report.skipped = train.skipped + test.skipped;
  report.targets = options.targets;
  for (const auto& target : options.targets) report.units.push_back(metrics::metric(target, "--targets").unit);

  auto [mean, std] = entry.fitAndPredict(options, train, test, report);
  for (Eigen::Index c = 0; c < std.cols(); ++c) report.meanStd.push_back(std.col(c).mean());
  report.mae = meanAbsoluteError(mean, test.targets);

  if (!options.predictionsCsv.empty()) {
    AtomicOutput output(options.predictionsCsv);
    {
      std::ofstream stream(output.tempPath());
      CsvWriter csv(stream);
      std::vector<std::string> header = {"sample"};
      for (std::size_t t = 0; t < options.targets.size(); ++t) {
        const auto& target = options.targets[t];
        const auto& unit = report.units[t];
        header.insert(header.end(), {columnWithUnit(target, unit), columnWithUnit(target + "_predicted", unit)});
        if (std.size() > 0) header.push_back(columnWithUnit(target + "_std", unit));
      }
      csv.writeRow(header);
      for (Eigen::Index r = 0; r < mean.rows(); ++r) {
        std::vector<std::string> row = {std::to_string(test.samples[static_cast<std::size_t>(r)])};
        for (Eigen::Index c = 0; c < mean.cols(); ++c) {
          row.push_back(formatNumber(test.targets(r, c)));
          row.push_back(formatNumber(mean(r, c)));
          if (std.size() > 0) row.push_back(formatNumber(std(r, c)));
        }
        csv.writeRow(row);
      }
      if (!stream) throw IoError(options.predictionsCsv.string() + ": write failed");
    }
    output.commit();
  }
  return report;
}

std::string BaselineReport::report() const {
  std::string text = fmt::format(
      "{} on {}: {} training rows, {} test rows ({} failed or non-finite rows left out); fit {:.2f} s, predict {:.2f} s\n",
      modelTitle, functionalScenario, trainRows, testRows, skipped,
      fitSeconds, predictSeconds);
  text += fmt::format("  {:<16} {:>10}{}  {}\n", "metric", "MAE", meanStd.empty() ? "" : "   mean std", "unit");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    text += fmt::format("  {:<16} {:>10.4f}{}  {}\n", targets[i], mae[i],
                        meanStd.empty() ? std::string() : fmt::format(" {:>10.4f}", meanStd[i]), units[i]);
  }
  return text;
}

}  // namespace vsd::baseline
