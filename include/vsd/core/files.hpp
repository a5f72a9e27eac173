#pragma once
// File helpers that uphold the project's output rule: a file is written under a
// temporary name and renamed when complete, so an interrupted run never leaves
// a file that looks finished.

#include <filesystem>
#include <string>
#include <vector>

namespace vsd {

/// A file being written. Write to tempPath(); commit() renames it to the final
/// path. If the object is destroyed without commit() (error, exception), the
/// temporary file is removed.
class AtomicOutput {
 public:
  explicit AtomicOutput(std::filesystem::path final_path);
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  AtomicOutput(AtomicOutput&& other) noexcept;
  AtomicOutput& operator=(AtomicOutput&& other) noexcept;
  ~AtomicOutput();

  const std::filesystem::path& tempPath() const { return tempPath_; }
  const std::filesystem::path& finalPath() const { return finalPath_; }
  /// Renames the temporary file to the final path (replacing an older file atomically).
  void commit();
  /// Removes the temporary file now.
  void abandon();

 private:
  std::filesystem::path finalPath_;
  std::filesystem::path tempPath_;
  bool active_ = true;
};

/// Checks, before any work starts, that `path` can become a file: refuses (ConfigError
/// naming `flag` and the path) an empty path, an existing directory, and a parent
/// that exists but is not a directory. A missing parent is fine (it gets created).
void requireFileOutputPath(const std::filesystem::path& path, const std::string& flag);

/// Writes a whole text file atomically.
void writeTextFileAtomically(const std::filesystem::path& path, const std::string& contents);

/// Reads a whole file; throws IoError naming the path.
std::string readTextFile(const std::filesystem::path& path);

/// Lower-case hex SHA-256 of a file's bytes; throws IoError naming the path.
std::string sha256OfFile(const std::filesystem::path& path);
/// Lower-case hex SHA-256 of a string.
std::string sha256OfString(const std::string& bytes);

/// Creates a directory (and parents); throws IoError naming the path.
void ensureDirectory(const std::filesystem::path& path);

/// A fresh private temporary directory, removed (recursively) on destruction
/// unless keep() was called.
class TemporaryDirectory {
 public:
  explicit TemporaryDirectory(const std::string& prefix = "vsd");
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  ~TemporaryDirectory();
  const std::filesystem::path& path() const { return path_; }
  void keep() { keep_ = true; }

 private:
  std::filesystem::path path_;
  bool keep_ = false;
};

}  // namespace vsd
