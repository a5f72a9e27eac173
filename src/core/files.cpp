#include "vsd/core/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <fmt/format.h>
#include <openssl/evp.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/interrupt.hpp"

namespace fs = std::filesystem;

namespace vsd {

namespace {

/// Writes `contents` to `path` (truncating) and closes it; errors name `shown`.
void writeWholeFile(const fs::path& path, const std::string& contents, const fs::path& shown) {
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  if (!stream) throw IoError(shown.string() + ": cannot open for writing");
  stream << contents;
  stream.close();
  if (!stream) throw IoError(shown.string() + ": write failed (disk full?)");
}

bool processAlive(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

/// The pid in "<prefix><pid><suffix>", or -1 if `name` does not have that form.
long pidIn(const std::string& name, const std::string& prefix, const std::string& suffix) {
  if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return -1;
  }
  const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::strtol(digits.c_str(), nullptr, 10);
}

/// Removes ".<name>.<pid>.part" files of processes that no longer exist.
void removeStaleParts(const fs::path& final_path) {
  const fs::path dir = final_path.parent_path().empty() ? fs::path(".") : final_path.parent_path();
  const std::string prefix = "." + final_path.filename().string() + ".";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const long pid = pidIn(name, prefix, ".part");
    if (pid > 0 && !processAlive(pid)) {
      std::error_code ignored;
      fs::remove(it->path(), ignored);
    }
  }
}

}  // namespace

AtomicOutput::AtomicOutput(fs::path final_path) : finalPath_(std::move(final_path)) {
  // Same directory as the final file so that rename() never crosses file systems;
  // a leading dot and the ".part" suffix make an abandoned file obviously unfinished.
  tempPath_ = finalPath_.parent_path() /
              ("." + finalPath_.filename().string() + "." + std::to_string(::getpid()) + ".part");
  removeStaleParts(finalPath_);
}

AtomicOutput::AtomicOutput(AtomicOutput&& other) noexcept
    : finalPath_(std::move(other.finalPath_)), tempPath_(std::move(other.tempPath_)), active_(other.active_) {
  other.active_ = false;
}

AtomicOutput& AtomicOutput::operator=(AtomicOutput&& other) noexcept {
  if (this != &other) {
    abandon();
    finalPath_ = std::move(other.finalPath_);
    tempPath_ = std::move(other.tempPath_);
    active_ = other.active_;
    other.active_ = false;
  }
  return *this;
}

AtomicOutput::~AtomicOutput() { abandon(); }

void AtomicOutput::commit() { commitFile(/*honour_interruption=*/false); }

void AtomicOutput::commitUnlessInterrupted() { commitFile(/*honour_interruption=*/true); }

void AtomicOutput::commitFile(bool honour_interruption) {
  if (!active_) throw IoError("internal: commit() of an already finished output " + finalPath_.string());
  const std::string name = finalPath_.filename().string();
  faultPoint("atomic.fsync:" + name);
  syncFile(tempPath_);
  if (honour_interruption) throwIfInterrupted();  // the last moment at which the older file stays
  faultPoint("atomic.rename:" + name);
  std::error_code ec;
  fs::rename(tempPath_, finalPath_, ec);
  if (ec) throw IoError(finalPath_.string() + ": cannot rename finished file into place: " + ec.message());
  active_ = false;
  syncDirectory(finalPath_.parent_path().empty() ? fs::path(".") : finalPath_.parent_path());
}

void AtomicOutput::abandon() {
  if (!active_) return;
  std::error_code ec;
  fs::remove(tempPath_, ec);
  active_ = false;
}

void syncFile(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(fmt::format("{}: cannot open to flush it to disk: {}", path.string(), std::strerror(errno)));
  const int status = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (status != 0) throw IoError(fmt::format("{}: cannot flush to disk: {}", path.string(), std::strerror(error)));
}

void syncDirectory(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);  // some file systems refuse fsync on directories; renames are then as durable as they get
  ::close(fd);
}

void requireFileOutputPath(const fs::path& path, const std::string& flag) {
  if (path.empty() || path.filename().empty() || path.filename() == "." || path.filename() == "..") {
    throw ConfigError::field("command line", flag, path.string(), "a file name");
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    throw ConfigError::field("command line", flag, path.string(), "a file name (this is an existing folder)");
  }
  for (fs::path parent = path.parent_path(); !parent.empty(); parent = parent.parent_path()) {
    if (fs::exists(parent, ec)) {
      if (!fs::is_directory(parent, ec)) {
        throw ConfigError::field("command line", flag, path.string(),
                                 fmt::format("a path in a folder ({} is a file)", parent.string()));
      }
      break;
    }
    if (parent == parent.parent_path()) break;
  }
}

void writeTextFileAtomically(const fs::path& path, const std::string& contents) {
  AtomicOutput output(path);
  writeWholeFile(output.tempPath(), contents, path);
  output.commit();
}

std::uintmax_t ReadLimit::effective() const {
  const char* text = std::getenv(variable);
  if (text == nullptr || *text == '\0') return bytes;
  std::uintmax_t value = 0;
  const char* end = text + std::strlen(text);
  const auto [stop, error] = std::from_chars(text, end, value, 10);
  return error == std::errc() && stop == end && value > 0 ? value : bytes;
}

namespace {

/// An open file descriptor, closed on destruction.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

const char* fileTypeName(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string tooLarge(const fs::path& path, const ReadLimit& limit, std::uintmax_t allowed, const std::string& size) {
  return fmt::format("{}: {}: larger than the {} bytes a {} may have (set {} to a larger byte count if it is meant "
                     "to be this large)",
                     path.string(), size, allowed, limit.kind, limit.variable);
}

}  // namespace

std::string readTextFile(const fs::path& path, const ReadLimit& limit) {
  Descriptor file;
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below.
  file.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (file.fd < 0) {
    throw IoError(fmt::format("{}: cannot open for reading ({})", path.string(), std::strerror(errno)));
  }
  struct stat status {};
  if (::fstat(file.fd, &status) != 0) throw IoError(fmt::format("{}: cannot read: {}", path.string(), std::strerror(errno)));
  if (!S_ISREG(status.st_mode)) {
    throw IoError(fmt::format("{}: {}, expected a regular file", path.string(), fileTypeName(status.st_mode)));
  }
  const std::uintmax_t allowed = limit.effective();
  if (static_cast<std::uintmax_t>(status.st_size) > allowed) {
    throw IoError(tooLarge(path, limit, allowed, fmt::format("{} bytes", status.st_size)));
  }
  std::string text;
  std::array<char, 1 << 16> buffer{};
  for (;;) {
    const ssize_t got = ::read(file.fd, buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw IoError(fmt::format("{}: read failed: {}", path.string(), std::strerror(errno)));
    if (got == 0) break;
    // A file that grows while it is read (or reports size 0, as /proc files do) is bounded all the same.
    if (text.size() + static_cast<std::size_t>(got) > allowed) {
      throw IoError(tooLarge(path, limit, allowed, "more bytes"));
    }
    text.append(buffer.data(), static_cast<std::size_t>(got));
  }
  return text;
}

fs::path requirePathInside(const fs::path& base, const fs::path& path, const std::string& where,
                           const std::string& field) {
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(fs::absolute(base), ec);
  const fs::path resolved = fs::weakly_canonical(path.is_absolute() ? path : fs::absolute(base) / path, ec);
  if (ec) throw ConfigError::field(where, field, path.string(), fmt::format("a path that can be resolved ({})", ec.message()));
  const auto mismatch = std::mismatch(root.begin(), root.end(), resolved.begin(), resolved.end());
  if (mismatch.first != root.end()) {
    throw ConfigError::field(where, field, path.string(),
                             fmt::format("a path inside {} (the file's own folder or below; it resolves to {})",
                                         root.string(), resolved.string()));
  }
  return resolved;
}

void requireSafeName(const std::string& name, const std::string& where, const std::string& field) {
  static constexpr const char* kAllowed = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-";
  if (name.empty() || name.front() == '.' || name.size() > 200 || name.find_first_not_of(kAllowed) != std::string::npos) {
    throw ConfigError::field(where, field, name,
                             "a plain name (letters, digits, '.', '_', '-'; not starting with '.'; no '/'): it becomes "
                             "a file or folder name inside the output folder");
  }
}

namespace {

struct DigestContextDeleter {
  void operator()(EVP_MD_CTX* context) const { EVP_MD_CTX_free(context); }
};

std::string hexOf(const unsigned char* bytes, unsigned int size) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex(size * 2U, '0');
  for (unsigned int i = 0; i < size; ++i) {
    hex[2U * i] = kDigits[bytes[i] >> 4U];
    hex[2U * i + 1U] = kDigits[bytes[i] & 0x0FU];
  }
  return hex;
}

class Sha256 {
 public:
  Sha256() : context_(EVP_MD_CTX_new()) {
    if (!context_ || EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr) != 1) {
      throw Error("OpenSSL: cannot initialise SHA-256");
    }
  }
  void update(const void* data, std::size_t size) { EVP_DigestUpdate(context_.get(), data, size); }
  std::string hex() {
    std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
    unsigned int size = 0;
    EVP_DigestFinal_ex(context_.get(), digest.data(), &size);
    return hexOf(digest.data(), size);
  }

 private:
  std::unique_ptr<EVP_MD_CTX, DigestContextDeleter> context_;
};

}  // namespace

std::string sha256OfFile(const fs::path& path) {
  std::error_code ec;
  const auto type = fs::status(path, ec).type();
  if (type != fs::file_type::regular && type != fs::file_type::not_found) {
    throw IoError(path.string() + ": not a regular file (a device, FIFO, socket or folder), cannot hash it");
  }
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw IoError(path.string() + ": cannot open for hashing (does it exist?)");
  Sha256 hasher;
  std::array<char, 1 << 16> buffer{};
  while (stream) {
    stream.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    hasher.update(buffer.data(), static_cast<std::size_t>(stream.gcount()));
  }
  return hasher.hex();
}

std::string sha256OfString(const std::string& bytes) {
  Sha256 hasher;
  hasher.update(bytes.data(), bytes.size());
  return hasher.hex();
}

void ensureDirectory(const fs::path& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) throw IoError(path.string() + ": cannot create directory: " + ec.message());
  if (!fs::is_directory(path)) throw IoError(path.string() + ": exists but is not a directory");
}

TemporaryDirectory::TemporaryDirectory(const std::string& prefix) {
  const char* base = std::getenv("TMPDIR");
  std::string pattern = (fs::path(base && *base ? base : "/tmp") / (prefix + "-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) throw IoError(pattern + ": cannot create temporary directory");
  path_ = pattern;
}

TemporaryDirectory::~TemporaryDirectory() {
  if (keep_) return;
  std::error_code ec;
  fs::remove_all(path_, ec);
}

}  // namespace vsd
