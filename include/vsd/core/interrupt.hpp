#pragma once
// SIGINT / SIGTERM: the handler only records the signal; long stages poll
// interrupted() between units of work (and every blocking wait of a parent
// process polls it at least every 100 ms), then throw InterruptedError, so
// that RAII stops worker processes and removes unfinished outputs. The CLI
// exits with 128 + the signal number: 130 (SIGINT) or 143 (SIGTERM).

#include "vsd/core/error.hpp"

namespace vsd {

class InterruptedError : public Error {
 public:
  /// `signal`: the signal that arrived (SIGINT or SIGTERM).
  explicit InterruptedError(int signal);
  int signal() const { return signal_; }
  /// The process exit code that reports this signal: 128 + signal.
  int exitCode() const { return 128 + signal_; }

 private:
  int signal_;
};

/// Installs SIGINT/SIGTERM handlers that record the signal (the CLI calls this
/// once). Without SA_RESTART: blocking calls return EINTR and notice it.
void installInterruptHandlers();
bool interrupted();
/// The signal that arrived (0 if none).
int interruptSignal();
/// Throws InterruptedError if a signal arrived.
void throwIfInterrupted();
/// Forgets a signal that has been handled (for callers that go on, e.g. tests).
void clearInterruption();
/// In a forked worker process: SIGINT/SIGTERM get their default action again
/// (the parent supervises the worker and ends it; a worker that a user signals
/// directly dies and is reported as such).
void restoreDefaultSignalActions();

}  // namespace vsd
