#include "vsd/bench/measure.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::bench {

namespace {

Usage usageOf(int who) {
  struct rusage usage {};
  ::getrusage(who, &usage);
  const auto seconds = [](const timeval& time) {
    return static_cast<double>(time.tv_sec) + 1e-6 * static_cast<double>(time.tv_usec);
  };
  return {seconds(usage.ru_utime), seconds(usage.ru_stime), static_cast<double>(usage.ru_minflt)};
}

}  // namespace

Usage Usage::self() { return usageOf(RUSAGE_SELF); }

Usage Usage::children() { return usageOf(RUSAGE_CHILDREN); }

Usage Usage::operator-(const Usage& before) const {
  return {user - before.user, system - before.system, pageFaults - before.pageFaults};
}

std::string loadAverage() {
  double load[3] = {0.0, 0.0, 0.0};
  if (::getloadavg(load, 3) != 3) return "unknown";
  return fmt::format("{:.2f} {:.2f} {:.2f}", load[0], load[1], load[2]);
}

ToolRun runChecked(const std::vector<std::string>& argv, const fs::path& log) {
  const double cpu_before = Usage::children().cpu();
  const auto result = runProcess(argv, log);
  const double cpu_seconds = Usage::children().cpu() - cpu_before;
  if (result.exitCode != 0) {
    throw Error(fmt::format("benchmark process failed (exit {}): {}", result.exitCode, firstErrorLine(result.output)));
  }
  return {result, cpu_seconds};
}

std::vector<std::string> Tool::command(const std::vector<std::string>& args) const {
  std::vector<std::string> argv = {executable.string(), "--quiet"};
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

ToolRun Tool::run(const std::vector<std::string>& args, const fs::path& work) const {
  return runChecked(command(args), work / "bench.log");
}

bool sameRunOutputs(const fs::path& a, const fs::path& b) {
  for (const char* file : {"concrete.csv", "traces.h5", "dataset.h5"}) {
    if (sha256OfFile(a / file) != sha256OfFile(b / file)) return false;
  }
  return true;
}

}  // namespace vsd::bench
