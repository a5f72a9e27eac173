#include "vsd/pipeline/worker_pool.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "vsd/core/bytes.hpp"
#include "vsd/core/error.hpp"
#include "vsd/core/interrupt.hpp"

namespace vsd::pipeline {

namespace {

enum FrameType : unsigned char { kData = 1, kError = 2, kEnd = 3 };
enum ErrorKind : unsigned char { kGeneric, kConfig, kSumo, kDataset, kModel, kIo, kInterrupted };

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

/// Reads exactly `size` bytes; false on end of file.
bool readAll(int fd, char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t got = ::read(fd, data, size);
    if (got < 0) {
      if (errno == EINTR) {
        throwIfInterrupted();
        continue;
      }
      throw Error(std::string("reading from a worker process failed: ") + std::strerror(errno));
    }
    if (got == 0) return false;
    data += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

ErrorKind kindOf(const std::exception& error) {
  if (dynamic_cast<const InterruptedError*>(&error)) return kInterrupted;
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
    case kInterrupted: throw InterruptedError();
    case kGeneric: break;
  }
  throw Error(message);
}

}  // namespace

void WorkerChannel::sendFrame(unsigned char type, const std::vector<char>& payload) {
  ByteWriter header;
  header.put<unsigned char>(type);
  header.put<std::uint64_t>(payload.size());
  writeAll(fd_, header.bytes().data(), header.bytes().size());
  writeAll(fd_, payload.data(), payload.size());
}

void WorkerChannel::send(const std::vector<char>& payload) { sendFrame(kData, payload); }

WorkerPool::WorkerPool(int workers, const Body& body) {
  for (int w = 0; w < workers; ++w) {
    int fds[2];
    if (::pipe(fds) != 0) throw Error(std::string("cannot create a pipe for worker processes: ") + std::strerror(errno));
    const pid_t pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
      throw Error(std::string("cannot start a worker process: ") + std::strerror(errno));
    }
    if (pid == 0) {
      // Worker: never returns into the parent's stack (no destructors of the
      // parent's open files run here), always leaves through _exit().
      ::close(fds[0]);
      for (const auto& other : workers_) ::close(other.fd);
      WorkerChannel channel(fds[1]);
      int status = 0;
      try {
        body(w, channel);
        channel.sendFrame(kEnd, {});
      } catch (const std::exception& error) {
        ByteWriter message;
        message.put<unsigned char>(kindOf(error));
        message.putString(error.what());
        channel.sendFrame(kError, message.bytes());
        status = 1;
      }
      ::close(fds[1]);
      ::_exit(status);
    }
    ::close(fds[1]);
    workers_.push_back({pid, fds[0]});
  }
}

WorkerPool::~WorkerPool() {
  for (auto& worker : workers_) {
    if (worker.fd >= 0) ::close(worker.fd);
    if (worker.pid > 0) {
      ::kill(worker.pid, SIGKILL);
      int status = 0;
      while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
      }
    }
  }
}

void WorkerPool::reportDeath(int worker) {
  auto& entry = workers_[static_cast<std::size_t>(worker)];
  int status = 0;
  while (::waitpid(entry.pid, &status, 0) < 0 && errno == EINTR) {
  }
  entry.pid = -1;
  throwIfInterrupted();
  if (WIFSIGNALED(status)) {
    throw SumoError(fmt::format("worker process {} died from signal {} ({})", worker, WTERMSIG(status),
                                strsignal(WTERMSIG(status))));
  }
  throw SumoError(fmt::format("worker process {} ended unexpectedly (exit code {})", worker,
                              WIFEXITED(status) ? WEXITSTATUS(status) : -1));
}

std::vector<char> WorkerPool::receive(int worker) {
  const int fd = workers_.at(static_cast<std::size_t>(worker)).fd;
  char header[sizeof(unsigned char) + sizeof(std::uint64_t)];
  if (!readAll(fd, header, sizeof(header))) reportDeath(worker);
  ByteReader reader(header, sizeof(header));
  const auto type = reader.get<unsigned char>();
  const auto size = static_cast<std::size_t>(reader.get<std::uint64_t>());
  std::vector<char> payload(size);
  if (!readAll(fd, payload.data(), size)) reportDeath(worker);
  if (type == kData) return payload;
  if (type == kError) {
    ByteReader message(payload);
    const auto kind = static_cast<ErrorKind>(message.get<unsigned char>());
    rethrow(kind, message.getString());
  }
  throw SumoError(fmt::format("worker process {} finished before sending all its results", worker));
}

void WorkerPool::finish() {
  for (std::size_t w = 0; w < workers_.size(); ++w) {
    auto& worker = workers_[w];
    char header[sizeof(unsigned char) + sizeof(std::uint64_t)];
    if (!readAll(worker.fd, header, sizeof(header))) reportDeath(static_cast<int>(w));
    ByteReader reader(header, sizeof(header));
    if (reader.get<unsigned char>() != kEnd) {
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
