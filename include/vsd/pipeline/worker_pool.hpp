#pragma once
// Worker processes. Code we do not control — Ego controller plugins, libsumo on
// a foreign map — runs in forked workers, whatever --jobs is, so that its crash,
// exit() or hang is contained: the parent stays alive, learns what the worker
// was doing (vsd/sim/activity.hpp: whose controller, which SUMO step), records
// the fault and starts a fresh worker to go on.
//
// Each worker runs a body that sends framed messages back through a pipe; the
// parent receives them in the order it chooses, so results can be written in
// sample order whatever the number of workers.
//
// - A worker's vsd::Error is re-thrown in the parent with the same type.
// - A worker that dies (signal, exit()) or that the watchdog stops is reported
//   by receive() as WorkerLost with the fault and the worker's last activity.
// - The watchdog: an activity other than Idle that lasts longer than its limit
//   (WatchdogOptions) gets the worker's process group SIGKILLed.
// - The parent polls for SIGINT/SIGTERM at least every 100 ms while it waits
//   and throws InterruptedError; destroying the pool kills every worker's
//   process group (netconvert included) and reaps it.
// - Workers run in their own process group (a terminal's Ctrl-C reaches the
//   parent only, which then stops them), die with the parent
//   (PR_SET_PDEATHSIG), and get SIGINT/SIGTERM's default action. exit() called
//   by a plugin ends the worker at once (no atexit handler of the parent's
//   libraries runs in the copy of their state). Workers write no core dumps.

#include <sys/types.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/sim/activity.hpp"
#include "vsd/core/error.hpp"

namespace vsd::pipeline {

/// Limits of the watchdog.
struct WatchdogOptions {
  /// Default of --step-timeout (s).
  static constexpr double kDefaultStepTimeout = 10.0;
  /// Loading a simulation and netconvert may take this many times longer than a step.
  static constexpr double kLoadFactor = 30.0;

  /// Longest Ego controller call, libsumo step, or libsumo call for one
  /// scenario's vehicles (s); 1e-3 .. 86400.
  double stepTimeout = kDefaultStepTimeout;

  /// Throws ConfigError naming `flag` if stepTimeout is out of range.
  void validate(const std::string& flag = "--step-timeout") const;
  /// The limit for `activity` (s); infinite for Idle.
  double limitFor(Activity activity) const;
};

/// How a worker ended when it should not have.
struct WorkerFault {
  enum class Kind { Signal, Exit, Timeout };
  Kind kind = Kind::Exit;
  int signal = 0;       ///< Kind::Signal: the signal that ended it
  int exitCode = 0;     ///< Kind::Exit: its exit code
  double limit = 0.0;   ///< Kind::Timeout: the limit it exceeded (s)
  ActivityRecord::Snapshot activity;  ///< what it was doing when it ended
  /// "crashed (signal 11, Segmentation fault)", "ended the process (exit code 0)",
  /// "did not return within 10 s (watchdog, --step-timeout)".
  std::string what() const;
};

/// Thrown by WorkerPool::receive() for a worker that died or was stopped.
class WorkerLost : public SumoError {
 public:
  WorkerLost(int worker, WorkerFault fault);
  int worker() const { return worker_; }
  const WorkerFault& fault() const { return fault_; }

 private:
  int worker_;
  WorkerFault fault_;
};

class WorkerChannel {
 public:
  explicit WorkerChannel(int fd) : fd_(fd) {}
  /// Sends one data message to the parent.
  void send(const std::vector<char>& payload);

 private:
  friend class WorkerPool;
  void sendFrame(unsigned char type, const std::vector<char>& payload);
  int fd_;
};

class WorkerPool {
 public:
  using Body = std::function<void(int worker, WorkerChannel& channel)>;

  /// Forks `workers` processes running `body(worker, channel)`.
  WorkerPool(int workers, Body body, WatchdogOptions watchdog = {});
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  /// Kills and reaps workers that are still running.
  ~WorkerPool();

  /// The next data message of `worker` (blocking, watchdog and signals
  /// checked meanwhile). Re-throws the worker's vsd::Error; throws WorkerLost
  /// if it died or was stopped, InterruptedError on SIGINT/SIGTERM.
  std::vector<char> receive(int worker);
  /// Starts a fresh process for `worker` after WorkerLost. It runs the body
  /// again; the fork copies the parent's state as it is now, so the body can
  /// read from it where to resume.
  void restart(int worker);
  /// Waits for every worker to finish cleanly.
  void finish();
  /// Workers started again after a fault.
  int restarts() const { return restarts_; }
  int size() const { return static_cast<int>(workers_.size()); }

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    bool timedOut = false;
    double limit = 0.0;
    ActivityRecord::Snapshot timedOutActivity;
  };
  void spawn(int worker);
  bool readExactly(int worker, char* data, std::size_t size);
  /// The next frame (type, payload); re-throws an error frame, reports a loss.
  std::pair<unsigned char, std::vector<char>> readFrame(int worker);
  void waitReadable(int worker);
  void checkWatchdog();
  [[noreturn]] void reportLoss(int worker);
  void stop(Worker& worker);

  Body body_;
  WatchdogOptions watchdog_;
  std::vector<Worker> workers_;
  ActivityRecord* records_ = nullptr;  ///< shared with the workers (one per worker)
  pid_t parent_ = -1;
  int restarts_ = 0;
};

}  // namespace vsd::pipeline
