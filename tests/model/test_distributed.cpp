// Data-parallel training: two `vsd-sumo train` processes on loopback (WORLD_SIZE / RANK /
// MASTER_ADDR / MASTER_PORT, as torchrun sets them) against one process.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <regex>

#include "synthetic_scenes.hpp"
#include "test_support.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/process.hpp"
#include "vsd/model/predictor.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

/// A port no other test run of this machine uses at the same time (by process id).
int freePort(int offset) { return 20000 + static_cast<int>(getpid() % 15000) * 3 + offset; }

std::vector<std::string> trainArgs(const fs::path& data, const fs::path& out) {
  // Batch 7 of 54 training samples: uneven slices (4 + 3) and a last batch of 5 (3 + 2).
  return {"train", "-d", data.string(), "-o", out.string(), "--steps", "24", "--minibatch", "7", "--threads", "1",
          "--hidden", "16", "--layers", "1", "--global-width", "16", "--heads", "1", "--decoder-hidden", "16",
          "--seed", "5"};
}

std::vector<std::string> withEnvironment(const std::vector<std::string>& variables, const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"timeout", "60", "env"};
  argv.insert(argv.end(), variables.begin(), variables.end());
  argv.push_back(test::vsdSumo().string());
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

/// Runs `ranks` processes of one distributed training; returns their results by rank.
std::vector<ProcessResult> runRanks(int ranks, int port, const std::vector<std::string>& args, const fs::path& work,
                                    const std::vector<std::string>& rank0_extra = {},
                                    const std::vector<int>& world_sizes = {}) {
  std::vector<ChildProcess> children;
  for (int rank = 0; rank < ranks; ++rank) {
    const int world = world_sizes.empty() ? ranks : world_sizes[static_cast<std::size_t>(rank)];
    std::vector<std::string> variables = {"MASTER_ADDR=127.0.0.1", fmt::format("MASTER_PORT={}", port),
                                          fmt::format("WORLD_SIZE={}", world), fmt::format("RANK={}", rank),
                                          "VSD_RENDEZVOUS_TIMEOUT=20"};
    if (rank == 0) variables.insert(variables.end(), rank0_extra.begin(), rank0_extra.end());
    const auto log = work / fmt::format("rank{}_{}.log", rank, port);
    fs::remove(log);
    children.push_back(ChildProcess::spawn(withEnvironment(variables, args), log));
  }
  std::vector<ProcessResult> results;
  for (auto& child : children) results.push_back(child.wait());
  return results;
}

/// The per-epoch training losses a run printed.
std::vector<double> trainLosses(const std::string& output) {
  std::vector<double> losses;
  const std::regex line(R"(epoch +\d+/\d+: train loss ([0-9.]+))");
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    losses.push_back(std::stod((*it)[1]));
  }
  return losses;
}

/// Largest distance between two models' predicted positions over `scenes`, m.
double largestDifference(const fs::path& a, const fs::path& b, const std::vector<vector::VectorizedScene>& scenes) {
  const auto pa = model::Predictor(a, 1).predict(scenes);
  const auto pb = model::Predictor(b, 1).predict(scenes);
  double largest = 0.0;
  for (std::size_t i = 0; i < pa.size(); ++i) {
    for (std::size_t k = 0; k < pa[i].size(); ++k) largest = std::max(largest, (pa[i][k] - pb[i][k]).norm());
  }
  return largest;
}

}  // namespace

TEST(DistributedTraining, TwoRanksFollowTheOneProcessLossCurveAndResume) {
  TemporaryDirectory dir;
  const auto data = test::writeDataset(dir.path() / "data.h5", 60);
  std::vector<vector::VectorizedScene> scenes;
  for (std::uint64_t i = 0; i < 60; i += 6) scenes.push_back(test::syntheticScene(i));

  const auto one = test::run(withEnvironment({}, trainArgs(data, dir.path() / "one.pt")), dir.path());
  ASSERT_EQ(one.exitCode, 0) << one.output;
  const auto curve = trainLosses(one.output);
  ASSERT_GE(curve.size(), 3u) << one.output;

  const auto two = runRanks(2, freePort(0), trainArgs(data, dir.path() / "two.pt"), dir.path());
  ASSERT_EQ(two[0].exitCode, 0) << two[0].output;
  ASSERT_EQ(two[1].exitCode, 0) << two[1].output;
  EXPECT_NE(two[0].output.find("data-parallel over 2 ranks"), std::string::npos) << two[0].output;
  EXPECT_EQ(two[1].output.find("epoch"), std::string::npos) << "rank 1 reports nothing: " << two[1].output;
  const auto parallel_curve = trainLosses(two[0].output);
  ASSERT_EQ(parallel_curve.size(), curve.size()) << two[0].output;
  for (std::size_t e = 0; e < curve.size(); ++e) EXPECT_NEAR(parallel_curve[e], curve[e], 2e-3) << "epoch " << e + 1;
  EXPECT_LT(largestDifference(dir.path() / "one.pt", dir.path() / "two.pt", scenes), 1e-3);

  // SIGTERM reaches rank 0 while it writes the first best model: both ranks stop at the
  // same step (143), and --resume on both continues to the model of the uninterrupted run.
  const auto stopped = runRanks(2, freePort(1), trainArgs(data, dir.path() / "res.pt"), dir.path(),
                                {"VSD_FAULT=term@atomic.fsync:res.pt"});
  EXPECT_EQ(stopped[0].exitCode, 143) << stopped[0].output;
  EXPECT_EQ(stopped[1].exitCode, 143) << stopped[1].output;
  ASSERT_TRUE(fs::exists(dir.path() / "res.pt.last"));
  auto resume = trainArgs(data, dir.path() / "res.pt");
  resume.push_back("--resume");
  const auto resumed = runRanks(2, freePort(2), resume, dir.path());
  ASSERT_EQ(resumed[0].exitCode, 0) << resumed[0].output;
  ASSERT_EQ(resumed[1].exitCode, 0) << resumed[1].output;
  EXPECT_NE(resumed[0].output.find("resuming"), std::string::npos) << resumed[0].output;
  EXPECT_LT(largestDifference(dir.path() / "two.pt", dir.path() / "res.pt", scenes), 1e-5);
}

TEST(DistributedTraining, BadRendezvousEndsWithOneClearLine) {
  TemporaryDirectory dir;
  const auto data = test::writeDataset(dir.path() / "data.h5", 20);
  const auto args = trainArgs(data, dir.path() / "x.pt");
  const auto single = [&](const std::vector<std::string>& variables) {
    return test::run(withEnvironment(variables, args), dir.path());
  };
  // Nobody listens at MASTER_PORT: the rendezvous times out (2 s), it does not hang.
  const auto unreachable = single({"MASTER_ADDR=127.0.0.1", fmt::format("MASTER_PORT={}", freePort(0)),
                                   "WORLD_SIZE=2", "RANK=1", "VSD_RENDEZVOUS_TIMEOUT=2"});
  EXPECT_EQ(unreachable.exitCode, 1) << unreachable.output;
  EXPECT_NE(unreachable.output.find(fmt::format("error: cannot reach the training rendezvous at MASTER_ADDR=127.0.0.1 "
                                                "MASTER_PORT={} (rank 1 of 2, WORLD_SIZE/RANK) within 2 s",
                                                freePort(0))),
            std::string::npos)
      << unreachable.output;
  EXPECT_EQ(unreachable.output.find("c10d"), std::string::npos) << "no libtorch log lines: " << unreachable.output;

  const auto too_many = single({"MASTER_ADDR=127.0.0.1", "WORLD_SIZE=8", "RANK=0"});
  EXPECT_EQ(too_many.exitCode, 1);
  EXPECT_NE(too_many.output.find("--batch 7: a distributed training over 8 ranks"), std::string::npos)
      << too_many.output;
  const auto bad_rank = single({"MASTER_ADDR=127.0.0.1", "WORLD_SIZE=2", "RANK=2"});
  EXPECT_EQ(bad_rank.exitCode, 1);
  EXPECT_NE(bad_rank.output.find("environment variable RANK: got '2', expected an integer in [0, 1]"),
            std::string::npos)
      << bad_rank.output;
  const auto no_address = single({"WORLD_SIZE=2", "RANK=0"});
  EXPECT_EQ(no_address.exitCode, 1);
  EXPECT_NE(no_address.output.find("MASTER_ADDR is not set"), std::string::npos) << no_address.output;

  // Rank 0 was started for 2 ranks, rank 1 for 3: both say so and stop.
  const auto mismatch = runRanks(2, freePort(1), args, dir.path(), {}, {2, 3});
  for (const auto& rank : mismatch) {
    EXPECT_EQ(rank.exitCode, 1) << rank.output;
    EXPECT_NE(rank.output.find("world size mismatch: rank 0 was started with a world of 2 ranks, rank 1 with 3"),
              std::string::npos)
        << rank.output;
  }
}
