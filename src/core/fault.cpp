#include "vsd/core/fault.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace vsd {

namespace {

struct FaultPlan {
  bool active = false;
  std::string action;
  std::string point;  ///< full name, or a prefix when `prefix` is set
  bool prefix = false;
  long occurrence = 1;
  long hits = 0;
  std::string traceFile;
};

FaultPlan parsePlan() {
  FaultPlan result;
  if (const char* trace = std::getenv("VSD_FAULT_TRACE"); trace && *trace) {
    result.traceFile = trace;
    result.active = true;
  }
  const char* spec = std::getenv("VSD_FAULT");
  if (!spec || !*spec) return result;
  std::string text = spec;
  const auto at = text.find('@');
  if (at == std::string::npos) {
    std::fprintf(stderr, "vsd-sumo: VSD_FAULT=%s ignored: expected <action>@<point>[#<n>]\n", spec);
    return result;
  }
  result.action = text.substr(0, at);
  std::string point = text.substr(at + 1);
  if (const auto hash = point.rfind('#'); hash != std::string::npos) {
    result.occurrence = std::max(1L, std::strtol(point.c_str() + hash + 1, nullptr, 10));
    point.erase(hash);
  }
  if (!point.empty() && point.back() == '*') {
    result.prefix = true;
    point.pop_back();
  }
  result.point = point;
  result.active = true;
  return result;
}

/// Parsed once from the environment. The environment is the test's interface,
/// so it is read where the hooks are, not passed through every layer.
FaultPlan& plan() {
  static FaultPlan parsed = parsePlan();
  return parsed;
}

void trace(const FaultPlan& faults, const char* point) {
  // O_APPEND writes of one short line are atomic: workers and parent can share the file.
  const int fd = ::open(faults.traceFile.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return;
  const std::string line = std::to_string(::getpid()) + " " + point + "\n";
  [[maybe_unused]] const auto ignored = ::write(fd, line.data(), line.size());
  ::close(fd);
}

bool matches(const FaultPlan& faults, const char* point) {
  if (faults.action.empty()) return false;
  if (faults.prefix) return std::strncmp(point, faults.point.c_str(), faults.point.size()) == 0;
  return faults.point == point;
}

void perform(const std::string& action) {
  if (action == "kill") ::kill(::getpid(), SIGKILL);
  if (action == "term") ::kill(::getpid(), SIGTERM);
  if (action == "int") ::kill(::getpid(), SIGINT);
  if (action == "abort") std::abort();
  if (action == "segv") {
    ::signal(SIGSEGV, SIG_DFL);
    ::kill(::getpid(), SIGSEGV);
  }
  if (action == "exit0") std::exit(0);
  if (action == "term-parent") ::kill(::getppid(), SIGTERM);
  if (action == "int-parent") ::kill(::getppid(), SIGINT);
  if (action == "hang") {
    for (;;) ::pause();
  }
}

}  // namespace

bool faultInjectionActive() { return plan().active; }

void reloadFaultInjection() { plan() = parsePlan(); }

void faultPoint(const char* point) {
  FaultPlan& faults = plan();
  if (!faults.active) return;
  if (!faults.traceFile.empty()) trace(faults, point);
  if (matches(faults, point) && ++faults.hits == faults.occurrence) perform(faults.action);
}

void faultPoint(const std::string& point) { faultPoint(point.c_str()); }

}  // namespace vsd
