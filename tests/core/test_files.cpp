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
