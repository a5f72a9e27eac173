#pragma once
// `vsd-sumo merge`: joins the shards of a sweep (vsd/run_folder/shards.hpp) into one run
// folder — concrete.csv, traces.h5 and dataset.h5 with the same bytes as one
// unsharded run of the same scenario, seed and samples — plus its manifest.json.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vsd::pipeline {

struct MergeOptions {
  std::filesystem::path sweep;   ///< folder with shards/shard-K-of-N/
  std::filesystem::path output;  ///< empty: the sweep folder itself (next to shards/)
  bool removeShards = false;     ///< delete the shard folders after a successful merge
  std::string commandLine;       ///< recorded in the manifest
};

struct MergeSummary {
  std::filesystem::path output;
  std::uint64_t shards = 0;
  std::uint64_t samples = 0;
  std::uint64_t ok = 0;
  std::uint64_t failed = 0;
  double seconds = 0.0;
  std::vector<std::filesystem::path> outputs;
  std::string report() const;
};

/// Checks the shards (all present and finished, one sweep, no gaps or overlaps, files
/// unchanged since their manifests were written) and writes the joined files under
/// temporary names, renamed when complete, manifest last. Throws DatasetError naming
/// the shard and the problem; nothing that looks complete is left behind.
MergeSummary mergeShards(const MergeOptions& options);

}  // namespace vsd::pipeline
