#include "vsd/pipeline/worker_pool.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <malloc.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <thread>

#include "vsd/core/bytes.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/interrupt.hpp"

namespace vsd::pipeline {

namespace {

enum FrameType : unsigned char { kData = 1, kError = 2, kEnd = 3 };
enum ErrorKind : unsigned char { kGeneric, kConfig, kSumo, kDataset, kModel, kIo };
constexpr std::size_t kHeaderSize = sizeof(unsigned char) + sizeof(std::uint64_t);
constexpr int kPollMilliseconds = 100;

void writeAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0) {
      if (errno == EINTR) continue;
      ::_exit(3);  // the parent is gone; nothing sensible is left to do
    }
    data += written;
    size -= static_cast<std::size_t>(written);
  }
}

ErrorKind kindOf(const std::exception& error) {
  if (dynamic_cast<const ConfigError*>(&error)) return kConfig;
  if (dynamic_cast<const SumoError*>(&error)) return kSumo;
  if (dynamic_cast<const DatasetError*>(&error)) return kDataset;
  if (dynamic_cast<const ModelError*>(&error)) return kModel;
  if (dynamic_cast<const IoError*>(&error)) return kIo;
  return kGeneric;
}

[[noreturn]] void rethrow(ErrorKind kind, const std::string& message) {
  switch (kind) {
    case kConfig: throw ConfigError(message);
    case kSumo: throw SumoError(message);
    case kDataset: throw DatasetError(message);
    case kModel: throw ModelError(message);
    case kIo: throw IoError(message);
    case kGeneric: break;
  }
  throw Error(message);
}

/// exit() called in a worker (by a plugin, say) ends it here, before any atexit
/// handler or static destructor runs on the worker's copy of the parent's state
/// (open HDF5 files, stdio buffers) — as if it had called _exit().
extern "C" void exitWorkerImmediately(int status, void* /*unused*/) { ::_exit(status); }

/// Kills a worker's whole process group (it and its netconvert), then the worker itself.
void killGroup(pid_t pid) {
  ::kill(-pid, SIGKILL);
  ::kill(pid, SIGKILL);
}

/// A worker allocates and frees about the same memory batch after batch (SUMO's network and
/// road users, the batch's scenes). By default glibc hands freed memory at the top of the heap,
/// and every block above 128 KiB, back to the kernel, which returns it page fault by page fault
/// for the next batch (docs/alks-scenarios.md). Kept (up to 256 MiB; blocks up to 32 MiB from
/// the heap), it stays at the peak a batch reaches anyway. Only in the worker: the parent may
/// go on to train in the same process (`experiment`), where glibc's own policy serves better.
void keepFreedMemoryForTheNextBatch() {
  ::mallopt(M_MMAP_THRESHOLD, 32 << 20);
  ::mallopt(M_TRIM_THRESHOLD, 256 << 20);
}

}  // namespace

void WatchdogOptions::validate(const std::string& flag) const {
  if (!(stepTimeout >= 1e-3 && stepTimeout <= 86400.0)) {
    throw ConfigError::field("command line", flag, formatValue(stepTimeout), "a time limit of 0.001 .. 86400 s");
  }
}

double WatchdogOptions::limitFor(Activity activity) const {
  switch (activity) {
    case Activity::Idle: return std::numeric_limits<double>::infinity();
    case Activity::Netconvert:
    case Activity::SumoLoad: return stepTimeout * kLoadFactor;
    case Activity::SumoVehicles:
    case Activity::SumoStep:
    case Activity::Controller: return stepTimeout;
  }
  return stepTimeout;
}

std::string WorkerFault::what() const {
  switch (kind) {
    case Kind::Signal: return fmt::format("crashed (signal {}, {})", signal, strsignal(signal));
    case Kind::Exit: return fmt::format("ended the process (exit code {})", exitCode);
    case Kind::Timeout: return fmt::format("did not return within {} s (watchdog, --step-timeout)", limit);
  }
  return "failed";
}

WorkerLost::WorkerLost(int worker, WorkerFault fault)
    : SumoError(fmt::format("worker process {} {} during {}", worker, fault.what(), activityName(fault.activity.activity))),
      worker_(worker),
      fault_(std::move(fault)) {}

void WorkerChannel::sendFrame(unsigned char type, const std::vector<char>& payload) {
  ByteWriter header;
  header.put<unsigned char>(type);
  header.put<std::uint64_t>(payload.size());
  writeAll(fd_, header.bytes().data(), header.bytes().size());
  writeAll(fd_, payload.data(), payload.size());
}

void WorkerChannel::send(const std::vector<char>& payload) { sendFrame(kData, payload); }

WorkerPool::WorkerPool(int workers, Body body, WatchdogOptions watchdog)
    : body_(std::move(body)), watchdog_(watchdog), workers_(static_cast<std::size_t>(workers)), parent_(::getpid()) {
  watchdog_.validate();
  void* shared = ::mmap(nullptr, sizeof(ActivityRecord) * workers_.size(), PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (shared == MAP_FAILED) throw Error(std::string("cannot map memory shared with workers: ") + std::strerror(errno));
  records_ = static_cast<ActivityRecord*>(shared);
  for (std::size_t w = 0; w < workers_.size(); ++w) new (&records_[w]) ActivityRecord();
  try {
    for (int w = 0; w < workers; ++w) spawn(w);
  } catch (...) {
    for (auto& worker : workers_) stop(worker);
    ::munmap(records_, sizeof(ActivityRecord) * workers_.size());
    throw;
  }
}

WorkerPool::~WorkerPool() {
  for (auto& worker : workers_) stop(worker);
  ::munmap(records_, sizeof(ActivityRecord) * workers_.size());
}

void WorkerPool::stop(Worker& worker) {
  if (worker.fd >= 0) ::close(worker.fd);
  worker.fd = -1;
  if (worker.pid > 0) {
    killGroup(worker.pid);
    int status = 0;
    while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  worker.pid = -1;
}

void WorkerPool::spawn(int w) {
  Worker& slot = workers_[static_cast<std::size_t>(w)];
  ActivityRecord* record = &records_[w];
  record->~ActivityRecord();
  new (record) ActivityRecord();
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    throw Error(std::string("cannot create a pipe for worker processes: ") + std::strerror(errno));
  }
  faultPoint("pool.fork");
  std::fflush(nullptr);  // or the child would flush the parent's buffered output a second time
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw Error(std::string("cannot start a worker process: ") + std::strerror(errno));
  }
  if (pid == 0) {
    // Worker: never returns into the parent's stack (no destructors of the
    // parent's open files run here), always leaves through _exit().
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent_) ::_exit(1);  // the parent died before prctl
    restoreDefaultSignalActions();
    const struct rlimit no_core {0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);  // a crashing plugin costs a restart, not a core dump per scenario
    ::on_exit(exitWorkerImmediately, nullptr);
    keepFreedMemoryForTheNextBatch();
    setActivityRecord(record);
    ::close(fds[0]);
    for (const auto& other : workers_) {
      if (other.fd >= 0) ::close(other.fd);
    }
    WorkerChannel channel(fds[1]);
    int status = 0;
    try {
      faultPoint("worker.start");
      body_(w, channel);
      reportActivity(Activity::Idle);
      channel.sendFrame(kEnd, {});
    } catch (const std::exception& error) {
      reportActivity(Activity::Idle);
      ByteWriter message;
      message.put<unsigned char>(kindOf(error));
      message.putString(error.what());
      channel.sendFrame(kError, message.bytes());
      status = 1;
    }
    ::close(fds[1]);
    ::_exit(status);
  }
  ::setpgid(pid, pid);  // also here: whichever of parent and child runs first
  ::close(fds[1]);
  slot = Worker{};
  slot.pid = pid;
  slot.fd = fds[0];
}

void WorkerPool::restart(int worker) {
  Worker& slot = workers_.at(static_cast<std::size_t>(worker));
  stop(slot);
  spawn(worker);
  ++restarts_;
}

void WorkerPool::checkWatchdog() {
  for (std::size_t w = 0; w < workers_.size(); ++w) {
    Worker& worker = workers_[w];
    if (worker.pid <= 0 || worker.timedOut) continue;
    const auto activity = records_[w].snapshot();
    const double limit = watchdog_.limitFor(activity.activity);
    if (activity.seconds > limit) {
      worker.timedOut = true;
      worker.limit = limit;
      worker.timedOutActivity = activity;
      killGroup(worker.pid);
    }
  }
}

void WorkerPool::waitReadable(int w) {
  const int fd = workers_[static_cast<std::size_t>(w)].fd;
  for (;;) {
    throwIfInterrupted();
    checkWatchdog();
    struct pollfd entry {fd, POLLIN, 0};
    const int ready = ::poll(&entry, 1, kPollMilliseconds);
    if (ready > 0) return;
    if (ready < 0 && errno != EINTR) {
      throw Error(std::string("waiting for a worker process failed: ") + std::strerror(errno));
    }
  }
}

bool WorkerPool::readExactly(int w, char* data, std::size_t size) {
  const int fd = workers_[static_cast<std::size_t>(w)].fd;
  while (size > 0) {
    waitReadable(w);
    const ssize_t got = ::read(fd, data, size);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw Error(std::string("reading from a worker process failed: ") + std::strerror(errno));
    }
    if (got == 0) return false;
    data += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

void WorkerPool::reportLoss(int w) {
  Worker& worker = workers_[static_cast<std::size_t>(w)];
  // The pipe is closed: the worker has ended (or closed it and will be killed).
  int status = 0;
  pid_t waited = 0;
  for (int attempt = 0; attempt < 100 && waited == 0; ++attempt) {
    waited = ::waitpid(worker.pid, &status, WNOHANG);
    if (waited == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (waited == 0) {
    killGroup(worker.pid);
    while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  ::kill(-worker.pid, SIGKILL);  // a netconvert it left behind
  WorkerFault fault;
  fault.activity = records_[w].snapshot();
  // Only the watchdog's SIGKILL makes a timeout. A worker that crashed or exited on its
  // own before it — or already lay dead while the parent read another worker, its
  // activity seemingly lasting on — ended as its status says.
  if (worker.timedOut && WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) {
    fault.kind = WorkerFault::Kind::Timeout;
    fault.limit = worker.limit;
    fault.activity = worker.timedOutActivity;
  } else if (WIFSIGNALED(status)) {
    fault.kind = WorkerFault::Kind::Signal;
    fault.signal = WTERMSIG(status);
  } else {
    fault.kind = WorkerFault::Kind::Exit;
    fault.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  ::close(worker.fd);
  worker = Worker{};
  throw WorkerLost(w, fault);
}

std::pair<unsigned char, std::vector<char>> WorkerPool::readFrame(int worker) {
  if (workers_.at(static_cast<std::size_t>(worker)).pid <= 0) {
    throw Error(fmt::format("internal: receive() from worker {}, which is not running", worker));
  }
  char header[kHeaderSize];
  if (!readExactly(worker, header, sizeof(header))) reportLoss(worker);
  ByteReader reader(header, sizeof(header));
  const auto type = reader.get<unsigned char>();
  const auto size = static_cast<std::size_t>(reader.get<std::uint64_t>());
  std::vector<char> payload(size);
  if (!readExactly(worker, payload.data(), size)) reportLoss(worker);
  if (type == kError) {
    ByteReader message(payload);
    const auto kind = static_cast<ErrorKind>(message.get<unsigned char>());
    rethrow(kind, message.getString());
  }
  return {type, std::move(payload)};
}

std::vector<char> WorkerPool::receive(int worker) {
  auto [type, payload] = readFrame(worker);
  if (type == kData) return payload;
  throw SumoError(fmt::format("worker process {} finished before sending all its results", worker));
}

void WorkerPool::finish() {
  for (std::size_t w = 0; w < workers_.size(); ++w) {
    auto& worker = workers_[w];
    if (worker.pid <= 0) continue;
    if (readFrame(static_cast<int>(w)).first != kEnd) {
      throw Error(fmt::format("internal: worker process {} sent more results than expected", w));
    }
    int status = 0;
    while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
    }
    worker.pid = -1;
    ::close(worker.fd);
    worker.fd = -1;
  }
}

}  // namespace vsd::pipeline
