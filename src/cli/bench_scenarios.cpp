// `vsd-sumo bench interop`, `bench library` and `bench reference`: flags and printing of
// the scenario benchmarks (vsd/bench/scenario_bench.hpp).

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/bench/scenario_bench.hpp"
#include "vsd/core/statistics.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

namespace {

int printInteropBench(const bench::InteropBenchOptions& options) {
  fmt::print("{} (seed {})\n", options.scenario.string(), options.seed);
  const auto result = bench::runInteropBench(options);
  const auto exported = static_cast<double>(result.exported);
  fmt::print("  export (scenario export, .xosc + .xodr each):\n");
  fmt::print("    {:>8} scenarios in {:.2f} s = {:.0f} scenarios/s, {:.1f} KiB per scenario\n", result.exported,
             result.exportSeconds, exported / result.exportSeconds,
             static_cast<double>(result.exportBytes) / 1024.0 / exported);
  const auto& values = result.deviations;
  fmt::print("  netconvert round trip (exported .xodr -> netconvert vs the generated network), lane centres:\n");
  fmt::print("    {:>8} scenarios: max deviation {:.4f} m, median {:.4f} m (target <= 0.05 m)\n", values.size(),
             values.back(), upperMedian(values));
  return 0;
}

int printLibraryBench(const bench::LibraryBenchOptions& options) {
  const auto files = bench::libraryScenarios(options.folder);
  fmt::print("bench library {}: {} scenarios, {} concrete scenarios each, seed {}, {} job(s)\n",
             options.folder.string(), files.size(), options.samples, options.seed, options.jobs);
  const auto checks =
      bench::runLibraryBench(options, files, [](const fs::path& file, const pipeline::LibraryScenarioCheck& check) {
        fmt::print("  {} in {:.1f} s\n", file.filename().string(), check.seconds);
      });
  fmt::print("{}", pipeline::libraryReport(checks));
  return 0;
}

}  // namespace

void addInteropBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::InteropBenchOptions>();
  CLI::App* interop = bench.add_subcommand("interop", "Export speed and netconvert round trip of OpenDRIVE/OpenSCENARIO");
  interop->add_option("scenario", options->scenario, "Logical scenario")->check(CLI::ExistingFile)->capture_default_str();
  addNumber(interop, "--export-samples", options->exportSamples, "Concrete scenarios to export")->capture_default_str();
  addNumber(interop, "--round-trip-samples", options->roundTripSamples, "Concrete scenarios for the netconvert round trip")
      ->capture_default_str();
  addNumber(interop, "--seed", options->seed, "Random seed")->capture_default_str();
  interop->callback([options, &context] { context.action = [options] { return printInteropBench(*options); }; });
}

void addLibraryBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<bench::LibraryBenchOptions>();
  CLI::App* library = bench.add_subcommand(
      "library", "Runs every scenario of a library and checks failures, road users' steps and scripted lane changes");
  library->add_option("folder", options->folder, "Folder of logical scenarios")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
  addNumber(library, "--samples", options->samples, "Concrete scenarios per logical scenario")->capture_default_str();
  addNumber(library, "--seed", options->seed, "Random seed")->capture_default_str();
  addNumber(library, "--jobs", options->jobs, "Worker processes")->capture_default_str();
  library->callback([options, &context] { context.action = [options] { return printLibraryBench(*options); }; });
}

void addReferenceBench(CLI::App& bench, CommandContext& context) {
  auto out = std::make_shared<fs::path>(bench::kReferenceResults);
  auto allow_dirty = std::make_shared<bool>(false);
  CLI::App* reference = bench.add_subcommand(
      "reference", "UN R157's reference driver on the regulation's documented cut-ins and ASAM's cut-in grid");
  reference->add_option("--out", *out, "Output folder")->capture_default_str();
  addAllowDirtyFlag(*reference, *allow_dirty);
  reference->callback([out, allow_dirty, &context] {
    context.action = [out, allow_dirty, &context] {
      const auto result = bench::runReferenceBench(*out, *allow_dirty, context.commandLine);
      fmt::print("{} documented cases, {} on the wrong side; {} grid cut-ins; written to {}\n", result.cases,
                 result.wrong, result.grid, out->string());
      return result.wrong == 0 ? 0 : 1;
    };
  });
}

}  // namespace vsd::cli
