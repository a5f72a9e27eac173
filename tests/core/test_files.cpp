#include <gtest/gtest.h>

#include <fstream>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

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
