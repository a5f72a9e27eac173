// The search's output folder (core/files.hpp: OutputFolder): every file is staged and
// the set is committed with its manifest at the end; traces.h5 and dataset.h5 are
// joined from the rounds' files in <out>/.rounds/ (written as `run` writes them).

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <map>
#include <sstream>

#include "search_internal.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/pipeline/outcome_files.hpp"
#include "vsd/pipeline/provenance.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/report/search_report.hpp"

namespace fs = std::filesystem;

namespace vsd::search {

namespace {

std::vector<std::string> executionHeader(const detail::SearchContext& context) {
  std::vector<std::string> header = {"functional_scenario", "round", "origin", "sample", "seed",
                                     "acquisition", "predicted_probability", "estimate_draws", "estimate_weight",
                                     "status", "failure", "critical"};
  for (const auto& input : context.logical->inputs) header.push_back(input.name);
  header.insert(header.end(), context.columnNames.begin(), context.columnNames.end());
  return header;
}

std::vector<std::string> executionRow(const detail::SearchContext& context, const Execution& e) {
  std::vector<std::string> row = {context.logical->name,
                                  std::to_string(e.round),
                                  e.origin,
                                  std::to_string(e.sample),
                                  std::to_string(context.options.seed),
                                  formatNumber(e.acquisition),
                                  formatNumber(e.predicted),
                                  std::to_string(e.draws),
                                  e.draws == 0 ? std::string() : formatNumber(e.weight),
                                  e.failure.empty() ? "ok" : "failed",
                                  e.failure,
                                  e.verdict < 0 ? "" : std::to_string(e.verdict)};
  for (const double value : e.inputs) row.push_back(formatNumber(value));
  for (const double value : e.metrics) row.push_back(formatNumber(value));
  return row;
}

std::string executionsCsv(const detail::SearchContext& context, const std::vector<Execution>& executions,
                          bool critical_only) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow(executionHeader(context));
  for (const auto& execution : executions) {
    if (!critical_only || execution.verdict == 1) csv.writeRow(executionRow(context, execution));
  }
  return text.str();
}

/// Critical scenarios found, and the cells they cover, vs executions: one row per round.
std::string learningCurveCsv(const detail::SearchContext& context, const std::vector<Execution>& executions) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow({"surrogate", "round", "executions", "critical", "coverage_cells", "random_stream_executions",
                "random_stream_critical"});
  std::uint64_t critical = 0, random = 0, random_critical = 0;
  for (std::size_t i = 0; i < executions.size(); ++i) {
    const auto& e = executions[i];
    critical += e.verdict == 1 ? 1 : 0;
    random += e.fromRandomStream() ? 1 : 0;
    random_critical += e.fromRandomStream() && e.verdict == 1 ? 1 : 0;
    if (i + 1 == executions.size() || executions[i + 1].round != e.round) {
      csv.writeRow({context.options.surrogate, std::to_string(e.round), std::to_string(i + 1),
                    std::to_string(critical), std::to_string(detail::coverageCells(context, executions, i + 1)),
                    std::to_string(random), std::to_string(random_critical)});
    }
  }
  return text.str();
}

/// Failure-region coverage: every cell (thirds of each normalised input's range) that
/// holds a critical scenario, with the executions and critical scenarios in it.
std::string coverageCsv(const detail::SearchContext& context, const std::vector<Execution>& executions) {
  std::map<std::vector<int>, std::pair<std::uint64_t, std::uint64_t>> cells;  // cell -> executions, critical
  for (const auto& execution : executions) {
    if (execution.inputs.empty()) continue;
    auto& counts = cells[detail::coverageCell(context, execution)];
    ++counts.first;
    counts.second += execution.verdict == 1 ? 1 : 0;
  }
  std::ostringstream text;
  CsvWriter csv(text);
  std::vector<std::string> header;
  for (const auto& input : context.logical->inputs) header.push_back(input.name + "_bin");
  header.insert(header.end(), {"executions", "critical"});
  csv.writeRow(header);
  for (const auto& [cell, counts] : cells) {
    if (counts.second == 0) continue;
    std::vector<std::string> row;
    for (const int bin : cell) row.push_back(std::to_string(bin));
    row.push_back(std::to_string(counts.first));
    row.push_back(std::to_string(counts.second));
    csv.writeRow(row);
  }
  return text.str();
}

std::string estimateJson(const detail::SearchContext& context, const SearchSummary& summary) {
  const auto& e = summary.estimate;
  nlohmann::json json = {{"criterion", summary.criterion},
                         {"expression", summary.expression},
                         {"surrogate", summary.surrogate},
                         {"budget", context.options.budget},
                         {"executions", summary.executions},
                         {"critical", summary.critical},
                         {"coverage_cells", summary.coverageCells},
                         {"method", e.method},
                         {"draws", e.draws},
                         {"estimate", e.estimate},
                         {"low", e.low},
                         {"high", e.high},
                         {"confidence", 0.95},
                         {"random_stream_executions", e.randomExecutions},
                         {"random_stream_critical", e.randomCritical},
                         {"random_stream_estimate", e.randomEstimate},
                         {"random_stream_low", e.randomLow},
                         {"random_stream_high", e.randomHigh},
                         {"same_budget_random_width", e.sameBudgetRandomWidth}};
  return json.dump(2) + "\n";
}

nlohmann::json searchManifest(const detail::SearchContext& context, const SearchSummary& summary,
                              const std::string& started) {
  const auto& o = context.options;
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  pipeline::provenance().addTo(manifest);
  manifest["command"] = "search";
  manifest["command_line"] = o.commandLine;
  manifest["scenario_file"] = context.logical->sourceFile.string();
  manifest["scenario_sha256"] = context.scenarioSha256;
  manifest["functional_scenario"] = context.logical->name;
  manifest["seed"] = o.seed;
  manifest["criterion"] = summary.criterion;
  manifest["expression"] = summary.expression;
  manifest["surrogate"] = o.surrogate;
  manifest["budget"] = o.budget;
  if (!o.reference.empty()) {
    manifest["reference"] = o.reference;
    manifest["simulations_per_execution"] = o.simulationsPerExecution();
  }
  manifest["executions"] = summary.executions;
  manifest["critical"] = summary.critical;
  manifest["failed"] = summary.failedRuns;
  manifest["started"] = started;
  manifest["finished"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["inputs"] = context.logical->inputNames();
  manifest["metrics"] = context.columnNames;
  return manifest;
}

}  // namespace

std::vector<fs::path> detail::roundFiles(const SearchContext& context, std::uint64_t rounds, const std::string& file) {
  std::vector<fs::path> files;
  for (std::uint64_t round = 0; round < rounds; ++round) {
    files.push_back(detail::roundFile(context, round, file));
    if (!fs::exists(files.back())) {
      throw DatasetError(fmt::format("{}: missing: the checkpoint lists round {} but its executions' {} are gone "
                                     "(start the search in a new --out folder)",
                                     files.back().string(), round, file));
    }
  }
  return files;
}

namespace {

void stageRoundData(const detail::SearchContext& context, OutputFolder& folder, const SearchSummary& summary) {
  pipeline::concatenateTraces(detail::roundFiles(context, summary.rounds, "traces.h5"), folder.stage("traces.h5"));
  folder.staged("traces.h5");
  pipeline::concatenateDatasets(detail::roundFiles(context, summary.rounds, "dataset.h5"), folder.stage("dataset.h5"),
                                pipeline::RunOptions{}.compression);
  folder.staged("dataset.h5");
}

std::vector<std::pair<std::string, std::string>> provenance(const detail::SearchContext& context) {
  const auto versions = pipeline::provenance();
  return {{"scenario", context.logical->sourceFile.string()},
          {"scenario SHA-256", context.scenarioSha256},
          {"seed", std::to_string(context.options.seed)},
          {"vsd-sumo", versions.toolVersion},
          {"SUMO", versions.sumoVersion},
          {"command line", context.options.commandLine}};
}

}  // namespace

std::string searchReportHtml(const std::vector<const SearchSummary*>& searches,
                             const std::vector<std::pair<std::string, std::string>>& provenance) {
  report::SearchReport report;
  if (searches.empty()) return report::renderSearchReport(report);
  const auto& first = *searches.front();
  report.title = fmt::format("{}: {}", first.functionalScenario,
                             first.criterion == first.expression ? first.expression
                                                                 : first.criterion + " (" + first.expression + ")");
  report.provenance = provenance;
  for (const auto* search : searches) {
    const std::string name = fmt::format("{} (seed {})", search->surrogate, search->seed);
    report.summary.push_back(fmt::format("{}: {} critical in {} executions ({} input cells), {:.1f} s", name,
                                         search->critical, search->executions, search->coverageCells,
                                         search->seconds));
    report::LearningCurve curve{name, {{0.0, 0.0}}};
    std::uint64_t critical = 0;
    const auto& list = search->executionsList;
    for (std::size_t i = 0; i < list.size(); ++i) {
      critical += list[i].verdict == 1 ? 1 : 0;
      if (i + 1 == list.size() || list[i + 1].round != list[i].round) {
        curve.points.emplace_back(static_cast<double>(i + 1), static_cast<double>(critical));
      }
    }
    report.curves.push_back(std::move(curve));
    const auto& e = search->estimate;
    report.rates.push_back({name, e.method == "monte-carlo" ? "monte-carlo (Wilson interval)" : e.method,
                            search->executions, e.estimate, e.low, e.high});
    if (e.method != "monte-carlo") {
      report.rates.push_back({name + ": its random-stream executions alone", "monte-carlo (Wilson interval)",
                              e.randomExecutions, e.randomEstimate, e.randomLow, e.randomHigh});
    }
  }
  return report::renderSearchReport(report);
}

void discardSearchState(const fs::path& folder) {
  std::error_code ignored;
  // The old search's outputs go first: a search resumes from whatever its folder holds.
  for (const auto& [name, entry] : readManifestOutputs(folder)) fs::remove(folder / name, ignored);
  fs::remove(folder / "manifest.json", ignored);
  fs::remove(folder / "checkpoint.json", ignored);  // as checkpoint.cpp names it
  fs::remove_all(folder / ".rounds", ignored);      // as roundFile() names them
}

fs::path detail::roundFile(const SearchContext& context, std::uint64_t round, const std::string& file) {
  return context.options.outputDir / ".rounds" / fmt::format("round-{:05d}.{}", round, file);
}

std::vector<fs::path> detail::commitSearchFolder(const SearchContext& context, OutputFolder& folder,
                                                 const SearchSummary& summary, const std::string& started) {
  const auto& executions = summary.executionsList;
  folder.stageText("concrete.csv", executionsCsv(context, executions, false));
  folder.stageText("failures.csv", executionsCsv(context, executions, true));
  folder.stageText("learning_curve.csv", learningCurveCsv(context, executions));
  folder.stageText("coverage.csv", coverageCsv(context, executions));
  folder.stageText("estimate.json", estimateJson(context, summary));
  folder.stageText("report.html", searchReportHtml({&summary}, provenance(context)));
  stageRoundData(context, folder, summary);
  return folder.commit(searchManifest(context, summary, started));
}

}  // namespace vsd::search
