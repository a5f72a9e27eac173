#include "vsd/core/interrupt.hpp"

#include <csignal>
#include <string>

namespace vsd {

namespace {
volatile std::sig_atomic_t g_signal = 0;
extern "C" void onSignal(int signal) { g_signal = signal; }

std::string describe(int signal) {
  return std::string("interrupted by ") + (signal == SIGTERM ? "SIGTERM" : signal == SIGINT ? "SIGINT" : "a signal") +
         "; workers stopped, unfinished outputs removed, earlier outputs kept";
}
}  // namespace

InterruptedError::InterruptedError(int signal) : Error(describe(signal)), signal_(signal) {}

void installInterruptHandlers() {
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: blocking reads return EINTR and notice the flag
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

void restoreDefaultSignalActions() {
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  g_signal = 0;
}

bool interrupted() { return g_signal != 0; }

int interruptSignal() { return g_signal; }

void clearInterruption() { g_signal = 0; }

void throwIfInterrupted() {
  if (const int signal = g_signal; signal != 0) throw InterruptedError(signal);
}

}  // namespace vsd
