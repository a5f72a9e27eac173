// The README's quickstart, run exactly as a reader copies it: the lines between
// <!-- quickstart --> and <!-- /quickstart --> in README.md, in a fresh folder that holds
// what a clone holds at that point (the scenarios, and build/ with the built vsd-sumo).
// A README whose first commands fail is the first thing a new user meets, so every line
// must succeed, and the chain must reach every step the README promises.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

/// The shell lines of the fenced block between the quickstart markers (fences dropped).
std::vector<std::string> quickstartLines(const fs::path& readme) {
  std::ifstream in(readme);
  std::vector<std::string> lines;
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.find("<!-- quickstart -->") != std::string::npos) {
      inside = true;
    } else if (line.find("<!-- /quickstart -->") != std::string::npos) {
      break;
    } else if (inside && line.rfind("```", 0) != 0) {
      lines.push_back(line);
    }
  }
  return lines;
}

std::string joined(const std::vector<std::string>& lines) {
  std::ostringstream out;
  for (const auto& line : lines) out << line << '\n';
  return out.str();
}

}  // namespace

TEST(Quickstart, ReadmeLinesRunVerbatimFromAFreshFolder) {
  const auto lines = quickstartLines(vsd::test::sourceDir() / "README.md");
  ASSERT_FALSE(lines.empty()) << "README.md has no <!-- quickstart --> ... <!-- /quickstart --> block";
  const std::string text = joined(lines);
  // The chain the README promises: simulate, train, evaluate and compare, search, export.
  for (const char* step : {"vsd-sumo run ", "vsd-sumo train ", "vsd-sumo evaluate ", "vsd-sumo compare ",
                           "vsd-sumo search ", "vsd-sumo scenario export "}) {
    EXPECT_NE(text.find(step), std::string::npos) << "the quickstart lacks '" << step << "'";
  }

  // A fresh folder with what a clone has after `tools/setup.sh`: the scenarios, and the
  // build folder (a link to this build, so `build/vsd-sumo` and `$PWD/build` work as written).
  const fs::path work = vsd::test::binaryDir() / "tests" / "docs" / "quickstart";
  fs::remove_all(work);
  fs::create_directories(work);
  fs::copy(vsd::test::sourceDir() / "scenarios", work / "scenarios", fs::copy_options::recursive);
  fs::create_directory_symlink(vsd::test::binaryDir(), work / "build");

  // One shell, so that what a line sets (e.g. PATH) holds for the next, as in a terminal;
  // the first failing line stops it and is named.
  std::ostringstream script;
  script << "set -euo pipefail\n"
         << "trap 'echo \"quickstart line failed (exit $?): $BASH_COMMAND\" >&2' ERR\n"
         << "cd '" << work.string() << "'\n"
         << "export PATH='" << vsd::test::binaryDir().string() << "':\"$PATH\"\n"
         << "export SUMO_HOME=\"${SUMO_HOME:-/usr/share/sumo}\"\n"
         << text;
  const auto script_file = vsd::test::writeFile(work.parent_path() / "quickstart.sh", script.str());
  const auto result = vsd::test::run({"/bin/bash", script_file.string()}, work.parent_path());
  EXPECT_EQ(result.exitCode, 0) << "the README's quickstart failed after " << result.seconds << " s:\n"
                                << result.output;
  std::cout << "quickstart: " << lines.size() << " lines in " << result.seconds << " s\n";

  // What the README tells the reader to open exists.
  EXPECT_TRUE(fs::exists(work / "reports" / "acc_lk" / "report.html"));
  EXPECT_TRUE(fs::exists(work / "out" / "search_acc_lk" / "report.html"));
}
