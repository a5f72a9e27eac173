#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>

#include "vsd/core/error.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/pipeline/cluster.hpp"
#include "vsd/pipeline/merge.hpp"
#include "vsd/pipeline/run.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

namespace {

std::string shardLine(const RunSummary& summary) {
  return nlohmann::json{{"label", summary.shard ? summary.shard->label() : std::string("whole sweep")},
                        {"first", summary.firstSample},
                        {"samples", summary.samples},
                        {"ok", summary.ok},
                        {"failed", summary.failed},
                        {"collisions", summary.collisions},
                        {"seconds", summary.seconds},
                        {"resumed", summary.resumed}}
      .dump();
}

std::string jobReport(const scenario::LogicalScenario& logical, const RunOptions& options,
                      const std::vector<std::string>& lines, double seconds) {
  std::uint64_t ok = 0, failed = 0, collisions = 0, resumed = 0;
  std::string ranks;
  for (std::size_t r = 0; r < lines.size(); ++r) {
    const auto shard = nlohmann::json::parse(lines[r]);
    ok += shard["ok"].get<std::uint64_t>();
    failed += shard["failed"].get<std::uint64_t>();
    collisions += shard["collisions"].get<std::uint64_t>();
    const bool was_resumed = shard["resumed"].get<bool>();
    resumed += was_resumed ? 1 : 0;
    const auto first = shard["first"].get<std::uint64_t>();
    ranks += fmt::format("  rank {:>3}: {}, samples {} .. {}: completed {}, failed {}{}\n", r,
                         shard["label"].get<std::string>(), first, first + shard["samples"].get<std::uint64_t>() - 1,
                         shard["ok"].get<std::uint64_t>(), shard["failed"].get<std::uint64_t>(),
                         was_resumed ? " (finished by an earlier attempt: not run again)"
                                     : fmt::format(" in {:.2f} s", shard["seconds"].get<double>()));
  }
  std::string text = fmt::format("{}: {} concrete scenarios (seed {}) on {} MPI ranks in {:.2f} s = {:.0f} scenarios/s{}\n",
                                 logical.name, options.samples, options.seed, lines.size(), seconds,
                                 static_cast<double>(options.samples) / std::max(seconds, 1e-9),
                                 resumed > 0 ? fmt::format(" ({} shards resumed)", resumed) : "");
  text += ranks;
  text += fmt::format("  completed {}, failed {}, collisions (d_min <= 0) {}\n", ok, failed, collisions);
  return text;
}

}  // namespace

ClusterRunResult runOnCluster(const RunOptions& options, bool merge, Communicator& communicator) {
  const auto start = std::chrono::steady_clock::now();
  const int rank = communicator.rank();
  std::shared_ptr<const scenario::LogicalScenario> logical;
  RunOptions mine = options;
  const bool valid = checkOnEveryRank(communicator, [&] {
    if (options.shard) {
      throw ConfigError("--shard and mpirun exclude each other: under mpirun, rank r of N runs shard r/N");
    }
    logical = scenario::loadLogicalScenario(options.scenarioFile);
    mine.shard = ShardId{static_cast<std::uint64_t>(rank), static_cast<std::uint64_t>(communicator.size())};
    mine.validate();
    shardRange(mine.firstSample, mine.samples, mine.batch, *mine.shard);
  });
  if (!valid) return {1, {}};
  RunSummary summary;
  workOrEndJob(communicator, mine.shard->label(), [&] { summary = runScenarios(logical, mine); });
  const auto lines = communicator.allGather(shardLine(summary));
  ClusterRunResult result;
  if (rank != 0) return result;
  result.report = jobReport(*logical, mine, lines, secondsSince(start));
  const fs::path out = mine.outputDir.empty() ? fs::path("out") / logical->name : mine.outputDir;
  if (merge) {
    MergeOptions merge_options;
    merge_options.sweep = out;
    merge_options.commandLine = mine.commandLine;
    result.report += mergeShards(merge_options).report();
  } else {
    result.report += fmt::format("  shards in {}: read them as one run (train, evaluate, compare --data, dataset) or "
                                 "join them with `vsd-sumo merge {}`\n",
                                 shardsFolder(out).string(), out.string());
  }
  return result;
}

}  // namespace vsd::pipeline
