// `vsd-sumo bench interop`: export speed of `scenario export` (.xosc + .xodr per
// concrete scenario) and the deviation of the lanes SUMO's netconvert builds from the
// exported .xodr files from the network vsd-sumo generates for the same scenarios.

#include <fmt/format.h>

#include <algorithm>
#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/files.hpp"
#include "vsd/interop/export.hpp"
#include "vsd/interop/roundtrip.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

struct InteropBenchOptions {
  fs::path scenario = "scenarios/acc_lk.yaml";
  std::uint64_t exportSamples = 5000;
  std::uint64_t roundTripSamples = 200;
  std::uint64_t seed = 1;
};

void benchExport(const InteropBenchOptions& options, const fs::path& work) {
  interop::ScenarioExportOptions export_options;
  export_options.input = options.scenario;
  export_options.outputDir = work / "export";
  export_options.samples = options.exportSamples;
  export_options.seed = options.seed;
  const auto summary = interop::exportScenarios(export_options);
  std::uintmax_t bytes = 0;
  for (const auto& entry : fs::directory_iterator(summary.outputDir)) bytes += entry.file_size();
  fmt::print("  export (scenario export, .xosc + .xodr each):\n");
  fmt::print("    {:>8} scenarios in {:.2f} s = {:.0f} scenarios/s, {:.1f} KiB per scenario\n", summary.exported,
             summary.seconds, static_cast<double>(summary.exported) / summary.seconds,
             static_cast<double>(bytes) / 1024.0 / static_cast<double>(summary.exported));
}

void benchRoundTrip(const InteropBenchOptions& options, const fs::path& work) {
  const auto logical = scenario::loadLogicalScenario(options.scenario);
  std::vector<scenario::ConcreteScenario> scenarios;
  for (std::uint64_t index = 0; index < options.roundTripSamples; ++index) {
    scenarios.push_back(scenario::sampleConcreteScenario(logical, options.seed, index));
  }
  const fs::path round_trip = work / "netconvert";
  ensureDirectory(round_trip);
  const auto deviations = interop::netconvertRoundTrip(scenarios, round_trip);
  std::vector<double> values;
  for (const auto& deviation : deviations) values.push_back(deviation.maxDeviation);
  std::sort(values.begin(), values.end());
  fmt::print("  netconvert round trip (exported .xodr -> netconvert vs the generated network), lane centres:\n");
  fmt::print("    {:>8} scenarios: max deviation {:.4f} m, median {:.4f} m (target <= 0.05 m)\n", values.size(),
             values.back(), values[values.size() / 2]);
}

}  // namespace

void addInteropBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<InteropBenchOptions>();
  CLI::App* interop = bench.add_subcommand("interop", "Export speed and netconvert round trip of OpenDRIVE/OpenSCENARIO");
  interop->add_option("scenario", options->scenario, "Logical scenario")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(interop, "--export-samples", options->exportSamples, "Concrete scenarios to export")->capture_default_str();
  addNumber(interop, "--round-trip-samples", options->roundTripSamples, "Concrete scenarios for the netconvert round trip")
      ->capture_default_str();
  addNumber(interop, "--seed", options->seed, "Random seed")->capture_default_str();
  interop->callback([options, &context] {
    context.action = [options] {
      TemporaryDirectory work("vsd-bench-interop");
      fmt::print("{} (seed {})\n", options->scenario.string(), options->seed);
      benchExport(*options, work.path());
      benchRoundTrip(*options, work.path());
      return 0;
    };
  });
}

}  // namespace vsd::cli
