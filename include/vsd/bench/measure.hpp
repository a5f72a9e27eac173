#pragma once
// What every benchmark measures with: CPU time and page faults (getrusage), the load
// average (medians: core/statistics.hpp), and `vsd-sumo` processes run to completion (the executable users start,
// so start-up, scenario loading and file writing are part of what is timed).

#include <filesystem>
#include <string>
#include <vector>

#include "vsd/core/process.hpp"

namespace vsd::bench {

/// The logical scenario the benchmarks use unless told otherwise: the paper's combined
/// ACC + lane-keeping scenario, relative to the repository (where `bench` is run from).
inline constexpr const char* kDefaultScenario = "scenarios/acc_lk.yaml";

/// Resource use of a process (or of the children it has reaped), or a difference of two.
struct Usage {
  double user = 0.0;        ///< CPU time in user mode (s)
  double system = 0.0;      ///< CPU time in the kernel (s): page faults, fork, pipes, files
  double pageFaults = 0.0;  ///< minor page faults (first touch of a page, copy on write)

  /// This process so far.
  static Usage self();
  /// Every child process this process has waited for, and their descendants they waited for.
  static Usage children();
  Usage operator-(const Usage& before) const;
  double cpu() const { return user + system; }  ///< s
};

/// The 1, 5 and 15 minute load averages, "0.50 1.17 1.87" ("unknown" if unavailable).
std::string loadAverage();

/// A process run to completion, with the CPU time of it and every process it started (s).
struct ToolRun {
  ProcessResult result;
  double cpuSeconds = 0.0;
};

/// Runs `argv` to completion, its output into `log`. Throws Error (with the process's
/// first error line) if it exits non-zero.
ToolRun runChecked(const std::vector<std::string>& argv, const std::filesystem::path& log);

/// The `vsd-sumo` executable benchmarks start as separate processes.
struct Tool {
  std::filesystem::path executable;

  /// {executable, "--quiet", args...}
  std::vector<std::string> command(const std::vector<std::string>& args) const;
  /// Runs `vsd-sumo --quiet args...` (output into work/bench.log); throws Error if it fails.
  ToolRun run(const std::vector<std::string>& args, const std::filesystem::path& work) const;
};

/// True if the run folders `a` and `b` hold the same bytes in concrete.csv, traces.h5 and dataset.h5.
bool sameRunOutputs(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace vsd::bench
