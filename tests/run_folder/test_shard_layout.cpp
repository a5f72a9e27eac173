// The shard layout of a sweep's run folder: which samples a shard holds and what its folder
// is called (merge and dataset readers rely on both).

#include <gtest/gtest.h>

#include "vsd/core/error.hpp"
#include "vsd/run_folder/shards.hpp"

using namespace vsd;

TEST(ShardLayout, ShardsHoldWholeContiguousBatchesCoveringTheSweep) {
  // 950 samples in batches of 100 = 10 batches over 3 shards: 4 + 3 + 3 batches, the last one short.
  const auto shard = [](std::uint64_t k) { return shardRange(1000, 950, 100, ShardId{k, 3}); };
  EXPECT_EQ(shard(0).first, 1000u);
  EXPECT_EQ(shard(0).samples, 400u);
  EXPECT_EQ(shard(1).first, 1400u);
  EXPECT_EQ(shard(1).samples, 300u);
  EXPECT_EQ(shard(2).first, 1700u);
  EXPECT_EQ(shard(2).samples, 250u);
  EXPECT_THROW(shardRange(0, 250, 100, ShardId{0, 4}), ConfigError);  // 3 batches cannot make 4 shards
}

TEST(ShardLayout, FolderNamesSortInShardOrder) {
  EXPECT_EQ((ShardId{3, 8}.folderName()), "shard-0003-of-0008");
  EXPECT_EQ((ShardId{3, 12345}.folderName()), "shard-00003-of-12345");
  EXPECT_EQ((ShardId{3, 8}.label()), "shard 3 of 8");
  EXPECT_EQ(shardsFolder("out/sweep"), std::filesystem::path("out/sweep/shards"));
}

TEST(ShardLayout, ShardsOfOneSweepAgreeOnEverySetting) {
  ShardInfo a;
  a.id = {0, 2};
  a.seed = 7;
  a.functionalScenario = "acc_lk";
  ShardInfo b = a;
  b.id = {1, 2};
  EXPECT_TRUE(a.sameSweep(b));
  b.seed = 8;
  EXPECT_FALSE(a.sameSweep(b));
}
