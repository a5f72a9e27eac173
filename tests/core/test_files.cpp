#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
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

// --- AtomicOutput leftovers and OutputFolder --------------------------------------

namespace {

/// Writes `files` (name -> contents) as one committed set.
void commitSet(const fs::path& folder, const std::map<std::string, std::string>& files) {
  OutputFolder output(folder);
  for (const auto& [name, contents] : files) output.stageText(name, contents);
  output.commit(nlohmann::json{{"kind", "test"}});
}

std::map<std::string, std::string> hashesOf(const std::map<std::string, std::string>& files) {
  std::map<std::string, std::string> hashes;
  for (const auto& [name, contents] : files) hashes[name] = sha256OfString(contents);
  return hashes;
}

/// Runs `body` in a forked child with VSD_FAULT (and VSD_FAULT_TRACE) set; returns its wait status.
int inChild(const std::string& fault, const std::string& trace, const std::function<void()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("VSD_FAULT", fault.c_str(), 1);
    ::setenv("VSD_FAULT_TRACE", trace.c_str(), 1);
    reloadFaultInjection();
    try {
      body();
    } catch (...) {
      ::_exit(2);
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

}  // namespace

TEST(AtomicOutput, RemovesTemporaryFilesOfDeadProcessesOnly) {
  TemporaryDirectory dir;
  const fs::path target = dir.path() / "model.pt";
  // pid 2^22 + 1 exceeds Linux's pid_max: certainly not running; our own pid is.
  const auto dead = test::writeFile(dir.path() / ".model.pt.4194305.part", "left by a killed run");
  const auto alive = test::writeFile(dir.path() / (".model.pt." + std::to_string(::getppid()) + ".part"), "busy");
  const auto other = test::writeFile(dir.path() / ".other.pt.4194305.part", "another file's");
  AtomicOutput output(target);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(other));
}

TEST(OutputFolder, ReplacesTheSetAndListsEveryFileInTheManifest) {
  TemporaryDirectory dir;
  const fs::path folder = dir.path() / "out";
  const std::map<std::string, std::string> old_set = {{"a.csv", "old a"}, {"nets/b.xml", "old b"}};
  commitSet(folder, old_set);
  test::writeFile(folder / "notes.txt", "the user's own file");
  EXPECT_EQ(test::listedOutputs(folder), hashesOf(old_set));
  EXPECT_TRUE(checkOutputFolder(folder, true).empty());

  const std::map<std::string, std::string> new_set = {{"a.csv", "new a"}, {"c.h5", "new c"}};
  commitSet(folder, new_set);
  EXPECT_EQ(test::listedOutputs(folder), hashesOf(new_set));
  EXPECT_EQ(readTextFile(folder / "a.csv"), "new a");
  EXPECT_FALSE(fs::exists(folder / "nets"));  // the old set's file and its emptied folder
  EXPECT_EQ(readTextFile(folder / "notes.txt"), "the user's own file");  // never listed: untouched
  const auto manifest = nlohmann::json::parse(readTextFile(folder / "manifest.json"));
  EXPECT_EQ(manifest["kind"], "test");
  EXPECT_EQ(manifest["outputs"]["c.h5"]["bytes"], 5);
  EXPECT_TRUE(test::hiddenEntries(folder).empty()) << test::hiddenEntries(folder).front();
}

TEST(OutputFolder, AnAbandonedUpdateKeepsTheOldSetAndLeavesNothing) {
  TemporaryDirectory dir;
  const fs::path folder = dir.path() / "out";
  commitSet(folder, {{"a.csv", "old"}});
  {
    OutputFolder output(folder);
    output.stageText("a.csv", "new, but the run failed");
  }
  EXPECT_EQ(readTextFile(folder / "a.csv"), "old");
  EXPECT_TRUE(checkOutputFolder(folder, true).empty());
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 2);  // a.csv, manifest.json
  {
    OutputFolder output(dir.path() / "fresh");
    output.stageText("x.csv", "never committed");
  }
  EXPECT_FALSE(fs::exists(dir.path() / "fresh"));  // created by the failed writer, so removed with it
}

TEST(OutputFolder, ReadersRefuseIncompleteOrChangedFolders) {
  TemporaryDirectory dir;
  const fs::path folder = dir.path() / "out";
  test::writeFile(folder / "dataset.h5", "no manifest");
  EXPECT_THAT(checkOutputFolder(folder, false).front(), ::testing::HasSubstr("no manifest.json"));
  EXPECT_THROW(requireCompleteOutputFolder(folder, false), DatasetError);
  // A file no manifest lists is the user's: no commit replaces it (docs/output-policy.md).
  EXPECT_THROW(commitSet(folder, {{"dataset.h5", "0123456789"}}), ConfigError);
  EXPECT_EQ(readTextFile(folder / "dataset.h5"), "no manifest");
  fs::remove(folder / "dataset.h5");

  commitSet(folder, {{"dataset.h5", "0123456789"}});
  EXPECT_NO_THROW(requireCompleteOutputFolder(folder, true));
  test::writeFile(folder / "dataset.h5", "01234");  // truncated
  EXPECT_THAT(checkOutputFolder(folder, false).front(), ::testing::HasSubstr("5 bytes"));
  test::writeFile(folder / "dataset.h5", "0123456780");  // same size, other bytes
  EXPECT_TRUE(checkOutputFolder(folder, false).empty());
  EXPECT_THAT(checkOutputFolder(folder, true).front(), ::testing::HasSubstr("SHA-256"));
}

TEST(OutputFolder, OneWriterAtATimeAndAnOptionallyRefusedEarlierSet) {
  TemporaryDirectory dir;
  const fs::path folder = dir.path() / "out";
  commitSet(folder, {{"a.csv", "a"}});
  OutputFolder::Options refuse;
  refuse.refuseExisting = true;
  EXPECT_THROW(OutputFolder(folder, refuse), ConfigError);
  test::writeFile(dir.path() / "foreign" / "notes.txt", "mine");  // no manifest, but not ours to mix into
  EXPECT_THROW(OutputFolder(dir.path() / "foreign", refuse), ConfigError);
  fs::create_directories(dir.path() / "empty");
  EXPECT_NO_THROW(OutputFolder(dir.path() / "empty", refuse));
  OutputFolder writer(folder);
  EXPECT_THROW(OutputFolder{folder}, IoError);  // locked by `writer`
  test::writeFile(dir.path() / "file", "x");
  EXPECT_THROW(OutputFolder{dir.path() / "file"}, ConfigError);
}

TEST(OutputFolder, AKillAtAnyWriteOrRenamePointLeavesTheOldOrTheNewSet) {
  TemporaryDirectory dir;
  const fs::path folder = dir.path() / "out";
  const std::map<std::string, std::string> old_set = {{"a.csv", "old a"}, {"b.h5", "old b"}, {"gone.txt", "old"}};
  const std::map<std::string, std::string> new_set = {{"a.csv", "new a"}, {"b.h5", "new b"}, {"sub/c.svg", "new c"}};
  auto update = [&] { commitSet(folder, new_set); };

  // The points an update passes, in order (traced by one uninterrupted update).
  commitSet(folder, old_set);
  const fs::path trace = dir.path() / "trace.txt";
  ASSERT_EQ(inChild("", trace.string(), update), 0);
  std::vector<std::string> points;
  std::istringstream lines(readTextFile(trace));
  for (std::string pid, point; lines >> pid >> point;) points.push_back(point);
  EXPECT_GE(points.size(), 12u);
  EXPECT_NE(std::find(points.begin(), points.end(), "folder.decide"), points.end());

  for (const auto& point : points) {
    fs::remove_all(folder);
    commitSet(folder, old_set);
    const int status = inChild("kill@" + point, "", update);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << point;
    // What a reader sees right after the kill: the old set, or no manifest at all.
    const auto problems = checkOutputFolder(folder, true);  // also completes a decided update
    EXPECT_TRUE(problems.empty()) << point << ": " << problems.front();
    const auto listed = test::listedOutputs(folder);
    EXPECT_TRUE(listed == hashesOf(old_set) || listed == hashesOf(new_set)) << point;
    const bool decided = std::find(points.begin(), points.end(), point) > std::find(points.begin(), points.end(), "folder.decide");
    EXPECT_EQ(listed == hashesOf(new_set), decided) << point;
    EXPECT_EQ(fs::exists(folder / "gone.txt"), !decided) << point;
    // The next writer finds nothing left over.
    commitSet(folder, new_set);
    EXPECT_TRUE(test::hiddenEntries(folder).empty()) << point << ": " << test::hiddenEntries(folder).front();
  }
}

TEST(FaultInjection, SignalsActionsAtTheNthHitOfAPoint) {
  TemporaryDirectory dir;
  int status = inChild("exit0@test.point#3", "", [] {
    for (int i = 0; i < 2; ++i) faultPoint("test.point");
    faultPoint("other.point");
    ::_exit(7);  // not reached if the third hit had fired
  });
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 7);
  status = inChild("segv@test.*#2", "", [] {
    faultPoint("test.a");
    faultPoint("test.b");
  });
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGSEGV);
  status = inChild("exit0@test.point", "", [] {
    faultPoint("test.point");
    ::_exit(7);
  });
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
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
  const BuildProvenance dirty{"0123456789ab", true, {}};
  const BuildProvenance clean{"0123456789ab", false, {}};
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

TEST(Provenance, ModulesHaveTheirOwnCodeIdentity) {
  const auto built = buildProvenance();
  if (built.commit.empty()) GTEST_SKIP() << "built outside a git checkout: the tool version stands in";
  // Every module's code is identified on its own, so an experiment cache keeps artefacts
  // whose modules did not change.
  for (const char* module : {"core", "sim", "vector", "model", "experiment"}) {
    ASSERT_TRUE(built.modules.count(module)) << module;
    EXPECT_GE(built.modules.at(module).size(), 26u) << module << ": two tree ids";
  }
  EXPECT_NE(built.modules.at("model"), built.modules.at("sim"));
  EXPECT_EQ(codeIdentity({"core", "model"}),
            "core=" + built.modules.at("core") + ";model=" + built.modules.at("model") + ";");
  EXPECT_THROW(codeIdentity({"modle"}), Error);
}
