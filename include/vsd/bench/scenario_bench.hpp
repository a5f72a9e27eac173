#pragma once
// Benchmarks of scenarios rather than of speed alone: `bench interop` (export speed of
// `scenario export` and the netconvert round trip of the exported .xodr files), `bench
// library` (every logical scenario of a library run and checked) and `bench reference`
// (UN R157's reference driver on the regulation's documented cut-ins and ASAM's cut-in
// grid, written to results/reference_driver/).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "vsd/bench/measure.hpp"
#include "vsd/pipeline/library_check.hpp"

namespace vsd::bench {

struct InteropBenchOptions {
  std::filesystem::path scenario = kDefaultScenario;
  std::uint64_t exportSamples = 5000;
  std::uint64_t roundTripSamples = 200;
  std::uint64_t seed = 1;
};

struct InteropBenchResult {
  std::uint64_t exported = 0;       ///< concrete scenarios written as .xosc + .xodr
  double exportSeconds = 0.0;
  std::uintmax_t exportBytes = 0;   ///< of every file written
  std::vector<double> deviations;   ///< per round-trip scenario, largest lane-centre deviation (m), ascending
};

InteropBenchResult runInteropBench(const InteropBenchOptions& options);

struct LibraryBenchOptions {
  std::filesystem::path folder = "scenarios/alks";
  std::uint64_t samples = 2000;
  std::uint64_t seed = 1;
  int jobs = 1;
};

/// The logical scenarios (*.yaml) of a library folder, sorted; throws ConfigError if there are none.
std::vector<std::filesystem::path> libraryScenarios(const std::filesystem::path& folder);

/// Runs and checks each of `files`; `on_checked` is called after each.
std::vector<pipeline::LibraryScenarioCheck> runLibraryBench(
    const LibraryBenchOptions& options, const std::vector<std::filesystem::path>& files,
    const std::function<void(const std::filesystem::path&, const pipeline::LibraryScenarioCheck&)>& on_checked = {});

/// Where `bench reference` writes by default.
inline constexpr const char* kReferenceResults = "results/reference_driver";

struct ReferenceBenchResult {
  std::size_t cases = 0;  ///< documented cases
  int wrong = 0;          ///< of them on the wrong side
  std::size_t grid = 0;   ///< grid cut-ins
};

/// Runs every documented case and the grid and writes the report to `out` (refused in the
/// repository's results/ from a dirty build unless `allow_dirty`).
ReferenceBenchResult runReferenceBench(const std::filesystem::path& out, bool allow_dirty,
                                       const std::string& command_line);

}  // namespace vsd::bench
