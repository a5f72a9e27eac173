// The vsd-sumo executable interrupted: a signal to the parent process alone
// (SIGINT or SIGTERM) ends it within seconds with 130 / 143, no worker left
// behind and the old outputs kept — also while a plugin loops forever.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <tuple>

#include "test_support.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

/// Runs vsd-sumo with VSD_FAULT / VSD_FAULT_TRACE set (empty: unset).
ProcessResult runVsd(const std::vector<std::string>& args, const fs::path& work, const std::string& fault = "",
                     const std::string& trace = "") {
  std::vector<std::string> argv = {test::vsdSumo().string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  if (!fault.empty()) ::setenv("VSD_FAULT", fault.c_str(), 1);
  if (!trace.empty()) ::setenv("VSD_FAULT_TRACE", trace.c_str(), 1);
  auto result = test::run(argv, work);
  ::unsetenv("VSD_FAULT");
  ::unsetenv("VSD_FAULT_TRACE");
  return result;
}

std::vector<std::string> runArgs(const fs::path& out, int seed, int jobs) {
  return {"run", test::scenarioFile("acc.yaml").string(), "--samples", "2", "--net-batch", "1", "--seed",
          std::to_string(seed), "--jobs", std::to_string(jobs), "--out", out.string()};
}

/// Processes (other than zombies) whose command line mentions `text`.
int processesMentioning(const std::string& text) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream cmdline(entry.path() / "cmdline", std::ios::binary);
    std::string line((std::istreambuf_iterator<char>(cmdline)), std::istreambuf_iterator<char>());
    std::ifstream stat(entry.path() / "stat");
    std::string pid, comm, state;
    stat >> pid >> comm >> state;
    if (state != "Z" && line.find(text) != std::string::npos) ++count;
  }
  return count;
}

}  // namespace

// (Every phase and every kill point of `run` is covered in-process by
// tests/pipeline/test_interruptions.cpp; here the executable's own handling.)
TEST(Interruptions, TheExitCodeSaysWhichSignalStoppedTheRun) {
  TemporaryDirectory dir;
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(runVsd(runArgs(out, 1, 1), dir.path()).exitCode, 0);
  const auto old_set = test::listedOutputs(out);
  // SIGINT while the parent writes; SIGTERM while one of two workers simulates.
  for (const auto& [fault, jobs, code] :
       std::vector<std::tuple<std::string, int, int>>{{"int@run.write", 1, 130}, {"term-parent@sumo.step#3", 2, 143}}) {
    const auto result = runVsd(runArgs(out, 2, jobs), dir.path(), fault);
    EXPECT_EQ(result.exitCode, code) << fault << ": " << result.output;
    EXPECT_NE(result.output.find("interrupted by SIG"), std::string::npos) << result.output;
    EXPECT_EQ(test::listedOutputs(out), old_set) << fault;
    EXPECT_TRUE(test::hiddenEntries(out).empty()) << fault << ": " << test::hiddenEntries(out).front();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_EQ(processesMentioning(out.string()), 0) << fault << ": a worker outlived the run";
  }
}

// Judging the parameter sets of a distribution (before a sweep, or all of them in a check)
// stops at a signal: no verdict, no outputs.
TEST(Interruptions, ASignalStopsJudgingTheSetsOfADistribution) {
  TemporaryDirectory dir;
  const fs::path variation = test::sourceDir() / "tests/interop/data/osc/cut_in_variation.xosc";
  const fs::path out = dir.path() / "out";
  for (const auto& [args, fault, code] : std::vector<std::tuple<std::vector<std::string>, std::string, int>>{
           {{"scenario", "check", variation.string()}, "int@osc.set#3", 130},
           {{"run", variation.string(), "--out", out.string()}, "term@osc.set#2", 143}}) {
    const auto result = runVsd(args, dir.path(), fault);
    EXPECT_EQ(result.exitCode, code) << fault << ": " << result.output;
    EXPECT_NE(result.output.find("interrupted by SIG"), std::string::npos) << result.output;
    EXPECT_EQ(result.output.find("would run"), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(Interruptions, SigtermToTheParentStopsAPluginThatLoopsForever) {
  TemporaryDirectory dir;
  const fs::path plugin = test::binaryDir() / "plugins" / "libvsd_misbehaving_egos.so";
  const auto scenario = test::writeFile(
      dir.path() / "hang.yaml",
      test::scenarioVariant("acc.yaml", "name: paper_ego\n      params: {time_gap: 2.0, set_speed: v_ego}",
                            "name: hanging_ego\n      library: " + plugin.string()));
  const fs::path out = dir.path() / "out";
  auto child = ChildProcess::spawn({test::vsdSumo().string(), "--quiet", "run", scenario.string(), "--samples", "4",
                                    "--out", out.string(), "--step-timeout", "600"},
                                   dir.path() / "log.txt");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const auto start = std::chrono::steady_clock::now();
  ::kill(child.pid(), SIGTERM);  // the parent alone, not its process group
  const auto result = child.wait();
  EXPECT_EQ(result.exitCode, 143) << result.output;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 3.0);
  EXPECT_FALSE(fs::exists(out));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(processesMentioning(out.string()), 0);
}
