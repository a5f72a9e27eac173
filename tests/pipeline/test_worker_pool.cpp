#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <thread>

#include "test_support.hpp"
#include "vsd/sim/activity.hpp"
#include "vsd/core/bytes.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/pipeline/worker_pool.hpp"

using namespace vsd;
using namespace vsd::pipeline;
namespace fs = std::filesystem;

namespace {

std::vector<char> bytesOf(int value) {
  ByteWriter writer;
  writer.put(value);
  return writer.bytes();
}

int valueOf(const std::vector<char>& bytes) {
  ByteReader reader(bytes);
  return reader.get<int>();
}

bool processExists(pid_t pid) { return ::kill(pid, 0) == 0; }

fs::path g_atexit_marker;
/// Writes the marker while a test waits for it (none after the test: the folder is gone).
extern "C" void writeAtexitMarker() {
  if (!g_atexit_marker.empty()) test::writeFile(g_atexit_marker, "the parent's atexit handler ran");
}

}  // namespace

TEST(WorkerPool, ACrashIsReportedWithTheSignalAndWhatTheWorkerWasDoing) {
  WorkerPool pool(1, [](int, WorkerChannel& channel) {
    channel.send(bytesOf(1));
    reportSubject(17);
    reportSimulationTime(2.4);
    const ActivityScope in_controller(Activity::Controller);
    std::raise(SIGSEGV);
  });
  EXPECT_EQ(valueOf(pool.receive(0)), 1);  // sent before the crash: still delivered
  try {
    pool.receive(0);
    FAIL() << "expected WorkerLost";
  } catch (const WorkerLost& lost) {
    EXPECT_EQ(lost.fault().kind, WorkerFault::Kind::Signal);
    EXPECT_EQ(lost.fault().signal, SIGSEGV);
    EXPECT_EQ(lost.fault().activity.activity, Activity::Controller);
    EXPECT_EQ(lost.fault().activity.subject, 17);
    EXPECT_DOUBLE_EQ(lost.fault().activity.time, 2.4);
    EXPECT_NE(std::string(lost.what()).find("Segmentation fault"), std::string::npos) << lost.what();
  }
}

TEST(WorkerPool, ExitInAWorkerSkipsTheParentsAtexitHandlersAndIsReported) {
  TemporaryDirectory dir;
  g_atexit_marker = dir.path() / "marker";
  std::atexit(writeAtexitMarker);  // registered in the parent (runs at the test program's exit)
  WorkerPool pool(1, [](int, WorkerChannel&) {
    const ActivityScope in_controller(Activity::Controller);
    std::exit(0);  // a plugin ending the process "successfully"
  });
  try {
    pool.receive(0);
    FAIL() << "expected WorkerLost";
  } catch (const WorkerLost& lost) {
    EXPECT_EQ(lost.fault().kind, WorkerFault::Kind::Exit);
    EXPECT_EQ(lost.fault().exitCode, 0);
    EXPECT_EQ(lost.fault().what(), "ended the process (exit code 0)");
  }
  EXPECT_FALSE(fs::exists(g_atexit_marker));  // the worker's exit() ran none of the parent's handlers
  g_atexit_marker.clear();  // the parent's own exit writes nothing into a removed folder
}

TEST(WorkerPool, TheWatchdogStopsAHangAndARestartedWorkerGoesOn) {
  WatchdogOptions watchdog;
  watchdog.stepTimeout = 0.2;
  int attempt = 0;  // the parent's state; a restarted worker sees its value at the restart
  WorkerPool pool(1, [&attempt](int, WorkerChannel& channel) {
    if (attempt == 0) {
      const ActivityScope stepping(Activity::SumoStep);
      for (;;) ::pause();
    }
    channel.send(bytesOf(attempt));
  }, watchdog);
  const auto start = std::chrono::steady_clock::now();
  try {
    pool.receive(0);
    FAIL() << "expected WorkerLost";
  } catch (const WorkerLost& lost) {
    EXPECT_EQ(lost.fault().kind, WorkerFault::Kind::Timeout);
    EXPECT_EQ(lost.fault().activity.activity, Activity::SumoStep);
    EXPECT_DOUBLE_EQ(lost.fault().limit, 0.2);
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  attempt = 1;
  pool.restart(0);
  EXPECT_EQ(valueOf(pool.receive(0)), 1);
  pool.finish();
  EXPECT_EQ(pool.restarts(), 1);
}

// While the parent waits for worker 0, worker 1 exits inside its controller; its
// record still says "controller" and the watchdog sees that activity last past the
// limit. It must still be reported as the exit it was, not as a hang.
TEST(WorkerPool, AWorkerThatExitedWhileTheParentReadAnotherIsNotTakenForAHang) {
  WatchdogOptions watchdog;
  watchdog.stepTimeout = 0.2;
  WorkerPool pool(2, [](int worker, WorkerChannel& channel) {
    const ActivityScope in_controller(Activity::Controller);
    if (worker == 1) std::exit(0);
    std::this_thread::sleep_for(std::chrono::milliseconds(600));  // outlasts the limit: worker 0 times out
    channel.send(bytesOf(worker));
  }, watchdog);
  auto fault_of = [&pool](int worker) {
    try {
      pool.receive(worker);
    } catch (const WorkerLost& lost) {
      return lost.fault();
    }
    ADD_FAILURE() << "expected WorkerLost from worker " << worker;
    return WorkerFault{};
  };
  EXPECT_EQ(fault_of(0).kind, WorkerFault::Kind::Timeout);
  const WorkerFault exited = fault_of(1);
  EXPECT_EQ(exited.kind, WorkerFault::Kind::Exit) << exited.what();
  EXPECT_EQ(exited.exitCode, 0);
}

TEST(WorkerPool, IdleWorkersAreNotStoppedByTheWatchdogAndErrorsKeepTheirType) {
  WatchdogOptions watchdog;
  watchdog.stepTimeout = 0.05;
  WorkerPool pool(2, [](int worker, WorkerChannel& channel) {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // Idle: not watched
    if (worker == 1) throw ConfigError("bad parameter");
    channel.send(bytesOf(worker));
  }, watchdog);
  EXPECT_EQ(valueOf(pool.receive(0)), 0);
  EXPECT_THROW(pool.receive(1), ConfigError);
}

TEST(WorkerPool, ASignalToTheParentStopsTheWaitAndEveryWorker) {
  installInterruptHandlers();
  pid_t worker_pid = 0;
  {
    std::array<int, 2> fds{};
    ASSERT_EQ(::pipe(fds.data()), 0);
    WorkerPool pool(1, [&fds](int, WorkerChannel&) {
      const pid_t self = ::getpid();
      [[maybe_unused]] auto written = ::write(fds[1], &self, sizeof(self));
      const ActivityScope in_controller(Activity::Controller);
      for (;;) ::pause();  // a hang the watchdog (10 s) has not caught yet
    });
    ASSERT_EQ(::read(fds[0], &worker_pid, sizeof(worker_pid)), static_cast<ssize_t>(sizeof(worker_pid)));
    std::thread([] {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      ::kill(::getpid(), SIGTERM);  // to this process only, not its group
    }).detach();
    const auto start = std::chrono::steady_clock::now();
    try {
      pool.receive(0);
      FAIL() << "expected InterruptedError";
    } catch (const InterruptedError& error) {
      EXPECT_EQ(error.exitCode(), 143);
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
    ::close(fds[0]);
    ::close(fds[1]);
  }
  clearInterruption();
  EXPECT_FALSE(processExists(worker_pid));  // killed and reaped when the pool was destroyed
}
