#pragma once
// Worker processes for parallel simulation (libsumo runs one simulation per
// process). Each worker runs a body that sends framed messages back through a
// pipe; the parent receives them in the order it chooses, so results can be
// written in sample order whatever the number of workers.
//
// A worker's vsd::Error is re-thrown in the parent with the same type; a
// worker that dies is reported with its signal.

#include <sys/types.h>

#include <functional>
#include <vector>

namespace vsd::pipeline {

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
  WorkerPool(int workers, const Body& body);
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  /// Kills and reaps workers that are still running.
  ~WorkerPool();

  /// The next data message of `worker` (blocking). Re-throws the worker's
  /// error; throws SumoError if it died, InterruptedError on Ctrl-C.
  std::vector<char> receive(int worker);
  /// Waits for every worker to finish cleanly.
  void finish();

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
  };
  [[noreturn]] void reportDeath(int worker);
  std::vector<Worker> workers_;
};

}  // namespace vsd::pipeline
