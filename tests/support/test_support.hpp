#pragma once
// Paths and helpers shared by the tests.

#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <system_error>
#include <unistd.h>
#include <string>
#include <vector>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/process.hpp"

namespace vsd::test {

inline std::filesystem::path sourceDir() { return VSD_SOURCE_DIR; }
inline std::filesystem::path binaryDir() { return VSD_BINARY_DIR; }
inline std::filesystem::path scenarioFile(const std::string& name) { return sourceDir() / "scenarios" / name; }
inline std::filesystem::path vsdSumo() { return binaryDir() / "vsd-sumo"; }
inline std::filesystem::path cautiousEgoPlugin() { return binaryDir() / "plugins" / "libvsd_cautious_ego.so"; }
/// Debian's python3 (with h5py, numpy, sklearn, traci), not a pyenv one from PATH.
inline std::string python() { return VSD_PYTHON; }

/// A fixture folder built once per build of the test executable and shared by its test
/// processes (ctest runs every TEST in a process of its own, so a per-suite fixture would
/// otherwise be rebuilt for each). Keyed by the executable's size and time: a rebuilt test
/// rebuilds its fixture and drops the older ones. Built under a temporary name and renamed,
/// so no process sees half of one; where two build it at once, the first rename wins.
inline std::filesystem::path sharedFixture(const std::string& name,
                                           const std::function<void(const std::filesystem::path&)>& build) {
  namespace fs = std::filesystem;
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const auto stamp = fs::last_write_time(exe).time_since_epoch().count();
  const fs::path root = binaryDir() / "test-fixtures";
  const std::string prefix = name + "-";
  const fs::path folder = root / (prefix + std::to_string(fs::file_size(exe)) + "-" + std::to_string(stamp));
  if (fs::exists(folder)) return folder;
  fs::create_directories(root);
  for (const auto& entry : fs::directory_iterator(root)) {
    const auto entry_name = entry.path().filename().string();
    std::error_code ignored;  // another process may be removing it too
    if (entry_name.rfind(prefix, 0) == 0 && entry_name.find(".partial-") == std::string::npos) fs::remove_all(entry, ignored);
  }
  const fs::path partial = folder.string() + ".partial-" + std::to_string(::getpid());
  fs::remove_all(partial);
  fs::create_directories(partial);
  build(partial);
  std::error_code lost;
  fs::rename(partial, folder, lost);
  if (lost) fs::remove_all(partial);  // another process renamed its copy first: use that
  return folder;
}

inline std::filesystem::path writeFile(const std::filesystem::path& path, const std::string& contents) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream << contents;
  return path;
}

/// Runs a command; output (stdout + stderr) is captured in a file inside `work`.
inline ProcessResult run(const std::vector<std::string>& argv, const std::filesystem::path& work) {
  std::filesystem::create_directories(work);
  const auto log = work / "command.log";
  std::filesystem::remove(log);
  return runProcess(argv, log);
}

/// Copies a model file with `from` replaced by `to` in its JSON description (inside the
/// torch archive); true on success.
inline bool rewriteModelDescription(const std::filesystem::path& model, const std::filesystem::path& copy,
                                    const std::string& from, const std::string& to) {
  const auto work = copy.parent_path();
  const auto script = writeFile(work / "rewrite_model.py", R"(
import sys, zipfile
src, dst, old, new = sys.argv[1], sys.argv[2], sys.argv[3].encode(), sys.argv[4].encode()
with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_STORED) as zout:
    for item in zin.infolist():
        zout.writestr(item, zin.read(item.filename).replace(old, new))
)");
  return run({python(), script.string(), model.string(), copy.string(), from, to}, work).exitCode == 0;
}

/// Copies a model file with its JSON description edited by `python_edit`, Python
/// statements on the parsed description `d` (e.g. "d['config']['hidden'] = 16").
/// The description is a length-prefixed string in the archive's data.pkl; the length
/// and the zip's checksums are rewritten. True on success.
inline bool rewriteModelDescription(const std::filesystem::path& model, const std::filesystem::path& copy,
                                    const std::string& python_edit) {
  const auto work = copy.parent_path();
  const auto script = writeFile(work / "rewrite_model_description.py", R"(
import sys, zipfile, struct, json
src, dst, edit = sys.argv[1], sys.argv[2], sys.argv[3]
with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_STORED) as zout:
    for item in zin.infolist():
        data = zin.read(item.filename)
        if item.filename.endswith("data.pkl"):
            at = data.find(b'{"architecture"')
            n = struct.unpack("<I", data[at - 4:at])[0]
            d = json.loads(data[at:at + n])
            exec(edit)
            new = json.dumps(d, separators=(",", ":")).encode()
            data = data[:at - 4] + struct.pack("<I", len(new)) + new + data[at + n:]
        zout.writestr(item, data)
)");
  return run({python(), script.string(), model.string(), copy.string(), python_edit}, work).exitCode == 0;
}

/// Copies a model file as if a future vsd-sumo had written it for feature schema v2.
inline bool writeModelForFeatureSchemaV2(const std::filesystem::path& model, const std::filesystem::path& copy) {
  return rewriteModelDescription(model, copy, R"("feature_version":1)", R"("feature_version":2)");
}

/// The files an output folder's manifest lists (relative path -> SHA-256); empty without a manifest.
inline std::map<std::string, std::string> listedOutputs(const std::filesystem::path& folder) {
  std::map<std::string, std::string> set;
  if (!std::filesystem::exists(folder / "manifest.json")) return set;
  for (const auto& [name, entry] : readManifestOutputs(folder)) set[name] = entry.sha256;
  return set;
}

/// Entries of `folder` whose name starts with '.' (staging or commit folders, temporary parts).
inline std::vector<std::string> hiddenEntries(const std::filesystem::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().filename().string().front() == '.') names.push_back(entry.path().filename().string());
  }
  return names;
}

/// Reads a scenario file and replaces `from` by `to` (to derive variants of the paper's scenarios).
/// The message of the ConfigError `action` throws; "(no ConfigError)" when it throws none.
inline std::string configErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const vsd::ConfigError& error) {
    return error.what();
  }
  return "(no ConfigError)";
}

inline std::string scenarioVariant(const std::string& name, const std::string& from, const std::string& to) {
  std::string text = readTextFile(scenarioFile(name));
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("scenarioVariant: '" + from + "' not in " + name);
  text.replace(at, from.size(), to);
  return text;
}

/// acc.yaml with a road that ends at x = 10 m: many Cos reach its end within 5 s
/// and SUMO removes them.
inline std::string shortRoadScenario() {
  std::string text =
      scenarioVariant("acc.yaml", "extension: {before: 30, after: 150}", "extension: {before: 30, after: 0}");
  const std::string range = "x_range: [-55, 55]";
  text.replace(text.find(range), range.size(), "x_range: [-55, 10]");
  return text;
}

}  // namespace vsd::test
