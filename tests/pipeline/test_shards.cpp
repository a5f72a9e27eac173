// Sweeps split into shards (Slurm array tasks, MPI ranks) and joined again.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/run_folder/shards.hpp"
#include "vsd/pipeline/merge.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

RunOptions sweep(const fs::path& out, std::uint64_t seed = 5) {
  RunOptions options;
  options.scenarioFile = test::scenarioFile("acc_lk.yaml");
  options.outputDir = out;
  options.samples = 45;
  options.firstSample = 3;
  options.batch = 10;
  options.seed = seed;
  return options;
}

void runShards(const RunOptions& base, std::uint64_t count, const std::vector<std::uint64_t>& which) {
  for (const auto k : which) {
    auto options = base;
    options.shard = ShardId{k, count};
    runScenarios(options);
  }
}

std::string expectDatasetError(const std::function<void()>& action) {
  try {
    action();
  } catch (const DatasetError& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected DatasetError";
  return {};
}

}  // namespace

TEST(Shards, MergedShardsHaveTheBytesOfOneRunAndReadAsOneRunBefore) {
  TemporaryDirectory dir;
  runScenarios(sweep(dir.path() / "whole"));
  // 5 batches in 3 shards: 2 + 2 + 1 batches; shards run in any order.
  runShards(sweep(dir.path() / "sweep"), 3, {2, 0, 1});
  const auto shards = readShardSet(dir.path() / "sweep");
  ASSERT_EQ(shards.size(), 3u);
  EXPECT_EQ(shards[0].firstSample, 3u);
  EXPECT_EQ(shards[0].samples, 20u);
  EXPECT_EQ(shards[2].firstSample, 43u);
  EXPECT_EQ(shards[2].samples, 5u);

  // Readers take the shard folder as one run, in sample order.
  vector::DatasetCollection collection;
  collection.add(dir.path() / "sweep");
  const auto refs = collection.all();
  ASSERT_EQ(refs.size(), 45u);
  for (std::size_t i = 0; i < refs.size(); ++i) EXPECT_EQ(collection.scene(refs[i]).sample, 3 + i);

  MergeOptions merge;
  merge.sweep = dir.path() / "sweep";
  const auto summary = mergeShards(merge);
  EXPECT_EQ(summary.samples, 45u);
  EXPECT_EQ(summary.ok + summary.failed, 45u);
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    EXPECT_EQ(sha256OfFile(dir.path() / "sweep" / file), sha256OfFile(dir.path() / "whole" / file)) << file;
  }
  EXPECT_TRUE(fs::exists(dir.path() / "sweep" / "manifest.json"));
}

// A scenario whose road users' kinds (and so sizes) are drawn per sample: the merged
// traces keep the file's sizes as one process writes them (NaN where drawn per sample).
TEST(Shards, MergedShardsOfRoadUsersOfDrawnKindsHaveTheBytesOfOneRun) {
  TemporaryDirectory dir;
  auto whole = sweep(dir.path() / "whole");
  whole.scenarioFile = test::scenarioFile("alks/cut_in.yaml");
  whole.samples = 20;
  runScenarios(whole);
  auto sharded = whole;
  sharded.outputDir = dir.path() / "sweep";
  runShards(sharded, 2, {1, 0});
  MergeOptions merge;
  merge.sweep = dir.path() / "sweep";
  mergeShards(merge);
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    EXPECT_EQ(sha256OfFile(dir.path() / "sweep" / file), sha256OfFile(dir.path() / "whole" / file)) << file;
  }
}

TEST(Shards, FinishedShardsAreNotRunAgain) {
  TemporaryDirectory dir;
  auto options = sweep(dir.path() / "sweep");
  options.shard = ShardId{1, 2};
  const auto first = runScenarios(options);
  EXPECT_FALSE(first.resumed);
  const auto folder = dir.path() / "sweep" / "shards" / "shard-0001-of-0002";
  const auto written = fs::last_write_time(folder / "dataset.h5");
  const auto again = runScenarios(options);
  EXPECT_TRUE(again.resumed);
  EXPECT_EQ(again.ok, first.ok);
  EXPECT_EQ(fs::last_write_time(folder / "dataset.h5"), written);
  // A shard with a damaged file is run again.
  fs::resize_file(folder / "traces.h5", 100);
  EXPECT_FALSE(runScenarios(options).resumed);
}

TEST(Shards, MergeRefusesMissingUnfinishedForeignOrChangedShards) {
  TemporaryDirectory dir;
  const auto folder = dir.path() / "sweep";
  runShards(sweep(folder), 3, {0, 2});
  MergeOptions merge;
  merge.sweep = folder;
  auto message = expectDatasetError([&] { mergeShards(merge); });
  EXPECT_NE(message.find("shard 1 of 3 is missing"), std::string::npos) << message;
  EXPECT_NE(message.find("--shard 1/3"), std::string::npos) << message;

  // Shard 1 of the same sweep but with another seed.
  runShards(sweep(dir.path() / "other", 6), 3, {1});
  fs::rename(dir.path() / "other" / "shards" / "shard-0001-of-0003", folder / "shards" / "shard-0001-of-0003");
  message = expectDatasetError([&] { mergeShards(merge); });
  EXPECT_NE(message.find("belongs to another sweep"), std::string::npos) << message;
  EXPECT_NE(message.find("seed 6"), std::string::npos) << message;
  fs::remove_all(folder / "shards" / "shard-0001-of-0003");

  // An unfinished shard (no manifest yet) and a shard whose file changed afterwards.
  runShards(sweep(folder), 3, {1});
  fs::rename(folder / "shards" / "shard-0001-of-0003" / "manifest.json", dir.path() / "manifest.json");
  message = expectDatasetError([&] { mergeShards(merge); });
  EXPECT_NE(message.find("unfinished shard"), std::string::npos) << message;
  fs::rename(dir.path() / "manifest.json", folder / "shards" / "shard-0001-of-0003" / "manifest.json");
  test::writeFile(folder / "shards" / "shard-0002-of-0003" / "concrete.csv", "edited\n");
  message = expectDatasetError([&] { mergeShards(merge); });
  EXPECT_NE(message.find("changed since shard 2 of 3 was written"), std::string::npos) << message;

  // Shards of another split in the same folder.
  runShards(sweep(folder), 2, {0});
  message = expectDatasetError([&] { mergeShards(merge); });
  EXPECT_NE(message.find("2 different splits"), std::string::npos) << message;
  // Nothing that looks like a merged run was left behind.
  EXPECT_FALSE(fs::exists(folder / "dataset.h5"));
  EXPECT_FALSE(fs::exists(folder / "manifest.json"));
}

// Issue 29: a shard's manifest is tied to its contents — an edited seed is refused by its
// checksum, and (with the checksum removed too) by the records: concrete.csv's seeds, the
// dataset's samples and inputs. `dataset validate` says the same.
TEST(Shards, EditedManifestsAndForeignFilesAreRefusedByMergeAndValidate) {
  TemporaryDirectory dir;
  const auto folder = dir.path() / "sweep";
  runShards(sweep(folder), 2, {0, 1});
  const auto shard = folder / "shards" / "shard-0000-of-0002";
  const auto manifest_path = shard / "manifest.json";
  const std::string original = readTextFile(manifest_path);
  MergeOptions merge;
  merge.sweep = folder;
  const auto edit = [&](bool drop_checksum) {
    auto manifest = nlohmann::json::parse(original);
    manifest["seed"] = 99;
    manifest["shard"]["seed"] = 99;
    if (drop_checksum) manifest.erase(kManifestChecksumKey);
    test::writeFile(manifest_path, manifest.dump(2));
  };
  edit(false);
  EXPECT_THAT(expectDatasetError([&] { mergeShards(merge); }), testing::HasSubstr("edited after it was written"));
  EXPECT_FALSE(vector::validateDataset(shard).ok());
  // With the checksums removed and both shards edited alike, the shards "agree" on seed 99.
  edit(true);
  auto other = nlohmann::json::parse(readTextFile(folder / "shards" / "shard-0001-of-0002" / "manifest.json"));
  other["seed"] = 99;
  other["shard"]["seed"] = 99;
  other.erase(kManifestChecksumKey);
  test::writeFile(folder / "shards" / "shard-0001-of-0002" / "manifest.json", other.dump(2));
  EXPECT_THAT(expectDatasetError([&] { mergeShards(merge); }),
              testing::HasSubstr("concrete.csv: row 1 has seed 5, the manifest says 99"));
  const auto validation = vector::validateDataset(shard);
  ASSERT_FALSE(validation.ok());
  EXPECT_THAT(validation.problems.front(), testing::HasSubstr("has seed 5, the manifest says 99"));
  EXPECT_FALSE(fs::exists(folder / "dataset.h5"));
  test::writeFile(manifest_path, original);
  EXPECT_TRUE(vector::validateDataset(shard).ok());
}

TEST(Shards, BadShardSpecificationsAreRefused) {
  for (const char* text : {"3/2", "2/2", "1/0", "a/2", "1", "-1/2", "1/2/3", ""}) {
    EXPECT_THROW(ShardId::parse(text, "command line"), ConfigError) << text;
  }
  try {
    ShardId::parse("3/2", "command line");
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("0 <= K < N"), std::string::npos) << error.what();
  }
  EXPECT_EQ(ShardId::parse("7/12", "x").folderName(), "shard-0007-of-0012");
  // 45 samples in batches of 10 are 5 batches: 6 shards cannot each get one.
  auto options = sweep("unused");
  options.shard = ShardId{0, 6};
  try {
    runScenarios(options);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("only 5 batches"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists("unused"));
}
