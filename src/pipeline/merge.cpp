#include "vsd/pipeline/merge.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <optional>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/run_folder/shards.hpp"
#include "vsd/pipeline/outcome_files.hpp"
#include "vsd/vector/dataset.hpp"

namespace fs = std::filesystem;

namespace vsd::pipeline {

namespace {

constexpr const char* kRunFiles[] = {"concrete.csv", "traces.h5", "dataset.h5"};

/// Every output a shard's manifest lists must still have its recorded size and hash.
void checkShardFiles(const ShardInfo& shard, const nlohmann::json& manifest) {
  for (const char* file : kRunFiles) {
    const fs::path path = shard.folder / file;
    if (!manifest.at("outputs").contains(file)) {
      throw DatasetError(fmt::format("{}: its manifest lists no {}", shard.folder.string(), file));
    }
    const auto& entry = manifest.at("outputs").at(file);
    std::error_code ec;
    const auto bytes = fs::file_size(path, ec);
    if (ec || bytes != entry.at("bytes").get<std::uintmax_t>() ||
        sha256OfFile(path) != entry.at("sha256").get<std::string>()) {
      throw DatasetError(fmt::format("{}: missing or changed since {} was written (size or SHA-256 differs from "
                                     "manifest.json): run {} again",
                                     path.string(), shard.id.label(), shard.id.label()));
    }
  }
}

/// concrete.csv: one header (the same in every shard), then every shard's rows in order.
void mergeCsv(const std::vector<ShardInfo>& shards, const fs::path& target) {
  std::ofstream out(target, std::ios::binary | std::ios::trunc);
  std::string first_header;
  for (const auto& shard : shards) {
    std::ifstream in(shard.folder / "concrete.csv", std::ios::binary);
    std::string header;
    std::getline(in, header);
    if (first_header.empty()) {
      first_header = header;
      out << header << '\n';
    } else if (header != first_header) {
      throw DatasetError(fmt::format("{}: its columns differ from {}'s", (shard.folder / "concrete.csv").string(),
                                     shards.front().id.label()));
    }
    if (in.peek() != std::ifstream::traits_type::eof()) out << in.rdbuf();
  }
  out.flush();
  if (!out) throw IoError(target.string() + ": write failed (disk full?)");
}

std::vector<fs::path> shardFiles(const std::vector<ShardInfo>& shards, const char* file) {
  std::vector<fs::path> files;
  for (const auto& shard : shards) files.push_back(shard.folder / file);
  return files;
}

nlohmann::json mergedManifest(const std::vector<ShardInfo>& shards, const std::vector<nlohmann::json>& manifests,
                              const MergeOptions& options, const std::string& started) {
  nlohmann::json manifest = manifests.front();
  manifest.erase("shard");
  manifest.erase(kManifestChecksumKey);  // the merged manifest gets its own
  const ShardInfo& first = shards.front();
  std::uint64_t ok = 0, failed = 0, collisions = 0;
  double seconds = 0.0;
  nlohmann::json folders = nlohmann::json::array();
  for (std::size_t s = 0; s < shards.size(); ++s) {
    ok += manifests[s].at("ok").get<std::uint64_t>();
    failed += manifests[s].at("failed").get<std::uint64_t>();
    collisions += manifests[s].at("collisions").get<std::uint64_t>();
    seconds += manifests[s].at("seconds").get<double>();
    folders.push_back(fs::relative(shards[s].folder, options.sweep).string());
  }
  manifest["first_sample"] = first.sweepFirstSample;
  manifest["samples"] = first.sweepSamples;
  manifest["ok"] = ok;
  manifest["failed"] = failed;
  manifest["collisions"] = collisions;
  manifest["seconds"] = seconds;  // summed over the shards (CPU-side work, not wall time)
  manifest["command_line"] = options.commandLine;
  manifest["started"] = started;
  manifest["finished"] = utcTimestamp();
  manifest["merged_from"] = {{"shards", shards.size()}, {"folders", folders}};
  return manifest;
}

}  // namespace

MergeSummary mergeShards(const MergeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::string started = utcTimestamp();
  const auto shards = readShardSet(options.sweep);
  std::vector<nlohmann::json> manifests;
  for (const auto& shard : shards) {
    manifests.push_back(readManifest(shard.folder));
    checkShardFiles(shard, manifests.back());
    // What the manifest says (seed, range, scenario) against what the files hold, before anything is written.
    const auto problems = vector::runFolderRecordProblems(shard.folder);
    if (!problems.empty()) throw DatasetError(fmt::format("{}: {}", shard.id.label(), problems.front()));
  }
  const fs::path out = options.output.empty() ? options.sweep : options.output;
  ensureDirectory(out);

  AtomicOutput csv(out / "concrete.csv");
  AtomicOutput traces(out / "traces.h5");
  AtomicOutput dataset(out / "dataset.h5");
  mergeCsv(shards, csv.tempPath());
  concatenateTraces(shardFiles(shards, "traces.h5"), traces.tempPath());
  concatenateDatasets(shardFiles(shards, "dataset.h5"), dataset.tempPath(), shards.front().compression);
  csv.commit();
  traces.commit();
  dataset.commit();

  nlohmann::json manifest = mergedManifest(shards, manifests, options, started);
  MergeSummary summary;
  summary.output = out;
  summary.shards = shards.size();
  summary.samples = shards.front().sweepSamples;
  summary.ok = manifest["ok"].get<std::uint64_t>();
  summary.failed = manifest["failed"].get<std::uint64_t>();
  nlohmann::json files = nlohmann::json::object();
  for (const char* file : kRunFiles) {
    files[file] = {{"sha256", sha256OfFile(out / file)}, {"bytes", fs::file_size(out / file)}};
    summary.outputs.push_back(out / file);
  }
  manifest["outputs"] = files;
  writeTextFileAtomically(out / "manifest.json", sealManifest(manifest).dump(2) + "\n");
  summary.outputs.push_back(out / "manifest.json");
  if (options.removeShards) {
    std::error_code ignored;
    fs::remove_all(shardsFolder(options.sweep), ignored);
  }
  summary.seconds = secondsSince(start);
  return summary;
}

std::string MergeSummary::report() const {
  std::string text = fmt::format("merged {} shards: {} concrete scenarios (completed {}, failed {}) in {:.2f} s\n",
                                 shards, samples, ok, failed, seconds);
  text += "  outputs:\n";
  for (const auto& path : outputs) text += fmt::format("    {}\n", path.string());
  return text;
}

}  // namespace vsd::pipeline
