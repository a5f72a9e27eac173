#pragma once
// Fault-injection and fuzz suite: running vsd-sumo under a watchdog, and the
// oracle every run must satisfy whatever input it got.
//
// The oracle (README "Fault-injection and fuzz suite"):
//   - no death by a signal, no hang (the watchdog kills the process group);
//   - an exit code of 0 or 1 only (3 = "internal error" is never right for input);
//   - exit 0: the promised outputs exist and are complete (checked by the case);
//   - exit 1: exactly one line on stderr, starting with "vsd-sumo: ", and no output
//     that looks complete: a fresh output path stays absent (or an empty folder), an
//     existing one is left byte-identical, and no temporary file is left behind.

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace vsd::fuzz {

struct RunResult {
  bool exited = false;      ///< false: killed by a signal (see signal) or by the watchdog
  int exitCode = -1;
  int signal = 0;           ///< the signal that ended it (when !exited)
  bool timedOut = false;    ///< the watchdog stopped it
  std::string stdoutText;
  std::string stderrText;
  double seconds = 0.0;
  double peakMiB = 0.0;     ///< largest resident set of the process (and the workers it waited for)
};

/// Runs argv in its own process group with stdout/stderr captured separately; after
/// `timeout` the group gets SIGTERM, 5 s later SIGKILL. Extra environment entries
/// ("NAME=value") are added to the inherited environment.
RunResult runWatched(const std::vector<std::string>& argv, const std::filesystem::path& work,
                     std::chrono::seconds timeout, const std::vector<std::string>& environment = {});

/// Lines of text (a missing final newline still counts the last line).
std::size_t lineCount(const std::string& text);

/// A file or folder's content, to compare before and after a failed run.
struct Snapshot {
  std::map<std::string, std::string> files;  ///< relative path -> SHA-256 (empty map: absent)
  bool exists = false;
  static Snapshot of(const std::filesystem::path& path);
  bool operator==(const Snapshot& other) const { return exists == other.exists && files == other.files; }
};

/// Temporary files an interrupted or failed write may leave: ".<name>.<pid>.part",
/// "*.tmp" and hidden partial folders. Returns their paths under `folder`.
std::vector<std::filesystem::path> leftovers(const std::filesystem::path& folder);

/// One fuzz case: what was run, and what a correct outcome is.
struct Case {
  std::string name;                             ///< category/what, for failure messages
  std::vector<std::string> args;                ///< vsd-sumo arguments (without the program)
  std::vector<std::filesystem::path> outputs;   ///< what the command promises to write
  /// Extra check of the outputs after exit 0 (e.g. the dataset validates); returns a
  /// problem description, empty when fine.
  std::function<std::string()> checkOutputs;
  /// `dataset validate` reports an invalid file with exit 1 and its problems on stdout.
  bool exitOneIsAVerdict = false;
  std::vector<std::string> environment;         ///< e.g. fault-injection settings
  std::chrono::seconds timeout{60};
  /// A kill case (VSD_FAULT=kill@<point> in `environment`): the run must die by
  /// SIGKILL at the point (or, if it never reaches it, pass as usual), each output must
  /// be as before or complete (checkOutputs passes), and the same command without the
  /// fault must then succeed and leave no temporary file.
  bool expectKill = false;
  /// Paths the input aimed at (a file a scenario tried to make SUMO write, a folder out
  /// of reach): they must be as before whatever the exit code (absent stays absent).
  std::vector<std::filesystem::path> untouched;
  /// The input must be refused (exit 1): a hostile file that is accepted is a failure.
  bool mustRefuse = false;
};

/// Outcome of a case, for the summary.
struct Verdict {
  std::string name;
  std::vector<std::string> problems;  ///< empty: the oracle holds
  int exitCode = -1;
  double seconds = 0.0;
  double peakMiB = 0.0;  ///< the largest resident set of the case's runs
};

/// Runs a case and applies the oracle. `work` is the case's scratch folder.
Verdict runCase(const Case& c, const std::filesystem::path& work);

/// The suite's random source: one seed, reproducible case by case.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  std::size_t index(std::size_t size) { return std::uniform_int_distribution<std::size_t>(0, size - 1)(engine_); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0.0, 1.0)(engine_) < p; }
  template <typename T>
  const T& pick(const std::vector<T>& values) {
    return values[index(values.size())];
  }
  std::mt19937_64& engine() { return engine_; }

 private:
  std::mt19937_64 engine_;
};

/// Texts that break numbers in every way: signs, infinities, NaN, huge and tiny
/// magnitudes, overflowing integers, non-numbers, other bases, empty.
const std::vector<std::string>& hostileNumbers();

}  // namespace vsd::fuzz
