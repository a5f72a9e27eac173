// OutputFolder: a folder of outputs that changes as a whole or not at all
// (protocol in vsd/core/files.hpp).

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "vsd/core/error.hpp"
#include "vsd/core/fault.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/interrupt.hpp"
#include "vsd/core/output_policy.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vsd {

namespace {

constexpr const char* kManifest = "manifest.json";
constexpr const char* kObsolete = ".obsolete.json";  // old files the new set lacks (inside a commit folder)
const std::string kStagingPrefix = ".staging-";
const std::string kCommitPrefix = ".commit-";

/// The folder's lock: flock on the directory itself (no lock file to leave behind).
/// Returns the descriptor, or -1 if another process holds it.
int tryLock(const fs::path& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw IoError(fmt::format("{}: cannot open the output folder: {}", folder.string(), std::strerror(errno)));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

void writeJsonDurably(const fs::path& path, const json& value) {
  {
    std::ofstream stream(path, std::ios::binary | std::ios::trunc);
    stream << value.dump(2) << "\n";
    stream.close();
    if (!stream) throw IoError(fmt::format("{}: write failed (disk full?)", path.string()));
  }
  syncFile(path);
}

std::vector<std::string> stagedFiles(const fs::path& staging) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(staging); it != fs::recursive_directory_iterator(); ++it) {
    if (it->path().filename().string().front() == '.') {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) files.push_back(fs::relative(it->path(), staging).generic_string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

/// Removes `path`'s parent folders up to (not including) `root` while they are empty.
void removeEmptyParents(fs::path path, const fs::path& root) {
  std::error_code ec;
  for (path = path.parent_path(); !path.empty() && path != root && fs::is_empty(path, ec) && !ec;
       path = path.parent_path()) {
    fs::remove(path, ec);
  }
}

/// Step 4 of the protocol; idempotent, so that a later process can repeat it
/// after this one died anywhere inside it.
void rollForward(const fs::path& folder, const fs::path& commit_dir) {
  std::error_code ec;
  const fs::path staged_manifest = commit_dir / kManifest;
  if (!fs::exists(staged_manifest)) {  // already published: only the cleanup was left
    fs::remove_all(commit_dir, ec);
    return;
  }
  const json manifest = json::parse(readTextFile(staged_manifest));
  faultPoint("folder.unlink-manifest");
  fs::remove(folder / kManifest, ec);
  if (fs::exists(commit_dir / kObsolete)) {
    for (const auto& old : json::parse(readTextFile(commit_dir / kObsolete))) {
      const std::string name = old.get<std::string>();
      faultPoint("folder.remove:" + name);
      fs::remove(folder / name, ec);
      removeEmptyParents(folder / name, folder);
    }
  }
  std::set<fs::path> touched;
  for (const auto& [name, entry] : manifest.at("outputs").items()) {
    const fs::path source = commit_dir / name;
    if (!fs::exists(source)) continue;  // renamed before an interruption
    faultPoint("folder.rename:" + name);
    const fs::path target = folder / name;
    fs::create_directories(target.parent_path(), ec);
    fs::rename(source, target, ec);
    if (ec) throw IoError(fmt::format("{}: cannot rename the new file into place: {}", target.string(), ec.message()));
    touched.insert(target.parent_path());
  }
  for (const auto& directory : touched) syncDirectory(directory);  // the renames are durable before the manifest
  faultPoint("folder.publish");
  fs::rename(staged_manifest, folder / kManifest, ec);
  if (ec) throw IoError(fmt::format("{}: cannot publish the manifest: {}", (folder / kManifest).string(), ec.message()));
  syncDirectory(folder);
  faultPoint("folder.cleanup");
  fs::remove_all(commit_dir, ec);
}

/// With the lock held: finishes interrupted commits, removes abandoned staging folders.
void recoverLocked(const fs::path& folder) {
  std::vector<fs::path> commits;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(kCommitPrefix, 0) == 0) commits.push_back(it->path());
    if (name.rfind(kStagingPrefix, 0) == 0) {
      std::error_code ignored;
      fs::remove_all(it->path(), ignored);
    }
  }
  // At most one commit can be pending (the lock serialises writers); sorted for determinism anyway.
  std::sort(commits.begin(), commits.end());
  for (const auto& commit : commits) rollForward(folder, commit);
}

/// Whether `folder` holds anything but hidden entries (leftovers of this mechanism, a lock).
bool holdsVisibleEntries(const fs::path& folder) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().filename().string().front() != '.') return true;
  }
  return false;
}

std::set<std::string> listedOutputs(const fs::path& folder) {
  std::set<std::string> names;
  try {
    for (const auto& [name, entry] : readManifestOutputs(folder)) names.insert(name);
  } catch (const Error&) {
    // No readable manifest: nothing of an old set to remove (files without a manifest are left alone).
  }
  return names;
}

}  // namespace

OutputFolder::OutputFolder(fs::path folder, const Options& options) : folder_(folder.lexically_normal()) {
  if (folder_.filename().empty()) folder_ = folder_.parent_path();  // "reports/acc_lk/"
  if (folder_.empty()) folder_ = ".";
  if (fs::exists(folder_) && !fs::is_directory(folder_)) {
    throw ConfigError(fmt::format("{} {}: exists and is not a folder", options.flag, folder_.string()));
  }
  createdFolder_ = !fs::exists(folder_);
  ensureDirectory(folder_);
  lockFd_ = tryLock(folder_);
  if (lockFd_ < 0) {
    throw IoError(fmt::format("{} {}: another vsd-sumo process is writing to this folder", options.flag,
                              folder_.string()));
  }
  try {
    recoverLocked(folder_);
    if (options.refuseExisting && holdsVisibleEntries(folder_)) {
      throw ConfigError(fmt::format("{} {}: the folder exists; choose another or pass {} to replace it", options.flag,
                                    folder_.string(), options.forceFlag));
    }
    staging_ = folder_ / (kStagingPrefix + std::to_string(::getpid()));
    fs::remove_all(staging_);
    ensureDirectory(staging_);
  } catch (...) {
    ::close(lockFd_);
    throw;
  }
}

OutputFolder::~OutputFolder() {
  std::error_code ignored;
  if (!committed_ && !staging_.empty()) fs::remove_all(staging_, ignored);
  if (!committed_ && createdFolder_ && fs::is_empty(folder_, ignored)) fs::remove(folder_, ignored);
  if (lockFd_ >= 0) ::close(lockFd_);
}

fs::path OutputFolder::stage(const fs::path& relative) const {
  const fs::path path = staging_ / relative;
  ensureDirectory(path.parent_path());
  return path;
}

void OutputFolder::stageText(const fs::path& relative, const std::string& contents) const {
  const fs::path path = stage(relative);
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream << contents;
  stream.close();
  if (!stream) throw IoError(fmt::format("{}: write failed (disk full?)", (folder_ / relative).string()));
  staged(relative);
}

void OutputFolder::staged(const fs::path& relative) const {
  if (!fs::is_regular_file(staging_ / relative)) {
    throw IoError(fmt::format("{}: the staged output is missing", (folder_ / relative).string()));
  }
  faultPoint("folder.stage:" + relative.generic_string());
}

std::vector<fs::path> OutputFolder::commit(const json& manifest_in) {
  if (committed_) throw IoError("internal: commit() of an output folder that was already committed");
  if (!manifest_in.is_object()) throw Error("internal: an output folder's manifest must be a JSON object");
  json manifest = manifest_in;
  json outputs = json::object();
  const auto files = stagedFiles(staging_);
  // The output policy's last line of defence, for every writer of a folder: a file of the
  // new set whose name is taken by a file no manifest lists is the user's (docs/output-policy.md).
  const auto old_set = listedOutputs(folder_);
  const std::vector<std::string> listed(old_set.begin(), old_set.end());
  for (const auto& name : files) {
    std::error_code ec;
    if (fs::exists(fs::symlink_status(folder_ / name, ec))) refuseUnlistedFile(folder_, name, listed, "");
  }
  for (const auto& name : files) {
    const fs::path path = staging_ / name;
    faultPoint("folder.fsync:" + name);
    syncFile(path);
    outputs[name] = {{"sha256", sha256OfFile(path)}, {"bytes", fs::file_size(path)}};
  }
  manifest["outputs"] = outputs;
  faultPoint("folder.manifest");
  writeJsonDurably(staging_ / kManifest, sealManifest(manifest));
  json obsolete = json::array();
  for (const auto& old : old_set) {
    if (!outputs.contains(old)) obsolete.push_back(old);
  }
  writeJsonDurably(staging_ / kObsolete, obsolete);
  for (auto it = fs::recursive_directory_iterator(staging_); it != fs::recursive_directory_iterator(); ++it) {
    if (it->is_directory()) syncDirectory(it->path());
  }
  syncDirectory(staging_);

  throwIfInterrupted();  // the last moment at which the old set stays
  faultPoint("folder.decide");
  const fs::path commit_dir = folder_ / (kCommitPrefix + std::to_string(::getpid()));
  std::error_code ec;
  fs::rename(staging_, commit_dir, ec);
  if (ec) throw IoError(fmt::format("{}: cannot commit the new outputs: {}", folder_.string(), ec.message()));
  syncDirectory(folder_);
  committed_ = true;
  rollForward(folder_, commit_dir);

  std::vector<fs::path> paths;
  for (const auto& name : files) paths.push_back(folder_ / name);
  paths.push_back(folder_ / kManifest);
  return paths;
}

namespace {

std::string manifestChecksum(json manifest) {
  manifest.erase(kManifestChecksumKey);
  return sha256OfString(manifest.dump());
}

}  // namespace

json sealManifest(json manifest) {
  manifest[kManifestChecksumKey] = manifestChecksum(manifest);
  return manifest;
}

json readManifest(const fs::path& folder) {
  const fs::path path = folder / kManifest;
  if (!fs::exists(path)) {
    throw DatasetError(fmt::format("{}: no {}: not a complete vsd-sumo output folder (an interrupted run, or "
                                   "written by something else)",
                                   folder.string(), kManifest));
  }
  json manifest;
  try {
    manifest = json::parse(readTextFile(path, read_limits::kState));
    if (!manifest.is_object()) throw DatasetError(fmt::format("{}: damaged manifest: not a JSON object", path.string()));
    if (manifest.contains(kManifestChecksumKey) &&
        manifest.at(kManifestChecksumKey).get<std::string>() != manifestChecksum(manifest)) {
      throw DatasetError(fmt::format("{}: edited after it was written (its {} does not match its contents): the "
                                     "folder's record cannot be trusted; produce it again",
                                     path.string(), kManifestChecksumKey));
    }
  } catch (const json::exception& error) {
    throw DatasetError(fmt::format("{}: damaged manifest: {}", path.string(), error.what()));
  } catch (const IoError& error) {
    throw DatasetError(error.what());
  }
  return manifest;
}

std::map<std::string, ManifestEntry> readManifestOutputs(const fs::path& folder) {
  const json manifest = readManifest(folder);
  std::map<std::string, ManifestEntry> entries;
  try {
    for (const auto& [name, entry] : manifest.at("outputs").items()) {
      entries[name] = {entry.at("sha256").get<std::string>(), entry.at("bytes").get<std::uintmax_t>()};
    }
  } catch (const json::exception& error) {
    throw DatasetError(fmt::format("{}: damaged manifest: {}", (folder / kManifest).string(), error.what()));
  }
  return entries;
}

std::vector<std::string> checkOutputFolder(const fs::path& folder, bool hashes) {
  recoverOutputFolder(folder);  // a decided update counts as done, even if its writer died
  std::vector<std::string> problems;
  std::map<std::string, ManifestEntry> entries;
  try {
    entries = readManifestOutputs(folder);
  } catch (const DatasetError& error) {
    return {error.what()};
  }
  for (const auto& [name, entry] : entries) {
    const fs::path path = folder / name;
    std::error_code ec;
    const auto bytes = fs::file_size(path, ec);
    if (ec) {
      problems.push_back(fmt::format("{}: listed in {} but missing", path.string(), kManifest));
    } else if (bytes != entry.bytes) {
      problems.push_back(fmt::format("{}: {} bytes, but {} lists {} (changed or truncated after it was written)",
                                     path.string(), bytes, kManifest, entry.bytes));
    } else if (hashes && sha256OfFile(path) != entry.sha256) {
      problems.push_back(fmt::format("{}: SHA-256 differs from the one in {} (changed after it was written)",
                                     path.string(), kManifest));
    }
  }
  return problems;
}

void requireCompleteOutputFolder(const fs::path& folder, bool hashes) {
  const auto problems = checkOutputFolder(folder, hashes);
  if (!problems.empty()) throw DatasetError(problems.front());
}

void recoverOutputFolder(const fs::path& folder) {
  try {
    if (!fs::is_directory(folder)) return;
    const int fd = tryLock(folder);
    if (fd < 0) return;  // a writer is at work; it recovers for itself
    try {
      recoverLocked(folder);
    } catch (const std::exception&) {
      // Read-only folder or the like: readers then report the folder as incomplete.
    }
    ::close(fd);
  } catch (const std::exception&) {
  }
}

}  // namespace vsd
