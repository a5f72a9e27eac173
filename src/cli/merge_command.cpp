#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "vsd/core/output_policy.hpp"
#include "vsd/run_folder/shards.hpp"
#include "vsd/pipeline/merge.hpp"

namespace vsd::cli {

void addMergeCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<pipeline::MergeOptions>();
  CLI::App* merge = app.add_subcommand(
      "merge", "Join the shards of a sweep (run --shard K/N, or mpirun) into one run folder: the same concrete.csv, "
               "traces.h5 and dataset.h5 as one unsharded run");
  merge->add_option("sweep", options->sweep, "Sweep folder (the --out of the shards; holds shards/)")
      ->required()
      ->check(CLI::ExistingDirectory);
  merge->add_option("-o,--out", options->output, "Output folder (default: the sweep folder)");
  merge->add_flag("--remove-shards", options->removeShards, "Delete the shard folders after a successful merge");
  auto force = std::make_shared<bool>(false);
  merge->add_flag("--force", *force, "Replace a run folder of another functional scenario (docs/output-policy.md)");
  merge->callback([options, force, &context] {
    context.action = [options, force, &context] {
      options->commandLine = context.commandLine;
      // The merged folder is a run folder of the shards' scenario; the shards are its inputs.
      const auto shards = readShardSet(options->sweep);
      std::vector<std::pair<std::string, std::filesystem::path>> inputs;
      for (const auto& shard : shards) inputs.emplace_back("sweep", shard.folder);
      checkOutput({options->output.empty() ? options->sweep : options->output, &output_kinds::runFolder(),
                   shards.empty() ? std::string() : shards.front().functionalScenario, *force, "--out", "--force",
                   inputs});
      fmt::print("{}", pipeline::mergeShards(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
