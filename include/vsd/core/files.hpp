#pragma once
// Files and folders that change as a whole or not at all.
//
// A single output file is written under a temporary name next to it, closed,
// flushed to disk and only then renamed (AtomicOutput). A folder of outputs
// (a run, a report, experiment results) is one unit (OutputFolder): its files
// are staged, flushed, listed with their SHA-256 and size in a manifest, and
// swapped in as one set; readers check the manifest (checkOutputFolder), and
// the next writer finishes or removes what an interrupted one left behind.
//
// Fault-injection points along the way are listed in vsd/core/fault.hpp.

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace vsd {

/// A file being written. Write to tempPath() and close it; commit() flushes it
/// to disk and renames it to the final path. If the object is destroyed without
/// commit() (error, exception, interruption) the temporary file is removed.
/// Temporary files a killed process left next to the final path
/// (".<name>.<pid>.part" of a process that no longer exists) are removed when
/// the next AtomicOutput for that path is created.
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
  /// Flushes the (closed) temporary file to disk and renames it to the final
  /// path, replacing an older file atomically. Throws IoError naming the path.
  void commit();
  /// Like commit(), but throws InterruptedError before the rename if SIGINT or
  /// SIGTERM arrived (the older file stays): for the one output of a command
  /// the user is stopping. (commit() serves deliberate saves on the way out,
  /// e.g. a training's resume state.)
  void commitUnlessInterrupted();
  /// Removes the temporary file now.
  void abandon();

 private:
  void commitFile(bool honour_interruption);

  std::filesystem::path finalPath_;
  std::filesystem::path tempPath_;
  bool active_ = true;
};

/// An output folder that changes as a whole or not at all.
///
///   OutputFolder folder("out/acc_lk");     // locks it; finishes or removes leftovers
///   write folder.stage("traces.h5"), close it, ...
///   folder.commit(manifest);              // the staged files become the folder's set
///
/// Staged files live in <folder>/.staging-<pid>/ (same file system: renames are
/// atomic). commit():
///   1. flushes every staged file to disk and records its SHA-256 and size,
///   2. writes the manifest (the caller's JSON object plus "outputs":
///      {relative path: {"sha256", "bytes"}}) into the staging folder, with the
///      list of files of the old set that the new one lacks,
///   3. renames the staging folder to .commit-<pid> — the decision: from here on
///      the new set wins, even if the process dies,
///   4. removes the old manifest, then the old files the new set lacks, renames
///      every staged file into place, and renames the manifest last.
/// A folder therefore holds either a complete set described by its manifest,
/// or no manifest (readers refuse it). The next OutputFolder (or reader) on the
/// folder completes an interrupted step 4 and removes staging folders of
/// processes that died before step 3. Files not listed in any manifest (a
/// user's notes, an experiment's cache/) are never touched. Names starting with
/// '.' inside the staging folder are scratch space, not part of the set.
///
/// One writer at a time: the folder is locked (flock on the directory) for the
/// object's lifetime; a second writer gets IoError. Forked workers inherit the
/// lock; they die with the parent.
class OutputFolder {
 public:
  struct Options {
    /// Refuse (ConfigError) a folder that already holds files (other than
    /// hidden ones), naming `flag` and `forceFlag` (e.g. "--out", "--force").
    /// Without it (--force) the new set replaces the old one; files that no
    /// manifest listed are kept all the same.
    bool refuseExisting = false;
    std::string flag = "--out";
    std::string forceFlag = "--force";
  };

  /// Creates the folder if needed. Throws IoError if it cannot be created or is
  /// locked by another process, ConfigError as described in Options.
  explicit OutputFolder(std::filesystem::path folder, const Options& options);
  explicit OutputFolder(std::filesystem::path folder) : OutputFolder(std::move(folder), Options{}) {}
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  /// Without commit(): removes the staged files (and the folder, if this object
  /// created it and it is empty).
  ~OutputFolder();

  const std::filesystem::path& path() const { return folder_; }
  const std::filesystem::path& stagingPath() const { return staging_; }
  /// Where to write the output `relative` (e.g. "traces.h5", "nets/b.net.xml");
  /// its parent folders are created.
  std::filesystem::path stage(const std::filesystem::path& relative) const;
  /// Stages a whole text file.
  void stageText(const std::filesystem::path& relative, const std::string& contents) const;
  /// Declares the staged file `relative` complete and closed (a fault-injection
  /// point; throws IoError if it does not exist).
  void staged(const std::filesystem::path& relative) const;
  /// Makes the staged files the folder's contents (see above). `manifest` must
  /// be a JSON object; "outputs" is added. Returns the final paths of the
  /// outputs in sorted order, then the manifest. Throws InterruptedError before
  /// the decision if a signal arrived (the old set stays), IoError on failure.
  std::vector<std::filesystem::path> commit(const nlohmann::json& manifest);

 private:
  std::filesystem::path folder_;
  std::filesystem::path staging_;
  int lockFd_ = -1;
  bool createdFolder_ = false;
  bool committed_ = false;
};

/// A file of an output folder as its manifest lists it.
struct ManifestEntry {
  std::string sha256;
  std::uintmax_t bytes = 0;
};

/// The key of a manifest's own checksum: the SHA-256 of the manifest's JSON text
/// (compact, keys sorted) without this key. It ties what a manifest says about a folder
/// (seed, scenario hash, sample range, shard, every file's hash) to the manifest: an
/// edited manifest is refused wherever one is read. Manifests written before it existed
/// carry none and are checked by their files' hashes alone.
inline constexpr const char* kManifestChecksumKey = "manifest_sha256";
/// `manifest` with its checksum (kManifestChecksumKey) set.
nlohmann::json sealManifest(nlohmann::json manifest);
/// <folder>/manifest.json, parsed and its checksum checked. Throws DatasetError naming
/// the file if it is missing, damaged, or edited after it was written.
nlohmann::json readManifest(const std::filesystem::path& folder);

/// The "outputs" of <folder>/manifest.json. Throws DatasetError naming the folder
/// if the manifest is missing, damaged or edited.
std::map<std::string, ManifestEntry> readManifestOutputs(const std::filesystem::path& folder);

/// Problems of an output folder, one line each (empty: complete): no manifest
/// (an interrupted or foreign folder), a listed file missing or of another size,
/// with `hashes` also another SHA-256. An interrupted commit is completed first
/// if no process is writing to the folder.
std::vector<std::string> checkOutputFolder(const std::filesystem::path& folder, bool hashes);
/// Throws DatasetError with the first problem of checkOutputFolder().
void requireCompleteOutputFolder(const std::filesystem::path& folder, bool hashes);
/// Completes an interrupted commit and removes staging folders of dead writers,
/// unless another process holds the folder's lock. Never throws.
void recoverOutputFolder(const std::filesystem::path& folder);

/// Flushes a closed file's data to disk (fsync); throws IoError naming it.
void syncFile(const std::filesystem::path& path);
/// Flushes a directory's entries (renames) to disk; best effort.
void syncDirectory(const std::filesystem::path& path);
/// Checks, before any work starts, that `path` can become a file: refuses (ConfigError
/// naming `flag` and the path) an empty path, an existing directory, and a parent
/// that exists but is not a directory. A missing parent is fine (it gets created).
void requireFileOutputPath(const std::filesystem::path& path, const std::string& flag);

/// Writes a whole text file atomically.
void writeTextFileAtomically(const std::filesystem::path& path, const std::string& contents);

/// How much of one kind of input vsd-sumo reads at most. Inputs travel between teams
/// and tools, so none may make the tool read without end: every whole-file read has a
/// limit fitting its kind, which the environment variable `variable` (a byte count)
/// overrides for users who need more.
struct ReadLimit {
  const char* kind;       ///< "scenario file", ... (for messages)
  std::uintmax_t bytes;   ///< default limit
  const char* variable;   ///< environment variable that overrides it

  /// The limit in force: `variable` if it holds a whole number of bytes > 0, else `bytes`.
  std::uintmax_t effective() const;
};

/// The limits of the files vsd-sumo reads whole (README "Bad input").
namespace read_limits {
inline constexpr ReadLimit kScenario{"scenario file (YAML or OpenSCENARIO)", std::uintmax_t{16} << 20,
                                     "VSD_MAX_SCENARIO_BYTES"};
inline constexpr ReadLimit kRoadNetwork{"OpenDRIVE file", std::uintmax_t{64} << 20, "VSD_MAX_ROAD_BYTES"};
inline constexpr ReadLimit kSpec{"experiment spec", std::uintmax_t{1} << 20, "VSD_MAX_SPEC_BYTES"};
inline constexpr ReadLimit kState{"manifest or checkpoint", std::uintmax_t{256} << 20, "VSD_MAX_STATE_BYTES"};
inline constexpr ReadLimit kText{"text file", std::uintmax_t{1} << 30, "VSD_MAX_TEXT_BYTES"};
}  // namespace read_limits

/// Reads a whole regular file of at most `limit` bytes. Throws IoError naming the path
/// if it cannot be opened, is not a regular file (a device such as /dev/zero, a FIFO,
/// a socket or a folder: refused before a byte is read, and without blocking), or is
/// larger than the limit (refused before it is read, naming the limit and its variable).
std::string readTextFile(const std::filesystem::path& path, const ReadLimit& limit = read_limits::kText);

/// `path` resolved (symbolic links and "..") and required to lie inside `base` (itself
/// resolved) or one of its subfolders. Relative paths are relative to `base`. Throws
/// ConfigError "<where>: <field>: got '<path>', expected a path inside <base> (...)" otherwise.
/// For paths that a file names (an OpenDRIVE file, a plugin): a file received from
/// elsewhere must not make the tool read, load or write outside its own folder.
std::filesystem::path requirePathInside(const std::filesystem::path& base, const std::filesystem::path& path,
                                        const std::string& where, const std::string& field);

/// Checks a name that becomes one file or folder name inside an output folder (an
/// experiment's name, a figure's name): one path component of letters, digits, '.',
/// '_' and '-', not starting with '.'. Throws ConfigError naming `where`, `field` and it.
void requireSafeName(const std::string& name, const std::string& where, const std::string& field);

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
