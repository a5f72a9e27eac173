#include <gtest/gtest.h>

#include <fstream>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/core/provenance.hpp"

using namespace vsd;
namespace fs = std::filesystem;

TEST(AtomicOutput, NothingAppearsUntilCommitAndAbandonedFilesVanish) {
  TemporaryDirectory dir;
  const fs::path target = dir.path() / "result.csv";
  {
    AtomicOutput output(target);
    std::ofstream(output.tempPath()) << "partial";
    EXPECT_FALSE(fs::exists(target));
  }  // destroyed without commit: as if an exception had unwound
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir.path()));

  AtomicOutput output(target);
  std::ofstream(output.tempPath()) << "complete";
  output.commit();
  EXPECT_EQ(readTextFile(target), "complete");
}

TEST(AtomicOutput, ReplacesAnOlderFileOnlyWhenComplete) {
  TemporaryDirectory dir;
  const fs::path target = dir.path() / "manifest.json";
  writeTextFileAtomically(target, "old");
  {
    AtomicOutput output(target);
    std::ofstream(output.tempPath()) << "new but unfinished";
  }
  EXPECT_EQ(readTextFile(target), "old");
  writeTextFileAtomically(target, "new");
  EXPECT_EQ(readTextFile(target), "new");
}

TEST(Files, Sha256MatchesKnownDigest) {
  EXPECT_EQ(sha256OfString("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  TemporaryDirectory dir;
  const auto path = test::writeFile(dir.path() / "abc.txt", "abc");
  EXPECT_EQ(sha256OfFile(path), sha256OfString("abc"));
  EXPECT_THROW(sha256OfFile(dir.path() / "missing"), IoError);
}

TEST(Files, AnOutputFileThatCannotBeAFileIsRefusedBeforeAnyWork) {
  TemporaryDirectory dir;
  const auto folder = dir.path() / "folder";
  std::filesystem::create_directories(folder);
  const auto file = dir.path() / "file";
  std::ofstream(file) << "x";
  EXPECT_NO_THROW(requireFileOutputPath(dir.path() / "new" / "deeper" / "model.pt", "--out"));
  EXPECT_NO_THROW(requireFileOutputPath(file, "--out"));  // an older file is replaced
  try {
    requireFileOutputPath(folder, "--out");
    ADD_FAILURE() << "a folder was accepted as an output file";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("--out: got '" + folder.string() + "', expected a file name (this is an "
                                             "existing folder)"),
              std::string::npos)
        << error.what();
  }
  EXPECT_THROW(requireFileOutputPath(file / "model.pt", "--out"), ConfigError);  // inside a file
  EXPECT_THROW(requireFileOutputPath("", "--out"), ConfigError);
  EXPECT_THROW(requireFileOutputPath(dir.path() / "x" / "..", "--out"), ConfigError);
}

// Committed results must name the code that ran: a dirty build may not write into
// <source>/results unless forced; anywhere else, and clean builds, are fine.
TEST(Provenance, DirtyBuildsMayNotWriteCommittedResults) {
  TemporaryDirectory tree;
  const BuildProvenance dirty{"0123456789ab", true};
  const BuildProvenance clean{"0123456789ab", false};
  const auto results = tree.path() / "results" / "paper";
  try {
    refuseDirtyCommittedResults(results, false, "--allow-dirty", dirty, tree.path());
    FAIL() << "a dirty build wrote committed results";
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("0123456789ab with uncommitted changes"), std::string::npos) << message;
    EXPECT_NE(message.find("--allow-dirty"), std::string::npos) << message;
  }
  EXPECT_NO_THROW(refuseDirtyCommittedResults(results, true, "--allow-dirty", dirty, tree.path()));
  EXPECT_NO_THROW(refuseDirtyCommittedResults(results, false, "--allow-dirty", clean, tree.path()));
  EXPECT_NO_THROW(refuseDirtyCommittedResults(tree.path() / "out" / "paper", false, "--allow-dirty", dirty, tree.path()));
  EXPECT_NO_THROW(refuseDirtyCommittedResults(tree.path() / "results_elsewhere", false, "--allow-dirty", dirty, tree.path()));
  // The version this binary prints carries the commit it was built from, and the flag.
  const auto built = buildProvenance();
  if (!built.commit.empty()) {
    EXPECT_NE(toolVersion().find("+" + built.commit), std::string::npos) << toolVersion();
    EXPECT_EQ(toolVersion().find("-dirty") != std::string::npos, built.dirty) << toolVersion();
  }
}
