#include "fuzz_support.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "vsd/core/files.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace vsd::fuzz {

namespace {

std::string readAll(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

/// Child side of runWatched: own process group, redirected output, exec.
[[noreturn]] void execChild(const std::vector<std::string>& argv, const fs::path& out, const fs::path& err,
                            const std::vector<std::string>& environment) {
  ::setpgid(0, 0);
  const int in = ::open("/dev/null", O_RDONLY);
  const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (in < 0 || o < 0 || e < 0) ::_exit(125);
  ::dup2(in, STDIN_FILENO);
  ::dup2(o, STDOUT_FILENO);
  ::dup2(e, STDERR_FILENO);
  for (const auto& entry : environment) ::putenv(const_cast<char*>(entry.c_str()));
  std::vector<char*> raw;
  for (const auto& arg : argv) raw.push_back(const_cast<char*>(arg.c_str()));
  raw.push_back(nullptr);
  ::execv(raw[0], raw.data());
  ::_exit(126);
}

}  // namespace

RunResult runWatched(const std::vector<std::string>& argv, const fs::path& work, std::chrono::seconds timeout,
                     const std::vector<std::string>& environment) {
  fs::create_directories(work);
  const fs::path out = work / "stdout.txt";
  const fs::path err = work / "stderr.txt";
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) execChild(argv, out, err, environment);
  ::setpgid(pid, pid);  // also from the parent: no race with the kill below

  RunResult result;
  int status = 0;
  struct rusage usage {};
  bool terminated = false;
  auto deadline = start + timeout;
  while (true) {
    const pid_t waited = ::wait4(pid, &status, WNOHANG, &usage);
    if (waited == pid) break;
    if (waited < 0 && errno != EINTR) throw std::runtime_error("waitpid failed");
    if (std::chrono::steady_clock::now() > deadline) {
      result.timedOut = true;
      ::kill(-pid, terminated ? SIGKILL : SIGTERM);
      deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
      terminated = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // Workers the tool forked must not outlive it.
  ::kill(-pid, SIGKILL);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.peakMiB = static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
  result.exited = WIFEXITED(status);
  result.exitCode = result.exited ? WEXITSTATUS(status) : -1;
  result.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  result.stdoutText = readAll(out);
  result.stderrText = readAll(err);
  return result;
}

std::size_t lineCount(const std::string& text) {
  if (text.empty()) return 0;
  const auto newlines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  return newlines + (text.back() == '\n' ? 0 : 1);
}

Snapshot Snapshot::of(const fs::path& path) {
  Snapshot snapshot;
  std::error_code ec;
  snapshot.exists = fs::exists(path, ec);
  if (!snapshot.exists) return snapshot;
  if (fs::is_regular_file(path, ec)) {
    snapshot.files[path.filename().string()] = sha256OfFile(path);
    return snapshot;
  }
  for (const auto& entry : fs::recursive_directory_iterator(path, ec)) {
    if (entry.is_regular_file()) snapshot.files[fs::relative(entry.path(), path).string()] = sha256OfFile(entry.path());
  }
  return snapshot;
}

std::vector<fs::path> leftovers(const fs::path& folder) {
  std::vector<fs::path> found;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return found;
  for (const auto& entry : fs::recursive_directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    const bool part = name.size() > 5 && name.compare(name.size() - 5, 5, ".part") == 0;
    const bool tmp = name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0;
    if (part || tmp) found.push_back(entry.path());
  }
  return found;
}

namespace {

/// The oracle for a run that ended with exit 1 (bad input refused).
void checkRefusal(const Case& c, const RunResult& run, const std::vector<Snapshot>& before,
                  std::vector<std::string>& problems) {
  if (c.exitOneIsAVerdict && run.stderrText.empty()) return;
  const std::size_t lines = lineCount(run.stderrText);
  if (lines != 1) problems.push_back(fmt::format("{} lines on stderr (expected 1): {}", lines, run.stderrText));
  if (run.stderrText.rfind("vsd-sumo: ", 0) != 0) problems.push_back("stderr does not start with 'vsd-sumo: '");
  for (std::size_t i = 0; i < c.outputs.size(); ++i) {
    const auto after = Snapshot::of(c.outputs[i]);
    const bool empty_folder = after.exists && after.files.empty() && !before[i].exists;
    if (!(after == before[i]) && !empty_folder) {
      problems.push_back(fmt::format("output {} changed although the command failed", c.outputs[i].string()));
    }
  }
}

}  // namespace

namespace {

std::vector<std::string> vsdArgv(const Case& c) {
  std::vector<std::string> argv = {(fs::path(VSD_BINARY_DIR) / "vsd-sumo").string(), "--quiet"};
  argv.insert(argv.end(), c.args.begin(), c.args.end());
  return argv;
}

/// The oracle of an ordinary run (any input, no fault injected).
void checkRun(const Case& c, const RunResult& run, const std::vector<Snapshot>& before,
              std::vector<std::string>& problems) {
  if (run.timedOut) {
    problems.push_back(fmt::format("hang: stopped by the watchdog after {:.0f} s", run.seconds));
  } else if (!run.exited) {
    problems.push_back(fmt::format("death by signal {} ({})", run.signal, strsignal(run.signal)));
  } else if (run.exitCode == 0) {
    for (const auto& output : c.outputs) {
      if (!fs::exists(output)) problems.push_back(fmt::format("exit 0 but {} was not written", output.string()));
    }
    if (problems.empty() && c.checkOutputs) {
      if (auto problem = c.checkOutputs(); !problem.empty()) problems.push_back("exit 0 but " + problem);
    }
  } else if (run.exitCode == 1 || run.exitCode == 2) {  // 2: a usage error (docs/cli.md), refused the same way
    checkRefusal(c, run, before, problems);
  } else {
    problems.push_back(fmt::format("exit code {} (expected 0, 1 or 2): {}", run.exitCode, run.stderrText));
  }
}

/// After a kill: every output is as before, or complete (checkOutputs passes) — never
/// a file or folder under its final name that is neither.
void checkAfterKill(const Case& c, const std::vector<Snapshot>& before, std::vector<std::string>& problems) {
  for (std::size_t i = 0; i < c.outputs.size(); ++i) {
    if (Snapshot::of(c.outputs[i]) == before[i]) continue;
    const std::string problem =
        c.checkOutputs ? c.checkOutputs() : std::string("it is neither the old output nor a checked new one");
    if (!problem.empty()) {
      problems.push_back(fmt::format("after the kill {} changed and is not complete: {}", c.outputs[i].string(), problem));
    }
  }
}

void checkLeftovers(const Case& c, std::vector<std::string>& problems) {
  for (const auto& output : c.outputs) {
    const fs::path folder = fs::is_directory(output) ? output : output.parent_path();
    for (const auto& leftover : leftovers(folder)) {
      problems.push_back(fmt::format("temporary file left behind: {}", leftover.string()));
    }
  }
}

}  // namespace

namespace {

/// The run's own TMPDIR (a fresh folder under `work`) as an environment entry.
std::vector<std::string> withTemporaryDirectory(std::vector<std::string> environment, const fs::path& scratch) {
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  environment.push_back("TMPDIR=" + scratch.string());
  return environment;
}

/// A run that ended by itself, or by a signal it handles, leaves its TMPDIR as it found it
/// (empty): scratch folders are removed on errors and interruptions too. A SIGKILL leaves them.
void checkTemporaryDirectory(const RunResult& run, const fs::path& scratch, std::vector<std::string>& problems) {
  if (run.exited) {
    for (const auto& entry : fs::directory_iterator(scratch)) {
      problems.push_back(
          fmt::format("left in TMPDIR after exit {}: {}", run.exitCode, entry.path().filename().string()));
    }
  }
  fs::remove_all(scratch);
}

}  // namespace

Verdict runCase(const Case& c, const fs::path& work) {
  Verdict verdict;
  verdict.name = c.name;
  std::vector<Snapshot> before;
  for (const auto& output : c.outputs) before.push_back(Snapshot::of(output));
  std::vector<Snapshot> aimed_at;
  for (const auto& path : c.untouched) aimed_at.push_back(Snapshot::of(path));
  const fs::path scratch = work / "tmp";
  const RunResult run = runWatched(vsdArgv(c), work, c.timeout, withTemporaryDirectory(c.environment, scratch));
  checkTemporaryDirectory(run, scratch, verdict.problems);
  verdict.exitCode = run.exitCode;
  verdict.seconds = run.seconds;
  verdict.peakMiB = run.peakMiB;
  auto& problems = verdict.problems;
  for (std::size_t i = 0; i < c.untouched.size(); ++i) {
    if (!(Snapshot::of(c.untouched[i]) == aimed_at[i])) {
      problems.push_back(fmt::format("{} was touched (the input aimed at it)", c.untouched[i].string()));
    }
  }
  if (c.mustRefuse && run.exited && run.exitCode == 0) {
    problems.push_back("a hostile input was accepted (exit 0, expected a refusal with exit 1)");
  }
  if (c.expectKill && !run.timedOut && !run.exited && run.signal == SIGKILL) {
    verdict.exitCode = 128 + SIGKILL;
    checkAfterKill(c, before, problems);
    // The next run (no fault) cleans up what the kill left and succeeds.
    Case again = c;
    again.environment.clear();
    again.expectKill = false;
    std::vector<Snapshot> now;
    for (const auto& output : c.outputs) now.push_back(Snapshot::of(output));
    const fs::path next_scratch = work / "next" / "tmp";
    const RunResult next =
        runWatched(vsdArgv(again), work / "next", c.timeout, withTemporaryDirectory({}, next_scratch));
    checkTemporaryDirectory(next, next_scratch, problems);
    verdict.seconds += next.seconds;
    verdict.peakMiB = std::max(verdict.peakMiB, next.peakMiB);
    if (!next.exited || next.exitCode != 0) {
      problems.push_back(fmt::format("the run after the kill failed (exit {}): {}", next.exitCode, next.stderrText));
    }
    checkRun(again, next, now, problems);
  } else {
    checkRun(c, run, before, problems);
  }
  checkLeftovers(c, problems);
  if (!problems.empty()) {
    std::string command;
    for (const auto& entry : c.environment) command += entry + " ";
    command += "vsd-sumo --quiet";
    for (const auto& arg : c.args) command += " '" + arg + "'";
    problems.push_back("command: " + command);
  }
  return verdict;
}

const std::vector<std::string>& hostileNumbers() {
  static const std::vector<std::string> values = {
      "-1",   "-5",      "0",         "-0",   "1e308",    "-1e308",  "1e999",      "inf",  "-inf",
      "nan",  "NaN",     "1e-320",    "0x10", "010",      "1.5",     "2147483648", "4294967296",
      "18446744073709551615",         "18446744073709551616",        "99999999999999999999999",
      "abc",  "",        " 3",        "3 ",   "+7",       "1,5",     "1e9",        "1e12", "0.0001"};
  return values;
}

}  // namespace vsd::fuzz
