// The search's output files. Each is written whole under a temporary name and
// renamed; the manifest comes last and lists every file's hash and size.

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <sstream>

#include "search_internal.hpp"
#include "vsd/core/csv.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/sim/sumo_session.hpp"

namespace fs = std::filesystem;

namespace vsd::search::detail {

namespace {

std::vector<std::string> executionHeader(const SearchContext& context) {
  std::vector<std::string> header = {"functional_scenario", "round", "origin", "sample", "seed",
                                     "acquisition", "predicted_probability", "estimate_draws", "estimate_weight",
                                     "status", "failure", "critical"};
  for (const auto& input : context.logical->inputs) header.push_back(input.name);
  header.insert(header.end(), context.metricNames.begin(), context.metricNames.end());
  return header;
}

std::vector<std::string> executionRow(const SearchContext& context, const Execution& e) {
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

fs::path writeExecutions(const SearchContext& context, const std::vector<Execution>& executions, bool critical_only,
                         const std::string& file) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow(executionHeader(context));
  for (const auto& execution : executions) {
    if (!critical_only || execution.verdict == 1) csv.writeRow(executionRow(context, execution));
  }
  const fs::path path = context.options.outputDir / file;
  writeTextFileAtomically(path, text.str());
  return path;
}

/// Critical scenarios found vs executions, one row per round.
fs::path writeLearningCurve(const SearchContext& context, const std::vector<Execution>& executions) {
  std::ostringstream text;
  CsvWriter csv(text);
  csv.writeRow({"surrogate", "round", "executions", "critical", "random_stream_executions", "random_stream_critical"});
  std::uint64_t done = 0, critical = 0, random = 0, random_critical = 0;
  for (std::size_t i = 0; i < executions.size(); ++i) {
    const auto& e = executions[i];
    ++done;
    critical += e.verdict == 1 ? 1 : 0;
    random += e.fromRandomStream() ? 1 : 0;
    random_critical += e.fromRandomStream() && e.verdict == 1 ? 1 : 0;
    if (i + 1 == executions.size() || executions[i + 1].round != e.round) {
      csv.writeRow({context.options.surrogate, std::to_string(e.round), std::to_string(done), std::to_string(critical),
                    std::to_string(random), std::to_string(random_critical)});
    }
  }
  const fs::path path = context.options.outputDir / "learning_curve.csv";
  writeTextFileAtomically(path, text.str());
  return path;
}

fs::path writeEstimate(const SearchContext& context, const SearchSummary& summary) {
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
  const fs::path path = context.options.outputDir / "estimate.json";
  writeTextFileAtomically(path, json.dump(2) + "\n");
  return path;
}

}  // namespace

std::vector<fs::path> writeSearchFiles(const SearchContext& context, const SearchSummary& summary) {
  return {writeExecutions(context, summary.executionsList, false, "concrete.csv"),
          writeExecutions(context, summary.executionsList, true, "failures.csv"),
          writeLearningCurve(context, summary.executionsList), writeEstimate(context, summary),
          context.options.outputDir / "checkpoint.json"};
}

void writeSearchManifest(const SearchContext& context, const SearchSummary& summary, const std::string& started) {
  const auto& o = context.options;
  nlohmann::json manifest;
  manifest["tool"] = "vsd-sumo";
  manifest["tool_version"] = toolVersion();
  manifest["sumo_version"] = sim::SumoSession::version();
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
  manifest["executions"] = summary.executions;
  manifest["critical"] = summary.critical;
  manifest["started"] = started;
  manifest["finished"] = utcTimestamp();
  manifest["seconds"] = summary.seconds;
  manifest["inputs"] = context.logical->inputNames();
  manifest["metrics"] = context.metricNames;
  nlohmann::json files = nlohmann::json::object();
  for (const auto& path : summary.outputs) {
    files[fs::relative(path, o.outputDir).string()] = {{"sha256", sha256OfFile(path)}, {"bytes", fs::file_size(path)}};
  }
  manifest["outputs"] = files;
  writeTextFileAtomically(o.outputDir / "manifest.json", manifest.dump(2) + "\n");
}

}  // namespace vsd::search::detail
