#include "vsd/core/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"

extern char** environ;

namespace vsd {

ChildProcess ChildProcess::spawn(const std::vector<std::string>& argv, const std::filesystem::path& output_file) {
  if (argv.empty()) throw Error("internal: spawn() without a program");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string output = output_file.string();
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);

  std::vector<char*> raw_args;
  raw_args.reserve(argv.size() + 1);
  for (const auto& arg : argv) raw_args.push_back(const_cast<char*>(arg.c_str()));
  raw_args.push_back(nullptr);

  pid_t pid = -1;
  const int status = posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, raw_args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (status != 0) {
    throw Error("cannot start '" + argv[0] + "': " + std::strerror(status) + " (is it installed and in PATH?)");
  }
  return ChildProcess(pid, output_file);
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(other.pid_), outputFile_(std::move(other.outputFile_)), started_(other.started_) {
  other.pid_ = -1;
}

ChildProcess& ChildProcess::operator=(ChildProcess&& other) noexcept {
  if (this != &other) {
    killAndReap();
    pid_ = other.pid_;
    outputFile_ = std::move(other.outputFile_);
    started_ = other.started_;
    other.pid_ = -1;
  }
  return *this;
}

ChildProcess::~ChildProcess() { killAndReap(); }

void ChildProcess::killAndReap() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
}

namespace {

/// Blocks until `pid` has exited (without reaping it), polling for SIGINT/SIGTERM
/// at least every 100 ms: the parent must never sit deaf in a wait.
void waitUntilExited(pid_t pid) {
  const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
  for (;;) {
    throwIfInterrupted();
    if (pidfd >= 0) {
      struct pollfd entry {pidfd, POLLIN, 0};
      const int ready = ::poll(&entry, 1, 100);
      if (ready > 0) break;
      continue;  // timeout or EINTR: check for a signal
    }
    siginfo_t info{};
    info.si_pid = 0;
    if (::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid) break;
    ::usleep(10'000);  // kernels without pidfd_open
  }
  if (pidfd >= 0) ::close(pidfd);
}

}  // namespace

ProcessResult ChildProcess::wait() {
  ProcessResult result;
  if (pid_ <= 0) throw Error("internal: wait() on a process that is not running");
  waitUntilExited(pid_);  // throws InterruptedError; the destructor then kills the child
  int status = 0;
  pid_t waited = -1;
  struct rusage usage {};
  do {
    waited = ::wait4(pid_, &status, 0, &usage);
  } while (waited < 0 && errno == EINTR);
  result.maxRssKiB = usage.ru_maxrss;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  pid_ = -1;
  if (waited < 0) throw Error(std::string("waitpid failed: ") + std::strerror(errno));
  if (WIFEXITED(status)) {
    result.exitCode = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.exitCode = 128 + WTERMSIG(status);
  }
  std::ifstream stream(outputFile_, std::ios::binary);
  if (stream) {
    std::ostringstream buffer;
    buffer << stream.rdbuf();
    result.output = buffer.str();
    constexpr std::size_t kKeep = 64 * 1024;
    if (result.output.size() > kKeep) result.output.erase(0, result.output.size() - kKeep);
  }
  return result;
}

ProcessResult runProcess(const std::vector<std::string>& argv, const std::filesystem::path& output_file) {
  return ChildProcess::spawn(argv, output_file).wait();
}

std::string firstErrorLine(const std::string& output) {
  std::istringstream lines(output);
  std::string line;
  std::string last;
  while (std::getline(lines, line)) {
    if (line.find("Error") != std::string::npos || line.find("error") != std::string::npos) return line;
    if (!line.empty()) last = line;
  }
  return last.empty() ? std::string("(no output)") : last;
}

}  // namespace vsd
