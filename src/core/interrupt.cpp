#include "vsd/core/interrupt.hpp"

#include <csignal>

namespace vsd {

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void onSignal(int /*signal*/) { g_interrupted = 1; }
}  // namespace

void installInterruptHandlers() {
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: blocking reads return EINTR and notice the flag
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool interrupted() { return g_interrupted != 0; }

void clearInterruption() { g_interrupted = 0; }

void throwIfInterrupted() {
  if (interrupted()) throw InterruptedError();
}

}  // namespace vsd
