#pragma once
// Child processes (netconvert, chromium, worker processes). Output goes to a
// file so that a chatty tool can never block on a full pipe.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace vsd {

struct ProcessResult {
  int exitCode = -1;       ///< exit status, or 128 + signal number if killed by a signal
  std::string output;      ///< combined stdout and stderr (at most the last 64 KiB)
  long maxRssKiB = 0;      ///< peak resident memory of the process (KiB)
  double seconds = 0.0;    ///< wall time from spawn to exit
};

/// A running child process. Destroying it without wait() kills and reaps it.
class ChildProcess {
 public:
  /// Starts argv[0] (looked up in PATH) with stdout and stderr appended to `output_file`.
  /// Throws Error if the program cannot be started.
  static ChildProcess spawn(const std::vector<std::string>& argv, const std::filesystem::path& output_file);

  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess();

  /// Waits for the process and returns its exit code and output. Throws
  /// InterruptedError (within 100 ms) if SIGINT/SIGTERM arrives meanwhile; the
  /// process is then killed when this object is destroyed.
  ProcessResult wait();
  bool running() const { return pid_ > 0; }
  /// The process id (-1 once waited for).
  pid_t pid() const { return pid_; }

 private:
  ChildProcess(pid_t pid, std::filesystem::path output_file)
      : pid_(pid), outputFile_(std::move(output_file)), started_(std::chrono::steady_clock::now()) {}
  void killAndReap();

  pid_t pid_ = -1;
  std::filesystem::path outputFile_;
  std::chrono::steady_clock::time_point started_;
};

/// Runs a program to completion (see ChildProcess::spawn).
ProcessResult runProcess(const std::vector<std::string>& argv, const std::filesystem::path& output_file);

/// The first line of `output` that contains "Error" (or the last non-empty line).
std::string firstErrorLine(const std::string& output);

}  // namespace vsd
