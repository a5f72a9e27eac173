// `vsd-sumo bench reference`: UN R157's reference driver (and the system under test and
// the Fuzzy Safety Model) on the cut-ins whose outcome the regulation and ASAM's scenarios
// state, and on ASAM's cut-in variation grid, in the kinematic harness (no SUMO). Writes
// results/reference_driver/ (vsd/sim/reference_cases.hpp says what each file holds).

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "vsd/core/provenance.hpp"
#include "vsd/sim/reference_cases.hpp"

namespace fs = std::filesystem;

namespace vsd::cli {

void addReferenceBench(CLI::App& bench, CommandContext& context) {
  auto out = std::make_shared<fs::path>("results/reference_driver");
  auto allow_dirty = std::make_shared<bool>(false);
  CLI::App* reference = bench.add_subcommand(
      "reference", "UN R157's reference driver on the regulation's documented cut-ins and ASAM's cut-in grid");
  reference->add_option("--out", *out, "Output folder")->capture_default_str();
  reference->add_flag("--allow-dirty", *allow_dirty,
                      "Write into the repository's results/ even though this binary was built from uncommitted changes");
  reference->callback([out, allow_dirty, &context] {
    context.action = [out, allow_dirty, &context] {
      refuseDirtyCommittedResults(*out, *allow_dirty, "--allow-dirty");
      const auto registry = sim::ControllerRegistry::withBuiltins();
      std::vector<sim::CaseResult> cases;
      for (const auto& documented : sim::documentedCases()) cases.push_back(sim::runDocumentedCase(registry, documented));
      const auto grid = sim::runGrid(registry);
      // The summary names the command as users type it (the manifest keeps the full invocation).
      const std::string command = *out == "results/reference_driver" ? "vsd-sumo bench reference"
                                                                      : "vsd-sumo bench reference --out " + out->string();
      const int wrong = sim::writeReferenceReport(*out, cases, grid, command, context.commandLine);
      fmt::print("{} documented cases, {} on the wrong side; {} grid cut-ins; written to {}\n", cases.size(), wrong,
                 grid.size(), out->string());
      return wrong == 0 ? 0 : 1;
    };
  });
}

}  // namespace vsd::cli
