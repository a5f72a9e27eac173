// `run` interrupted at awkward moments: killed (SIGKILL) at every write and
// rename point of its parent process, and signalled (SIGINT / SIGTERM to the
// parent alone) in every phase, with one and two jobs. Whatever happens, the
// output folder holds its old set or its new one — never a mix, never a file
// that looks complete but is not — and a signal stops the workers and keeps the
// old outputs. `export` keeps the old dataset file when killed or signalled
// while finishing it. Each case runs in a forked copy of this test process (no
// start-up cost), with the fault-injection hooks of vsd/core/fault.hpp.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "test_support.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/progress.hpp"
#include "vsd/pipeline/map_export.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/vector/dataset.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

RunOptions smallRun(const fs::path& out, std::uint64_t seed, int jobs) {
  RunOptions options;
  options.scenarioFile = test::scenarioFile("acc.yaml");
  options.outputDir = out;
  options.samples = 2;  // two batches: the parent writes twice before it commits
  options.batch = 1;
  options.seed = seed;
  options.jobs = jobs;
  return options;
}

/// Runs `work` in a forked child with VSD_FAULT / VSD_FAULT_TRACE set and
/// signals handled as by the CLI. The child exits 0 on success, 128 + signal when
/// interrupted (also after completing), 1 on an error. Returns the wait status.
/// Its TMPDIR is a folder of its own: a child that exits (on an error or signal too) must
/// leave it empty; what a SIGKILL leaves there is removed with it.
int inChild(const std::function<void()>& work, const std::string& fault, const fs::path& trace = {}) {
  const TemporaryDirectory scratch("vsd-child-tmp");
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("TMPDIR", scratch.path().c_str(), 1);
    ::setenv("VSD_FAULT", fault.c_str(), 1);
    ::setenv("VSD_FAULT_TRACE", trace.c_str(), 1);
    reloadFaultInjection();
    Progress::setEnabled(false);
    installInterruptHandlers();
    int code = 0;
    try {
      work();
      if (interrupted()) code = 128 + interruptSignal();
    } catch (const InterruptedError& error) {
      code = error.exitCode();
    } catch (const std::exception&) {
      code = 1;
    }
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFEXITED(status)) {
    EXPECT_TRUE(fs::is_empty(scratch.path())) << "exit " << WEXITSTATUS(status) << " with '" << fault
                                               << "' left a scratch folder in TMPDIR";
  }
  return status;
}

int runInChild(const RunOptions& options, const std::string& fault, const fs::path& trace = {}) {
  return inChild([&options] { runScenarios(options); }, fault, trace);
}

struct TracedPoint {
  long pid;
  std::string point;
};

std::vector<TracedPoint> readTrace(const fs::path& trace) {
  std::vector<TracedPoint> points;
  std::istringstream text(readTextFile(trace));
  for (TracedPoint entry; text >> entry.pid >> entry.point;) points.push_back(entry);
  return points;
}

bool alive(long pid) {
  if (::kill(static_cast<pid_t>(pid), 0) != 0) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string id, comm, state;
  stat >> id >> comm >> state;
  return state != "Z";
}

class RunInterruptions : public ::testing::Test {
 protected:
  void SetUp() override {
    out_ = dir_.path() / "out";
    runScenarios(smallRun(out_, 1, 1));  // the earlier, complete run
    oldSet_ = test::listedOutputs(out_);
    fs::copy(out_, dir_.path() / "old", fs::copy_options::recursive);
  }
  void restoreOld() {
    fs::remove_all(out_);
    fs::copy(dir_.path() / "old", out_, fs::copy_options::recursive);
  }

  TemporaryDirectory dir_;
  fs::path out_;
  std::map<std::string, std::string> oldSet_;
};

}  // namespace

TEST_F(RunInterruptions, AKillAtEveryWriteAndRenamePointLeavesTheOldOrTheNewSet) {
  // The parent's points of an uninterrupted update, in order ("#n" counts repeats).
  const fs::path trace = dir_.path() / "trace.txt";
  ASSERT_EQ(runInChild(smallRun(dir_.path() / "new", 2, 1), "", trace), 0);
  const auto new_set = test::listedOutputs(dir_.path() / "new");
  ASSERT_NE(new_set, oldSet_);
  const auto traced = readTrace(trace);
  long parent = 0;
  for (const auto& entry : traced) {
    if (entry.point == "run.write") parent = entry.pid;
  }
  std::vector<std::string> points;
  std::map<std::string, int> repeats;
  for (const auto& entry : traced) {
    if (entry.pid == parent && entry.point != "pool.fork") {
      points.push_back(entry.point + "#" + std::to_string(++repeats[entry.point]));
    }
  }
  ASSERT_EQ(points.size(), 16u);  // 2 batches written; 3 files staged and flushed; manifest, decide, unlink, 3 renames, publish, cleanup

  bool decided = false;
  for (const auto& point : points) {
    decided = decided || point.rfind("folder.unlink-manifest", 0) == 0;
    restoreOld();
    const int status = runInChild(smallRun(out_, 2, 1), "kill@" + point);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << point;
    // A reader completes a decided update, or sees the old set; every hash is checked.
    const auto problems = checkOutputFolder(out_, /*hashes=*/true);
    EXPECT_TRUE(problems.empty()) << point << ": " << problems.front();
    EXPECT_EQ(test::listedOutputs(out_), decided ? new_set : oldSet_) << point;
    const auto validation = vector::validateDataset(out_);
    EXPECT_TRUE(validation.ok()) << point << ": " << validation.problems.front();
  }
  // The next run finds whatever the last kill left, cleans it up and completes.
  restoreOld();
  ASSERT_TRUE(WIFSIGNALED(runInChild(smallRun(out_, 2, 1), "kill@run.write#2")));
  EXPECT_FALSE(test::hiddenEntries(out_).empty());  // the killed run's staging folder
  runScenarios(smallRun(out_, 2, 1));
  EXPECT_TRUE(test::hiddenEntries(out_).empty()) << test::hiddenEntries(out_).front();
  EXPECT_EQ(test::listedOutputs(out_), new_set);
}

TEST_F(RunInterruptions, ASignalInAnyPhaseStopsTheWorkersAndKeepsTheOldOutputs) {
  // The signal reaches the parent while it forks a worker, while a worker waits
  // for netconvert or simulates, while the parent writes, and while it flushes
  // the finished files before putting them in place.
  const std::vector<std::pair<std::string, int>> phases = {
      {"term@pool.fork", 143},        {"int-parent@netconvert.wait", 130}, {"term-parent@sumo.step#3", 143},
      {"int@run.write", 130},         {"term@folder.fsync:dataset.h5", 143}, {"int@folder.manifest", 130}};
  for (const int jobs : {1, 2}) {
    for (const auto& [fault, code] : phases) {
      const fs::path trace = dir_.path() / ("trace-" + std::to_string(jobs) + fault + ".txt");
      const int status = runInChild(smallRun(out_, 2, jobs), fault, trace);
      ASSERT_TRUE(WIFEXITED(status)) << fault;
      EXPECT_EQ(WEXITSTATUS(status), code) << fault << " --jobs " << jobs;
      EXPECT_EQ(test::listedOutputs(out_), oldSet_) << fault << " --jobs " << jobs;
      EXPECT_TRUE(test::hiddenEntries(out_).empty()) << fault << ": " << test::hiddenEntries(out_).front();
      std::set<long> workers;
      for (const auto& entry : readTrace(trace)) {
        if (entry.point == "worker.start") workers.insert(entry.pid);
      }
      for (const long worker : workers) EXPECT_FALSE(alive(worker)) << fault << ": worker " << worker << " survived";
    }
  }
}

TEST(ExportInterruptions, TheOldDatasetIsKeptWhenKilledOrSignalledWhileFinishing) {
  TemporaryDirectory dir;
  const fs::path map = test::sourceDir() / "sumo_nets" / "opendrive_curve";
  auto exporting = [&](std::uint64_t seed) {
    ExportOptions options;
    options.openDrive = map / "curve.xodr";
    options.source.routes = {map / "curve.rou.xml"};
    options.output = dir.path() / "od.h5";
    options.end = 20.0;
    options.seed = seed;
    return [options] { exportMap(options); };
  };
  ASSERT_EQ(inChild(exporting(1), ""), 0);
  const auto old_hash = sha256OfFile(dir.path() / "od.h5");
  // Killed just before the finished file gets its name; signalled while it is
  // flushed (the last moment to keep the old one).
  const int killed = inChild(exporting(2), "kill@atomic.rename:od.h5");
  EXPECT_TRUE(WIFSIGNALED(killed) && WTERMSIG(killed) == SIGKILL);
  const int signalled = inChild(exporting(2), "term@atomic.fsync:od.h5");
  EXPECT_TRUE(WIFEXITED(signalled) && WEXITSTATUS(signalled) == 143);
  EXPECT_EQ(sha256OfFile(dir.path() / "od.h5"), old_hash);
  ASSERT_EQ(inChild(exporting(2), ""), 0);
  EXPECT_NE(sha256OfFile(dir.path() / "od.h5"), old_hash);
  // The parts the killed and the signalled export left are gone.
  EXPECT_TRUE(test::hiddenEntries(dir.path()).empty()) << test::hiddenEntries(dir.path()).front();
}
