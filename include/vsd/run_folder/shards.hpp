#pragma once
// Shards of a sweep: one `vsd-sumo run` split into N parts that run anywhere
// (Slurm array tasks, MPI ranks) and are joined afterwards (`vsd-sumo merge`) or
// read as one run directly.
//
// Layout: <sweep>/shards/shard-K-of-N/ is a complete run folder (concrete.csv,
// traces.h5, dataset.h5, manifest.json) of a contiguous range of sample indices;
// its manifest.json (written last) has a "shard" object that says which part of
// which sweep it is:
//   {"index": K, "count": N, "first_sample": f, "samples": n,
//    "sweep_first_sample": F, "sweep_samples": S, "seed": s,
//    "functional_scenario": "...", "scenario_sha256": "...", "batch": b, "compression": c}
// A folder without manifest.json is an unfinished shard.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vsd {

/// Shard `index` of `count` (0 <= index < count).
struct ShardId {
  std::uint64_t index = 0;
  std::uint64_t count = 1;

  /// "K/N" with 0 <= K < N <= 100000; throws ConfigError naming `where`, the text and the form.
  static ShardId parse(const std::string& text, const std::string& where);
  /// "shard-0003-of-0008" (indices zero-padded to the width of N, at least 4 digits).
  std::string folderName() const;
  /// "shard 3 of 8" (for messages).
  std::string label() const;
};

/// What a shard's manifest says about it.
struct ShardInfo {
  ShardId id;
  std::filesystem::path folder;
  std::uint64_t firstSample = 0;       ///< first sample index of this shard
  std::uint64_t samples = 0;           ///< samples of this shard
  std::uint64_t sweepFirstSample = 0;  ///< the whole sweep's range
  std::uint64_t sweepSamples = 0;
  std::uint64_t seed = 0;
  std::string functionalScenario;
  std::string scenarioSha256;
  std::uint64_t batch = 0;
  int compression = 1;

  /// The manifest's "shard" object as JSON text.
  std::string toJson() const;
  /// True if both belong to the same sweep (scenario, seed, range, shard count, settings).
  bool sameSweep(const ShardInfo& other) const;
};

/// The sample range [first, first + samples) of shard `id` of a sweep: the sweep's
/// batches are split into `count` contiguous groups of (almost) equal size, so shards
/// hold whole batches. Throws ConfigError if there are fewer batches than shards.
struct SampleRange {
  std::uint64_t first = 0;
  std::uint64_t samples = 0;
};
SampleRange shardRange(std::uint64_t sweep_first, std::uint64_t sweep_samples, std::uint64_t batch, const ShardId& id);

/// <sweep>/shards
std::filesystem::path shardsFolder(const std::filesystem::path& sweep);
/// True if `folder` has a shards/ subfolder.
bool hasShards(const std::filesystem::path& folder);

/// Reads `<folder>/manifest.json` of a finished shard. Throws DatasetError naming the
/// file if it is missing (unfinished shard), unreadable, or has no "shard" object.
ShardInfo readShardManifest(const std::filesystem::path& folder);

/// Every shard of the sweep, in sample order, checked to form exactly one sweep: all
/// N shards present and finished, the same functional scenario, scenario file hash,
/// seed, sweep range and settings, sample ranges without gaps or overlaps. Throws
/// DatasetError naming the shard folder and what is wrong.
std::vector<ShardInfo> readShardSet(const std::filesystem::path& sweep);

}  // namespace vsd
