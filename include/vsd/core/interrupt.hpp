#pragma once
// Ctrl-C / SIGTERM: long stages poll interrupted() between units of work and
// throw InterruptedError, so that RAII removes unfinished outputs.

#include "vsd/core/error.hpp"

namespace vsd {

class InterruptedError : public Error {
 public:
  InterruptedError() : Error("interrupted by signal; unfinished outputs were removed") {}
};

/// Installs SIGINT/SIGTERM handlers that set a flag (the CLI calls this once).
void installInterruptHandlers();
bool interrupted();
/// Throws InterruptedError if a signal arrived.
void throwIfInterrupted();
/// Forgets a signal that has been handled (for callers that go on, e.g. tests).
void clearInterruption();

}  // namespace vsd
