// vsd-sumo under mpirun (2 ranks on this machine, as CI runs them: root, loopback).
#include <gtest/gtest.h>

#include <algorithm>

#include "test_support.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

#ifdef VSD_TEST_MPIEXEC
constexpr const char* kMpiexec = VSD_TEST_MPIEXEC;
#else
constexpr const char* kMpiexec = "";
#endif

/// `mpirun -n <ranks> vsd-sumo --quiet <args>`, ended after 120 s if it hangs (exit 124).
ProcessResult mpirun(int ranks, const std::vector<std::string>& args, const fs::path& work) {
  std::vector<std::string> argv = {"timeout", "120", kMpiexec, "--allow-run-as-root", "--oversubscribe",
                                   "-n", std::to_string(ranks), test::vsdSumo().string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return test::run(argv, work);
}

std::vector<std::string> runArgs(const fs::path& out) {
  return {"run", test::scenarioFile("acc_lk.yaml").string(), "--samples", "40", "--net-batch", "10", "--seed", "3",
          "--out", out.string()};
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

#define SKIP_WITHOUT_MPI() \
  if (std::string(kMpiexec).empty()) GTEST_SKIP() << "this build has no MPI"

}  // namespace

TEST(Mpi, HelpSaysWhetherTheBuildHasMpi) {
  TemporaryDirectory dir;
  const auto help = test::run({test::vsdSumo().string(), "--help"}, dir.path());
  EXPECT_NE(help.output.find(std::string(kMpiexec).empty() ? "MPI: not in this build" : "MPI: Open MPI"),
            std::string::npos)
      << help.output;
}

TEST(Mpi, RunOnTwoRanksGivesTheBytesOfOneProcessAndResumesFinishedShards) {
  SKIP_WITHOUT_MPI();
  TemporaryDirectory dir;
  const auto one = test::run([&] {
    std::vector<std::string> argv = {test::vsdSumo().string(), "--quiet"};
    const auto args = runArgs(dir.path() / "one");
    argv.insert(argv.end(), args.begin(), args.end());
    return argv;
  }(), dir.path());
  ASSERT_EQ(one.exitCode, 0) << one.output;

  // Shard 0 finished in an earlier attempt: the MPI job resumes and runs shard 1 only.
  auto shard0 = runArgs(dir.path() / "sweep");
  shard0.insert(shard0.begin(), {test::vsdSumo().string(), "--quiet"});
  shard0.insert(shard0.end(), {"--shard", "0/2"});
  ASSERT_EQ(test::run(shard0, dir.path()).exitCode, 0);

  const auto job = mpirun(2, runArgs(dir.path() / "sweep"), dir.path());
  ASSERT_EQ(job.exitCode, 0) << job.output;
  EXPECT_NE(job.output.find("on 2 MPI ranks"), std::string::npos) << job.output;
  EXPECT_NE(job.output.find("rank   0: shard 0 of 2, samples 0 .. 19: completed 20, failed 0 (finished by an "
                            "earlier attempt"),
            std::string::npos)
      << job.output;
  EXPECT_NE(job.output.find("rank   1: shard 1 of 2, samples 20 .. 39: completed 20, failed 0 in"),
            std::string::npos)
      << job.output;

  // The shards read as one run before they are merged.
  const auto info = test::run({test::vsdSumo().string(), "dataset", "info", (dir.path() / "sweep").string()},
                              dir.path());
  EXPECT_EQ(info.exitCode, 0) << info.output;
  EXPECT_NE(info.output.find("(2 shards)"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("samples 40,"), std::string::npos) << info.output;

  // Run again with --merge: nothing left to simulate, rank 0 joins the shards.
  auto again = runArgs(dir.path() / "sweep");
  again.push_back("--merge");
  const auto merged = mpirun(2, again, dir.path());
  ASSERT_EQ(merged.exitCode, 0) << merged.output;
  EXPECT_NE(merged.output.find("(2 shards resumed)"), std::string::npos) << merged.output;
  EXPECT_NE(merged.output.find("merged 2 shards"), std::string::npos) << merged.output;
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    EXPECT_EQ(sha256OfFile(dir.path() / "sweep" / file), sha256OfFile(dir.path() / "one" / file)) << file;
  }
}

TEST(Mpi, AFailingRankEndsTheJobWithItsMessage) {
  SKIP_WITHOUT_MPI();
  TemporaryDirectory dir;
  // A file where rank 1's shard folder must go: rank 1 fails, rank 0 would run on.
  test::writeFile(dir.path() / "sweep" / "shards" / "shard-0001-of-0002", "in the way\n");
  auto args = runArgs(dir.path() / "sweep");
  args[3] = "400";  // --samples: rank 0 has work left when rank 1 fails
  args[5] = "100";  // --net-batch
  const auto job = mpirun(2, args, dir.path());
  EXPECT_NE(job.exitCode, 0) << job.output;
  EXPECT_NE(job.exitCode, 124) << "the job hung:\n" << job.output;
  EXPECT_NE(job.output.find("vsd-sumo: error: rank 1 of 2 (shard 1 of 2): "), std::string::npos) << job.output;
  EXPECT_NE(job.output.find("shard-0001-of-0002: exists and is a file vsd-sumo did not write, not a run folder"), std::string::npos) << job.output;
  EXPECT_FALSE(fs::exists(dir.path() / "sweep" / "shards" / "shard-0000-of-0002" / "manifest.json"));
}

TEST(Mpi, MoreRanksThanBatchesIsOneErrorLine) {
  SKIP_WITHOUT_MPI();
  TemporaryDirectory dir;
  auto args = runArgs(dir.path() / "sweep");
  args[3] = "20";  // --samples: 2 batches of 10 for 3 ranks
  const auto job = mpirun(3, args, dir.path());
  EXPECT_NE(job.exitCode, 0) << job.output;
  EXPECT_NE(job.exitCode, 124) << "the job hung:\n" << job.output;
  EXPECT_EQ(count(job.output, "vsd-sumo: error:"), 1u) << job.output;
  EXPECT_NE(job.output.find("3 shards (or ranks) but the sweep has only 2 batches"), std::string::npos)
      << job.output;
  EXPECT_FALSE(fs::exists(dir.path() / "sweep" / "shards"));
}

TEST(Mpi, ExportOnTwoRanksGivesTheDatasetOfOneProcess) {
  SKIP_WITHOUT_MPI();
  TemporaryDirectory dir;
  const std::vector<std::string> map = {"export", "--opendrive",
                                        (test::sourceDir() / "sumo_nets/opendrive_curve/curve.xodr").string(),
                                        "--routes",
                                        (test::sourceDir() / "sumo_nets/opendrive_curve/curve.rou.xml").string(),
                                        "--end", "40"};
  auto one = map;
  one.insert(one.begin(), {test::vsdSumo().string(), "--quiet"});
  one.insert(one.end(), {"--out", (dir.path() / "one.h5").string()});
  ASSERT_EQ(test::run(one, dir.path()).exitCode, 0);
  auto two = map;
  two.insert(two.end(), {"--out", (dir.path() / "two.h5").string()});
  const auto job = mpirun(2, two, dir.path());
  ASSERT_EQ(job.exitCode, 0) << job.output;
  EXPECT_NE(job.output.find("2 MPI ranks, windows spread over them"), std::string::npos) << job.output;
  EXPECT_EQ(sha256OfFile(dir.path() / "two.h5"), sha256OfFile(dir.path() / "one.h5"));
  EXPECT_FALSE(fs::exists(dir.path() / ".two.h5.parts"));  // the ranks' parts are gone

}

TEST(Slurm, ArrayScriptRunsOneShardPerTaskAndTheShardsMergeIntoOneRun) {
  TemporaryDirectory dir;
  const auto one = [&] {
    std::vector<std::string> argv = {test::vsdSumo().string(), "--quiet"};
    const auto args = runArgs(dir.path() / "one");
    argv.insert(argv.end(), args.begin(), args.end());
    return test::run(argv, dir.path());
  }();
  ASSERT_EQ(one.exitCode, 0) << one.output;
  const std::string script = (test::sourceDir() / "tools/slurm/run_shard.sh").string();
  auto task = [&](int id, int count, int max) {
    return test::run({"env", "VSD_SUMO=" + test::vsdSumo().string(), "SLURM_ARRAY_TASK_ID=" + std::to_string(id),
                      "SLURM_ARRAY_TASK_COUNT=" + std::to_string(count), "SLURM_ARRAY_TASK_MIN=0",
                      "SLURM_ARRAY_TASK_MAX=" + std::to_string(max), "bash", script,
                      test::scenarioFile("acc_lk.yaml").string(), (dir.path() / "sweep").string(), "--samples", "40",
                      "--net-batch", "10", "--seed", "3"},
                     dir.path());
  };
  for (int id : {1, 0}) {
    const auto result = task(id, 2, 1);
    ASSERT_EQ(result.exitCode, 0) << result.output;
  }
  const auto stepped = task(0, 2, 2);  // --array=0-2:2 has 2 tasks but would name shard 2/2
  EXPECT_EQ(stepped.exitCode, 2) << stepped.output;
  EXPECT_NE(stepped.output.find("the array must be 0-<N-1> without steps"), std::string::npos) << stepped.output;

  const auto merged = test::run({test::vsdSumo().string(), "--quiet", "merge", (dir.path() / "sweep").string()},
                                dir.path());
  ASSERT_EQ(merged.exitCode, 0) << merged.output;
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    EXPECT_EQ(sha256OfFile(dir.path() / "sweep" / file), sha256OfFile(dir.path() / "one" / file)) << file;
  }
}
