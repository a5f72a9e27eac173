// `vsd-sumo bench interop`, `bench import`, `bench library` and `bench reference`: flags and
// printing of the scenario benchmarks (vsd/bench/scenario_bench.hpp, interop for import).

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/bench/scenario_bench.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/statistics.hpp"
#include "vsd/interop/openscenario_import.hpp"

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

/// Issue 24's target: the import overhead per concrete scenario of a sweep (ms).
constexpr double kImportTargetMs = 20.0;

int printImportBench(const fs::path& file, const interop::OscImportOptions& import, std::uint64_t seed) {
  if (import.network) {
    throw ConfigError("command line: --network: bench import times the scenario language's import of a sweep "
                      "(a network scenario is one concrete scenario)");
  }
  const auto timing = interop::timeSweepImport(file, import, seed);
  fmt::print("vsd-sumo bench import: {} (seed {}), vsd-sumo {}\n", file.string(), seed, toolVersion());
  const auto& counts = timing.counts;
  fmt::print("  parameter sets: {} in the grid, {} skipped by the template's constraints, {} failed (refused by the "
             "import or road users that cannot start), {} would run\n",
             counts.sets, counts.skipped, counts.refused, counts.simulated);
  fmt::print("  grid read:                          {:9.3f} s\n", timing.gridSeconds);
  fmt::print("  every set imported and checked:     {:9.3f} s = {:.3f} ms per set\n", timing.acceptSeconds,
             1000.0 * timing.acceptSeconds / static_cast<double>(counts.sets));
  fmt::print("  every set run imported and sampled: {:9.3f} s = {:.3f} ms per set\n", timing.sampleSeconds,
             1000.0 * timing.sampleSeconds / static_cast<double>(counts.simulated));
  const double per_set = timing.millisecondsPerSet();
  fmt::print("  import overhead per concrete scenario: {:.3f} ms (target <= {:.0f} ms: {})\n", per_set, kImportTargetMs,
             per_set <= kImportTargetMs ? "met" : "not met");
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

void addImportBench(CLI::App& bench, CommandContext& context) {
  auto file = std::make_shared<fs::path>();
  auto import = std::make_shared<interop::OscImportOptions>();
  auto seed = std::make_shared<std::uint64_t>(1);
  CLI::App* command = bench.add_subcommand(
      "import", "Import overhead of an OpenSCENARIO sweep without its simulation (ms per concrete scenario)");
  command->add_option("variation", *file, "ParameterValueDistribution file (.xosc)")->required()->check(CLI::ExistingFile);
  addNumber(command, "--seed", *seed, "Random seed (as run --seed)")->capture_default_str();
  addImportOptions(*command, *import);
  command->callback([file, import, seed, &context] {
    context.action = [file, import, seed] { return printImportBench(*file, *import, *seed); };
  });
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
