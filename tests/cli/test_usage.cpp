// Usage errors (docs/cli.md): one line naming the unknown word and the nearest known one,
// exit code 2; runtime failures exit 1; old spellings work with a one-line note.
#include <gtest/gtest.h>

#include <algorithm>

#include "test_support.hpp"

using namespace vsd;
namespace fs = std::filesystem;

namespace {

/// stderr only (stdout discarded).
ProcessResult errorsOf(const std::vector<std::string>& args, const fs::path& work) {
  std::string command = test::vsdSumo().string();
  for (const auto& arg : args) command += " '" + arg + "'";
  return test::run({"sh", "-c", command + " >/dev/null"}, work);
}

std::size_t lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

}  // namespace

TEST(Usage, UnknownWordsNameTheNearestKnownOneAndExitTwo) {
  TemporaryDirectory dir;
  const auto acc = test::scenarioFile("acc.yaml").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"rnu", acc}, "unknown subcommand 'rnu' — did you mean 'run'?"},
      {{"run", acc, "--sample", "50"}, "run: unknown option '--sample' — did you mean '--samples'?"},
      {{"scenario", "exprt", acc}, "scenario: unknown subcommand 'exprt' — did you mean 'export'?"},
      {{"trian", "--data", "x"}, "unknown subcommand 'trian' — did you mean 'train'?"},  // handed to vsd-sumo-ml
      {{"predict", "--model", "cv", "--data", "x", "--out", "y", "--futurs", "3"},
       "predict: unknown option '--futurs' — did you mean '--futures'?"},
      {{"frobnicate"}, "unknown subcommand 'frobnicate'; the subcommands are run, export"},
      {{}, "vsd-sumo needs a subcommand: run, export"},
      {{"run", acc, "--samples", "0"}, "--samples: got '0', expected 1 .. 100000000"},  // a value out of its range
  };
  for (const auto& [args, expected] : cases) {
    const auto result = errorsOf(args, dir.path());
    EXPECT_EQ(result.exitCode, 2) << args.front() << ": " << result.output;
    EXPECT_EQ(lines(result.output), 1u) << result.output;
    EXPECT_NE(result.output.find(expected), std::string::npos) << result.output;
  }
  // A runtime failure is not a usage error.
  const auto missing_model = errorsOf({"evaluate", "--model", (dir.path() / "none.pt").string(), "--data", acc}, dir.path());
  EXPECT_EQ(missing_model.exitCode, 1) << missing_model.output;
}

TEST(Usage, OldSpellingsWorkWithOneNote) {
  TemporaryDirectory dir;
  const auto out = dir.path() / "out";
  const auto result = errorsOf({"run", test::scenarioFile("acc.yaml").string(), "--samples", "4", "--batch", "2",
                                "--out", out.string(), "-q"},
                               dir.path());
  EXPECT_EQ(result.exitCode, 0) << result.output;
  EXPECT_EQ(result.output, "vsd-sumo: note: run --batch is deprecated; use --net-batch (the old spelling still works "
                           "for now)\n");
  EXPECT_NE(readTextFile(out / "manifest.json").find("\"batch\": 2"), std::string::npos);
}

TEST(Usage, CriteriaThatAreNotComparisonsAreRefusedBeforeAnyWork) {
  TemporaryDirectory dir;
  for (const auto& [criterion, expected] : std::vector<std::pair<std::string, std::string>>{
           {"d_min = 2", "'=' is not a comparison"},
           {"d_min", "neither a comparison (e.g. 'd_min < 2') nor a criterion of"},
           {"d_min < 2, a_min < 0", "unexpected ','"},
           {"d_min < 1e400", "the number 1e400 is out of range"}}) {
    const auto out = dir.path() / "search";
    const auto result = errorsOf({"search", test::scenarioFile("acc.yaml").string(), "--criterion", criterion,
                                  "--budget", "8", "--initial", "4", "--round", "4", "--out", out.string()},
                                 dir.path());
    EXPECT_EQ(result.exitCode, 2) << result.output;  // the flag's text is wrong: a usage error
    EXPECT_EQ(lines(result.output), 1u) << result.output;
    EXPECT_NE(result.output.find(expected), std::string::npos) << criterion << ": " << result.output;
    EXPECT_FALSE(fs::exists(out / "manifest.json"));
  }
}
