#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
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
  merge->callback([options, &context] {
    context.action = [options, &context] {
      options->commandLine = context.commandLine;
      fmt::print("{}", pipeline::mergeShards(*options).report());
      return 0;
    };
  });
}

}  // namespace vsd::cli
