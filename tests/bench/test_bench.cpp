// The bench library's own measuring (medians, resource accounting, failing processes,
// intervals) and one small benchmark end to end: what `vsd-sumo bench` prints rests on these.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "test_support.hpp"
#include "vsd/bench/deviations_bench.hpp"
#include "vsd/bench/measure.hpp"
#include "vsd/bench/run_bench.hpp"
#include "vsd/bench/scenario_bench.hpp"
#include "vsd/bench/search_bench.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;
using namespace vsd;

TEST(Bench, ChildProcessCpuTimeIsCountedAndAFailureNamesItsError) {
  TemporaryDirectory work("vsd-test-bench");
  const auto busy = bench::runChecked(
      {"sh", "-c", "i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done"}, work.path() / "busy.log");
  EXPECT_GT(busy.cpuSeconds, 0.0);
  EXPECT_GE(busy.result.seconds, 0.0);
  const auto usage = bench::Usage::children();
  EXPECT_GE(usage.cpu(), busy.cpuSeconds);
  const auto difference = usage - usage;
  EXPECT_DOUBLE_EQ(difference.cpu(), 0.0);
  try {
    bench::runChecked({"sh", "-c", "echo 'error: the disk is full' >&2; exit 3"}, work.path() / "failing.log");
    FAIL() << "a failing process was taken for a measurement";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), testing::HasSubstr("exit 3"));
    EXPECT_THAT(error.what(), testing::HasSubstr("the disk is full"));
  }
}

TEST(Bench, LoadAverageIsThreeNumbers) {
  EXPECT_TRUE(std::regex_match(bench::loadAverage(), std::regex(R"([0-9]+\.[0-9]{2} [0-9]+\.[0-9]{2} [0-9]+\.[0-9]{2})")))
      << bench::loadAverage();
}

TEST(Bench, WilsonIntervalOfKnownCounts) {
  const auto [low, high] = bench::wilsonInterval(5.0, 10.0);
  EXPECT_NEAR(low, 0.2366, 1e-4);
  EXPECT_NEAR(high, 0.7634, 1e-4);
  const auto [zero_low, zero_high] = bench::wilsonInterval(0.0, 20.0);
  EXPECT_NEAR(zero_low, 0.0, 1e-12);
  EXPECT_NEAR(zero_high, 0.1611, 1e-4);
  EXPECT_TRUE(std::isnan(bench::wilsonInterval(0.0, 0.0).first));
}

TEST(Bench, OptionsOutsideTheirRangesAreRefused) {
  bench::SearchBenchOptions search;
  search.seeds = 0;
  EXPECT_THROW(search.validate(), ConfigError);
  bench::DeviationsBenchOptions deviations;
  deviations.share = 1.0;
  EXPECT_THROW(deviations.validate(), ConfigError);
  deviations.share = 0.3;
  deviations.level = 0.0;
  EXPECT_THROW(deviations.validate(), ConfigError);
  deviations.level = 0.05;
  deviations.calibrationSamples = 79;  // three metrics and the path: one extreme p gives 4 / 80
  EXPECT_THROW(deviations.validate(), ConfigError);
  deviations.calibrationSamples = 80;
  EXPECT_NO_THROW(deviations.validate());
  deviations.calibrationSamples = 0;  // not ranked among runs at all
  EXPECT_NO_THROW(deviations.validate());
}

TEST(Bench, LibraryScenariosAreTheSortedYamlFilesOfAFolder) {
  TemporaryDirectory work("vsd-test-bench");
  EXPECT_THROW(bench::libraryScenarios(work.path()), ConfigError);
  test::writeFile(work.path() / "b.yaml", "");
  test::writeFile(work.path() / "a.yaml", "");
  test::writeFile(work.path() / "notes.txt", "");
  EXPECT_EQ(bench::libraryScenarios(work.path()),
            (std::vector<fs::path>{work.path() / "a.yaml", work.path() / "b.yaml"}));
}

TEST(Bench, IsolationBenchRunsBothIsolationsToTheSameBytes) {
  bench::IsolationBenchOptions options;
  options.scenario = test::scenarioFile("acc_lk.yaml");
  options.samples = 4;
  options.rounds = 2;
  const auto result = bench::runIsolationBench(options);
  ASSERT_EQ(result.runs.size(), 4u);
  EXPECT_EQ(result.runs[0].isolation, pipeline::RunOptions::Isolation::None);
  EXPECT_EQ(result.runs[2].isolation, pipeline::RunOptions::Isolation::Process);  // round 2 starts with the other
  EXPECT_TRUE(result.identical);
  EXPECT_GT(result.codecBytes, 0.0);
  EXPECT_GT(result.medians(pipeline::RunOptions::Isolation::Process).wall, 0.0);
}
