#include "vsd/bench/scenario_bench.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/interop/openscenario_export.hpp"
#include "vsd/interop/roundtrip.hpp"
#include "vsd/scenario/concrete_scenario.hpp"
#include "vsd/sim/reference_cases.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

void benchExport(const InteropBenchOptions& options, const fs::path& work, InteropBenchResult& result) {
  interop::ScenarioExportOptions export_options;
  export_options.input = options.scenario;
  export_options.outputDir = work / "export";
  export_options.samples = options.exportSamples;
  export_options.seed = options.seed;
  const auto summary = interop::exportScenarios(export_options);
  for (const auto& entry : fs::directory_iterator(summary.outputDir)) result.exportBytes += entry.file_size();
  result.exported = summary.exported;
  result.exportSeconds = summary.seconds;
}

void benchRoundTrip(const InteropBenchOptions& options, const fs::path& work, InteropBenchResult& result) {
  const auto logical = scenario::loadLogicalScenario(options.scenario);
  std::vector<scenario::ConcreteScenario> scenarios;
  for (std::uint64_t index = 0; index < options.roundTripSamples; ++index) {
    scenarios.push_back(scenario::sampleConcreteScenario(logical, options.seed, index));
  }
  const fs::path round_trip = work / "netconvert";
  ensureDirectory(round_trip);
  for (const auto& deviation : interop::netconvertRoundTrip(scenarios, round_trip)) {
    result.deviations.push_back(deviation.maxDeviation);
  }
  std::sort(result.deviations.begin(), result.deviations.end());
}

}  // namespace

InteropBenchResult runInteropBench(const InteropBenchOptions& options) {
  TemporaryDirectory work("vsd-bench-interop");
  InteropBenchResult result;
  benchExport(options, work.path(), result);
  benchRoundTrip(options, work.path(), result);
  return result;
}

std::vector<fs::path> libraryScenarios(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw ConfigError(fmt::format("{}: no logical scenarios (*.yaml)", folder.string()));
  return files;
}

std::vector<pipeline::LibraryScenarioCheck> runLibraryBench(
    const LibraryBenchOptions& options, const std::vector<fs::path>& files,
    const std::function<void(const fs::path&, const pipeline::LibraryScenarioCheck&)>& on_checked) {
  std::vector<pipeline::LibraryScenarioCheck> checks;
  for (const auto& file : files) {
    checks.push_back(pipeline::checkLibraryScenario(file, options.samples, options.seed, options.jobs));
    if (on_checked) on_checked(file, checks.back());
  }
  return checks;
}

ReferenceBenchResult runReferenceBench(const fs::path& out, bool allow_dirty, const std::string& command_line) {
  refuseDirtyCommittedResults(out, allow_dirty, "--allow-dirty");
  const auto registry = sim::ControllerRegistry::withBuiltins();
  std::vector<sim::CaseResult> cases;
  for (const auto& documented : sim::documentedCases()) cases.push_back(sim::runDocumentedCase(registry, documented));
  const auto grid = sim::runGrid(registry);
  // The summary names the command as users type it (the manifest keeps the full invocation).
  const std::string command =
      out == kReferenceResults ? "vsd-sumo bench reference" : "vsd-sumo bench reference --out " + out.string();
  const int wrong = sim::writeReferenceReport(out, cases, grid, command, command_line);
  return {cases.size(), wrong, grid.size()};
}

}  // namespace vsd::bench
