#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "vsd/baseline/baseline.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/metrics/metrics.hpp"

namespace fs = std::filesystem;

namespace vsd::baseline {

fs::path concreteTableOf(const fs::path& run) {
  if (fs::is_directory(run)) {
    requireCompleteOutputFolder(run, /*hashes=*/false);  // as every reader of a run folder
    return run / "concrete.csv";
  }
  std::ifstream stream(run, std::ios::binary);
  std::string head(8, '\0');
  stream.read(head.data(), 8);
  if (stream.gcount() == 8 && head == std::string("\x89HDF\r\n\x1a\n", 8)) {
    throw DatasetError(fmt::format("{}: an HDF5 file (a dataset or traces); baseline learns from the concrete inputs "
                                   "of a run: give the run folder (e.g. out/acc), which holds concrete.csv",
                                   run.string()));
  }
  return run;
}

std::string functionalScenarioOf(const fs::path& csv_or_run) {
  const auto csv = CsvTable::read(concreteTableOf(csv_or_run));
  return csv.rows() > 0 ? csv.cell(0, csv.column("functional_scenario")) : std::string();
}

MetricTable readMetricTable(const fs::path& csv_or_run, const std::vector<std::string>& targets,
                            const std::vector<std::string>& inputs) {
  const fs::path path = concreteTableOf(csv_or_run);
  const auto csv = CsvTable::read(path);
  if (targets.empty()) throw ConfigError("--targets: no metric given");
  for (const auto& target : targets) {
    metrics::metric(target, "--targets");  // throws for an unknown name, listing the known ones
    if (!csv.findColumn(target)) {
      throw DatasetError(fmt::format("{}: no column '{}' (the scenario did not compute this metric; columns: {})",
                                     path.string(), target, fmt::join(csv.header(), ", ")));
    }
  }
  static const std::set<std::string> kBookkeeping = {"functional_scenario", "sample", "seed", "status", "failure"};
  for (const auto& column : kBookkeeping) csv.column(column);  // a CSV of vsd-sumo run has them all

  MetricTable table;
  table.path = path;
  table.targetNames = targets;
  if (inputs.empty()) {
    for (const auto& column : csv.header()) {
      if (!kBookkeeping.count(column) && !metrics::findMetric(column)) table.inputNames.push_back(column);
    }
  } else {
    for (const auto& input : inputs) csv.column(input);
    table.inputNames = inputs;
  }
  if (table.inputNames.empty()) throw DatasetError(fmt::format("{}: no input column", path.string()));

  const auto scenario_column = csv.column("functional_scenario");
  const auto status_column = csv.column("status");
  const auto sample_column = csv.column("sample");
  std::vector<std::size_t> input_columns;
  std::vector<std::size_t> target_columns;
  for (const auto& name : table.inputNames) input_columns.push_back(csv.column(name));
  for (const auto& name : targets) target_columns.push_back(csv.column(name));
  std::vector<std::size_t> rows;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    const auto& scenario = csv.cell(r, scenario_column);
    if (table.functionalScenario.empty()) table.functionalScenario = scenario;
    if (scenario != table.functionalScenario) {
      throw DatasetError(fmt::format("{}: rows of functional scenarios '{}' and '{}' in one table", path.string(),
                                     table.functionalScenario, scenario));
    }
    bool usable = csv.cell(r, status_column) == "ok";
    for (auto c : target_columns) usable = usable && std::isfinite(csv.number(r, c));
    if (usable) rows.push_back(r);
    else ++table.skipped;
  }
  if (rows.empty()) throw DatasetError(fmt::format("{}: no completed run with finite targets", path.string()));
  table.inputs.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(input_columns.size()));
  table.targets.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(target_columns.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t c = 0; c < input_columns.size(); ++c) {
      table.inputs(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) = csv.number(rows[i], input_columns[c]);
    }
    for (std::size_t c = 0; c < target_columns.size(); ++c) {
      table.targets(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) = csv.number(rows[i], target_columns[c]);
    }
    table.samples.push_back(static_cast<std::uint64_t>(csv.number(rows[i], sample_column)));
  }
  return table;
}

}  // namespace vsd::baseline
