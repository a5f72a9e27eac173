#include "vsd/run_folder/shards.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <optional>
#include <regex>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd {

namespace {

constexpr std::uint64_t kMaxShards = 100000;

/// A shard index or count: up to nine decimal digits, nothing else (no sign, no space).
std::optional<std::uint64_t> parseCount(const std::string& text) {
  if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  return std::stoull(text);
}

}  // namespace

ShardId ShardId::parse(const std::string& text, const std::string& where) {
  const std::string expected = fmt::format("K/N with 0 <= K < N <= {} (shard K of N, counted from 0)", kMaxShards);
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw ConfigError::field(where, "--shard", text, expected);
  const auto index = parseCount(text.substr(0, slash));
  const auto count = parseCount(text.substr(slash + 1));
  if (!index || !count) throw ConfigError::field(where, "--shard", text, expected);
  ShardId id;
  id.index = *index;
  id.count = *count;
  if (id.count < 1 || id.count > kMaxShards || id.index >= id.count) {
    throw ConfigError::field(where, "--shard", text, expected);
  }
  return id;
}

std::string ShardId::folderName() const {
  const auto width = std::max<std::size_t>(4, std::to_string(count).size());
  return fmt::format("shard-{:0{}}-of-{:0{}}", index, width, count, width);
}

std::string ShardId::label() const { return fmt::format("shard {} of {}", index, count); }

std::string ShardInfo::toJson() const {
  nlohmann::json json = {{"index", id.index},
                         {"count", id.count},
                         {"first_sample", firstSample},
                         {"samples", samples},
                         {"sweep_first_sample", sweepFirstSample},
                         {"sweep_samples", sweepSamples},
                         {"seed", seed},
                         {"functional_scenario", functionalScenario},
                         {"scenario_sha256", scenarioSha256},
                         {"batch", batch},
                         {"compression", compression}};
  return json.dump();
}

bool ShardInfo::sameSweep(const ShardInfo& other) const {
  return id.count == other.id.count && sweepFirstSample == other.sweepFirstSample &&
         sweepSamples == other.sweepSamples && seed == other.seed && functionalScenario == other.functionalScenario &&
         scenarioSha256 == other.scenarioSha256 && batch == other.batch && compression == other.compression;
}

SampleRange shardRange(std::uint64_t sweep_first, std::uint64_t sweep_samples, std::uint64_t batch, const ShardId& id) {
  const std::uint64_t batches = (sweep_samples + batch - 1) / batch;
  if (id.count > batches) {
    throw ConfigError(fmt::format("{} shards (or ranks) but the sweep has only {} batch{} of {} samples: use at most {} "
                                  "shards, or a smaller --net-batch",
                                  id.count, batches, batches == 1 ? "" : "es", batch, batches));
  }
  // Batches [b0, b1) of this shard: the first (batches % count) shards get one more.
  auto first_batch = [&](std::uint64_t k) { return k * (batches / id.count) + std::min(k, batches % id.count); };
  const std::uint64_t b0 = first_batch(id.index);
  const std::uint64_t b1 = first_batch(id.index + 1);
  const std::uint64_t first = b0 * batch;
  const std::uint64_t end = std::min(sweep_samples, b1 * batch);
  return {sweep_first + first, end - first};
}

fs::path shardsFolder(const fs::path& sweep) { return sweep / "shards"; }

bool hasShards(const fs::path& folder) { return fs::is_directory(shardsFolder(folder)); }

ShardInfo readShardManifest(const fs::path& folder) {
  const fs::path path = folder / "manifest.json";
  if (!fs::exists(path)) {
    throw DatasetError(fmt::format("{}: unfinished shard (no manifest.json): run it again", folder.string()));
  }
  ShardInfo info;
  info.folder = folder;
  const auto manifest = readManifest(folder);  // its checksum: an edited seed or range is refused here
  try {
    const auto& shard = manifest.at("shard");
    info.id.index = shard.at("index").get<std::uint64_t>();
    info.id.count = shard.at("count").get<std::uint64_t>();
    info.firstSample = shard.at("first_sample").get<std::uint64_t>();
    info.samples = shard.at("samples").get<std::uint64_t>();
    info.sweepFirstSample = shard.at("sweep_first_sample").get<std::uint64_t>();
    info.sweepSamples = shard.at("sweep_samples").get<std::uint64_t>();
    info.seed = shard.at("seed").get<std::uint64_t>();
    info.functionalScenario = shard.at("functional_scenario").get<std::string>();
    info.scenarioSha256 = shard.at("scenario_sha256").get<std::string>();
    info.batch = shard.at("batch").get<std::uint64_t>();
    info.compression = shard.at("compression").get<int>();
  } catch (const nlohmann::json::exception& error) {
    throw DatasetError(fmt::format("{}: not a shard manifest ({})", path.string(), error.what()));
  }
  return info;
}

namespace {

/// The shard folders under <sweep>/shards by their "of N", each by K.
std::map<std::uint64_t, std::map<std::uint64_t, fs::path>> listShardFolders(const fs::path& sweep) {
  static const std::regex name("shard-([0-9]+)-of-([0-9]+)");
  std::map<std::uint64_t, std::map<std::uint64_t, fs::path>> splits;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(shardsFolder(sweep), ec)) {
    std::smatch match;
    const std::string folder = entry.path().filename().string();
    if (!entry.is_directory() || !std::regex_match(folder, match, name)) continue;
    splits[std::stoull(match[2].str())][std::stoull(match[1].str())] = entry.path();
  }
  if (ec) throw DatasetError(fmt::format("{}: cannot list shards: {}", shardsFolder(sweep).string(), ec.message()));
  return splits;
}

}  // namespace

std::vector<ShardInfo> readShardSet(const fs::path& sweep) {
  const auto splits = listShardFolders(sweep);
  if (splits.empty()) throw DatasetError(fmt::format("{}: no shard folders (shard-K-of-N)", shardsFolder(sweep).string()));
  if (splits.size() > 1) {
    throw DatasetError(fmt::format("{}: shards of {} different splits (-of-{} and -of-{}): remove the stale ones",
                                   shardsFolder(sweep).string(), splits.size(), splits.begin()->first,
                                   std::next(splits.begin())->first));
  }
  const auto& [count, folders] = *splits.begin();
  std::vector<ShardInfo> shards;
  for (std::uint64_t k = 0; k < count; ++k) {
    const ShardId id{k, count};
    const auto it = folders.find(k);
    if (it == folders.end()) {
      throw DatasetError(fmt::format("{}: {} is missing ({}): run it with --shard {}/{}", sweep.string(), id.label(),
                                     (shardsFolder(sweep) / id.folderName()).string(), k, count));
    }
    ShardInfo info = readShardManifest(it->second);
    if (info.id.index != k || info.id.count != count) {
      throw DatasetError(fmt::format("{}: its manifest says {}, its name {}", it->second.string(), info.id.label(),
                                     id.label()));
    }
    if (!shards.empty()) {
      const ShardInfo& first = shards.front();
      if (!info.sameSweep(first)) {
        throw DatasetError(fmt::format(
            "{}: belongs to another sweep than {} (scenario {} {:.12}, seed {}, samples {}+{} vs scenario {} {:.12}, "
            "seed {}, samples {}+{})",
            it->second.string(), first.folder.string(), info.functionalScenario, info.scenarioSha256, info.seed,
            info.sweepFirstSample, info.sweepSamples, first.functionalScenario, first.scenarioSha256, first.seed,
            first.sweepFirstSample, first.sweepSamples));
      }
      const ShardInfo& previous = shards.back();
      const std::uint64_t expected = previous.firstSample + previous.samples;
      if (info.firstSample != expected) {
        throw DatasetError(fmt::format("{}: starts at sample {} but {} ends before sample {} ({})", it->second.string(),
                                       info.firstSample, previous.id.label(), expected,
                                       info.firstSample > expected ? "a gap" : "an overlap"));
      }
    } else if (info.firstSample != info.sweepFirstSample) {
      throw DatasetError(fmt::format("{}: the first shard starts at sample {}, the sweep at {}", it->second.string(),
                                     info.firstSample, info.sweepFirstSample));
    }
    shards.push_back(std::move(info));
  }
  const ShardInfo& last = shards.back();
  if (last.firstSample + last.samples != last.sweepFirstSample + last.sweepSamples) {
    throw DatasetError(fmt::format("{}: the last shard ends before sample {}, the sweep before {}", last.folder.string(),
                                   last.firstSample + last.samples, last.sweepFirstSample + last.sweepSamples));
  }
  return shards;
}

}  // namespace vsd
