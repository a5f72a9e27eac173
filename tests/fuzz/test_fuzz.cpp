// The fault-injection and fuzz suite (README "Fault-injection and fuzz suite").
// One ctest entry with a fixed seed; VSD_FUZZ_SEED and VSD_FUZZ_SCALE (a factor on
// the number of cases per category) make the longer local mode:
//
//   VSD_FUZZ_SCALE=20 VSD_FUZZ_SEED=7 build/tests/test_fuzz
//
// VSD_FUZZ_ONLY=hostile runs one category; VSD_FUZZ_CASES=1 lists every case with its exit
// code, time and peak memory (results/robustness/hostile.txt is made so; docs/robustness.md).
//
// Every case runs vsd-sumo on a mutated input and checks the oracle of
// fuzz_support.hpp; a failure lists each broken case with its command.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>

#include "fuzz_cases.hpp"
#include "vsd/core/files.hpp"

using namespace vsd;
using namespace vsd::fuzz;

namespace {

std::uint64_t environmentNumber(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text != nullptr && *text != '\0' ? std::strtoull(text, nullptr, 10) : fallback;
}

struct Category {
  std::string name;
  std::size_t count;  ///< cases at scale 1 (CI)
  std::function<std::vector<Case>(const Fixtures&, Random&, std::size_t)> generate;
};

}  // namespace

TEST(FaultInjection, NoCrashNoHangNoSilentSuccessNoCompleteLookingPartialOutput) {
  const std::uint64_t seed = environmentNumber("VSD_FUZZ_SEED", 1);
  const std::uint64_t scale = std::max<std::uint64_t>(1, environmentNumber("VSD_FUZZ_SCALE", 1));
  TemporaryDirectory dir("vsd-fuzz");
  const Fixtures fixtures = buildFixtures(dir.path());

  // CI counts: the suite must stay within 150 s on CI's two cores (about 2.5 s per
  // vsd-sumo run on a quiet machine; a kill case runs twice). VSD_FUZZ_SCALE=20 is the
  // local mode.
  const std::vector<Category> categories = {
      {"flags", 5, flagCases},  {"yaml", 3, scenarioYamlCases}, {"dataset", 5, datasetCases},
      {"model", 3, modelCases}, {"kills", 8, killCases},        {"plugins", 6, pluginCases},
      {"hostile", 8, hostileInputCases},  // every class of hostile input once (issue 29)
      {"issue29", 16, issueReproductionCases},  // its reproductions exactly as reported
  };
  const char* only = std::getenv("VSD_FUZZ_ONLY");
  const bool list_cases = environmentNumber("VSD_FUZZ_CASES", 0) != 0;
  std::vector<std::string> failures;
  for (const auto& category : categories) {
    if (only != nullptr && *only != '\0' && category.name != only) continue;
    // Each category draws from its own stream: adding cases to one keeps the others.
    Random random(seed * 1000003ULL + std::hash<std::string>{}(category.name));
    const auto cases = category.generate(fixtures, random, category.count * scale);
    std::map<int, std::size_t> exits;
    double seconds = 0.0;
    Verdict slowest;
    Verdict largest;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const Verdict verdict = runCase(cases[i], caseFolder(fixtures, category.name + "-work", i));
      ++exits[verdict.exitCode];
      seconds += verdict.seconds;
      if (verdict.seconds > slowest.seconds) slowest = verdict;
      if (verdict.peakMiB > largest.peakMiB) largest = verdict;
      if (list_cases) {
        std::printf("  %-8s exit %3d %6.2f s %7.1f MiB  %s\n", category.name.c_str(), verdict.exitCode, verdict.seconds,
                    verdict.peakMiB, verdict.name.c_str());
      }
      if (!verdict.problems.empty()) {
        failures.push_back(fmt::format("{}\n    {}", verdict.name, fmt::join(verdict.problems, "\n    ")));
      }
    }
    std::string distribution;
    for (const auto& [code, n] : exits) distribution += fmt::format(" exit {}: {}", code, n);
    std::printf("%-8s %4zu cases in %6.1f s;%s; slowest %.1f s, largest peak memory %.0f MiB\n",
                category.name.c_str(), cases.size(), seconds, distribution.c_str(), slowest.seconds, largest.peakMiB);
  }
  EXPECT_TRUE(failures.empty()) << failures.size() << " cases broke the oracle (seed " << seed << ", scale " << scale
                                << "):\n"
                                << fmt::format("{}", fmt::join(failures, "\n"));
}
