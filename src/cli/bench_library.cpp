// `vsd-sumo bench library [folder]`: every logical scenario of a library (scenarios/alks/)
// run and checked (pipeline/library_check.hpp); the output goes into results/.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "commands.hpp"
#include "flags.hpp"
#include "vsd/core/error.hpp"
#include "vsd/pipeline/library_check.hpp"

namespace vsd::cli {

namespace {

struct LibraryBenchOptions {
  std::filesystem::path folder = "scenarios/alks";
  std::uint64_t samples = 2000;
  std::uint64_t seed = 1;
  int jobs = 1;
};

int runLibraryBench(const LibraryBenchOptions& options) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(options.folder)) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw ConfigError(fmt::format("{}: no logical scenarios (*.yaml)", options.folder.string()));
  fmt::print("bench library {}: {} scenarios, {} concrete scenarios each, seed {}, {} job(s)\n",
             options.folder.string(), files.size(), options.samples, options.seed, options.jobs);
  std::vector<pipeline::LibraryScenarioCheck> checks;
  for (const auto& file : files) {
    checks.push_back(pipeline::checkLibraryScenario(file, options.samples, options.seed, options.jobs));
    fmt::print("  {} in {:.1f} s\n", file.filename().string(), checks.back().seconds);
  }
  fmt::print("{}", pipeline::libraryReport(checks));
  return 0;
}

}  // namespace

void addLibraryBench(CLI::App& bench, CommandContext& context) {
  auto options = std::make_shared<LibraryBenchOptions>();
  CLI::App* library = bench.add_subcommand(
      "library", "Runs every scenario of a library and checks failures, road users' steps and scripted lane changes");
  library->add_option("folder", options->folder, "Folder of logical scenarios")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
  addNumber(library, "--samples", options->samples, "Concrete scenarios per logical scenario")->capture_default_str();
  addNumber(library, "--seed", options->seed, "Random seed")->capture_default_str();
  addNumber(library, "--jobs", options->jobs, "Worker processes")->capture_default_str();
  library->callback([options, &context] { context.action = [options] { return runLibraryBench(*options); }; });
}

}  // namespace vsd::cli
