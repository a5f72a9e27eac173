// The output policy (vsd/core/output_policy.hpp): the kinds core recognises and the one
// check every command makes before it writes.

#include "vsd/core/output_policy.hpp"

#include <H5Cpp.h>
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/hdf5.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vsd {

namespace {

using Identify = std::function<std::optional<std::string>(const fs::path&)>;

std::optional<json> manifestOf(const fs::path& folder) {
  std::error_code ec;
  if (!fs::is_regular_file(folder / "manifest.json", ec)) return std::nullopt;
  try {
    auto manifest = json::parse(readTextFile(folder / "manifest.json"));
    if (manifest.is_object()) return manifest;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::string stringField(const json& manifest, const char* key) {
  const auto it = manifest.find(key);
  return it != manifest.end() && it->is_string() ? it->get<std::string>() : std::string();
}

/// A folder kind recognised by its manifest: `matches` says whether the manifest is of
/// the kind, `subject` reads what it is about.
Identify byManifest(std::function<bool(const json&)> matches, std::function<std::string(const json&)> subject) {
  return [matches = std::move(matches), subject = std::move(subject)](const fs::path& folder) -> std::optional<std::string> {
    const auto manifest = manifestOf(folder);
    if (!manifest || !matches(*manifest)) return std::nullopt;
    return subject(*manifest);
  };
}

std::function<std::string(const json&)> field(const char* key) {
  return [key](const json& manifest) { return stringField(manifest, key); };
}

/// The first `bytes` bytes of a regular file ("" if it cannot be read).
std::string headOf(const fs::path& path, std::size_t bytes) {
  std::ifstream stream(path, std::ios::binary);
  std::string text(bytes, '\0');
  stream.read(text.data(), static_cast<std::streamsize>(bytes));
  text.resize(static_cast<std::size_t>(std::max<std::streamsize>(0, stream.gcount())));
  return text;
}

bool startsWith(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

/// Whether `needle` occurs in the file (read in chunks; stops at `limit` bytes).
bool fileContains(const fs::path& path, const std::string& needle, std::size_t limit) {
  std::ifstream stream(path, std::ios::binary);
  constexpr std::size_t kChunk = 1 << 20;
  std::string window;
  std::size_t read = 0;
  std::string chunk(kChunk, '\0');
  while (stream && read < limit) {
    stream.read(chunk.data(), static_cast<std::streamsize>(kChunk));
    const auto got = static_cast<std::size_t>(stream.gcount());
    if (got == 0) break;
    read += got;
    window = window.substr(window.size() > needle.size() ? window.size() - needle.size() : 0) + chunk.substr(0, got);
    if (window.find(needle) != std::string::npos) return true;
  }
  return false;
}

/// An HDF5 file of ours: the schema attribute starts with `schema`; `subject` reads the rest.
Identify byHdf5Schema(std::string schema, std::function<std::string(const H5::Group&)> subject) {
  return [schema = std::move(schema), subject = std::move(subject)](const fs::path& path) -> std::optional<std::string> {
    if (!startsWith(headOf(path, 8), "\x89HDF\r\n\x1a\n")) return std::nullopt;
    try {
      h5::silenceErrorStack();
      const H5::H5File file(path.string(), H5F_ACC_RDONLY);
      const H5::Group root = file.openGroup("/");
      if (!h5::hasAttribute(root, "schema") || !startsWith(h5::readStringAttribute(root, "schema"), schema)) {
        return std::nullopt;
      }
      return subject(root);
    } catch (const std::exception&) {
      return std::nullopt;
    } catch (const H5::Exception&) {
      return std::nullopt;
    }
  };
}

std::string joined(const std::vector<std::string>& values) { return fmt::format("{}", fmt::join(values, ", ")); }

OutputKind folderKind(std::string noun, std::vector<std::string> writes, Identify identify) {
  OutputKind kind;
  kind.noun = std::move(noun);
  kind.folder = true;
  kind.writes = std::move(writes);
  kind.identify = std::move(identify);
  return kind;
}

OutputKind fileKind(std::string noun, Identify identify) {
  OutputKind kind;
  kind.noun = std::move(noun);
  kind.identify = std::move(identify);
  return kind;
}

bool has(const json& manifest, const char* key) { return manifest.contains(key); }

// --- the checks --------------------------------------------------------------------------

/// "a run folder" / "an evaluation table".
std::string withArticle(const std::string& noun) {
  const bool vowel = !noun.empty() && std::string("aeiou").find(noun.front()) != std::string::npos;
  return (vowel ? "an " : "a ") + noun;
}

std::string about(const std::string& subject) {
  return subject.empty() ? std::string("(its subject not recorded)") : "of " + subject;
}

/// What an existing path is, for messages: "a model file written by vsd-sumo", or "a file
/// vsd-sumo did not write".
std::string describe(const fs::path& path) {
  std::error_code ec;
  const bool folder = fs::is_directory(path, ec);
  for (const auto* kind : output_kinds::all()) {
    if (kind->folder == folder && kind->identify(path)) return withArticle(kind->noun) + " written by vsd-sumo";
  }
  if (folder && manifestOf(path)) return "an output folder of another vsd-sumo command";
  return folder ? "a folder vsd-sumo did not write" : "a file vsd-sumo did not write";
}

/// "run folder", or "output folder" for a folder of another command's manifest.
std::string folderNoun(const fs::path& folder) {
  for (const auto* kind : output_kinds::all()) {
    if (kind->folder && kind->identify(folder)) return kind->noun;
  }
  return "output folder";
}

bool samePath(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

[[noreturn]] void refuse(const OutputRequest& request, const std::string& reason) {
  throw ConfigError(fmt::format("{} {}: {}", request.flag, request.path.string(), reason));
}

void refuseInputs(const OutputRequest& request) {
  for (const auto& [flag, input] : request.inputs) {
    if (!input.empty() && samePath(request.path, input)) {
      refuse(request, fmt::format("is also this command's input ({}); choose another path for the output", flag));
    }
  }
}

/// A file listed in the manifest of a folder above it belongs to that folder's set.
void refusePartOfFolder(const OutputRequest& request) {
  std::error_code ec;
  const fs::path absolute = fs::weakly_canonical(fs::absolute(request.path, ec), ec);
  fs::path folder = absolute.parent_path();
  for (int level = 0; level < 4 && !folder.empty() && folder != folder.root_path(); ++level) {
    if (const auto manifest = manifestOf(folder)) {
      const std::string relative = absolute.lexically_relative(folder).generic_string();
      const auto outputs = manifest->find("outputs");
      if (outputs != manifest->end() && outputs->is_object() && outputs->contains(relative)) {
        // Named as the user named the output: relative to the working folder if it was relative.
        const fs::path shown = request.path.is_relative() ? folder.lexically_relative(fs::current_path(ec)) : folder;
        refuse(request, fmt::format("is part of the {} {} (its manifest.json lists it); write the {} outside that folder",
                                    folderNoun(folder), shown.empty() ? folder.string() : shown.string(),
                                    request.kind->noun));
      }
    }
    folder = folder.parent_path();
  }
}

std::vector<std::string> listedIn(const fs::path& folder) {
  std::vector<std::string> names;
  if (const auto manifest = manifestOf(folder)) {
    const auto outputs = manifest->find("outputs");
    if (outputs != manifest->end() && outputs->is_object()) {
      for (const auto& [name, entry] : outputs->items()) names.push_back(name);
    }
  }
  return names;
}

/// Entries the kind writes that are in the folder but in no manifest: the user's.
void refuseUnlistedEntries(const OutputRequest& request) {
  const auto listed = listedIn(request.path);
  for (const auto& entry : request.kind->writes) {
    std::error_code ec;
    const fs::path path = request.path / entry;
    if (!fs::exists(fs::symlink_status(path, ec))) continue;
    const bool covered = std::any_of(listed.begin(), listed.end(), [&](const std::string& name) {
      return name == entry || startsWith(name, entry + "/");
    });
    if (!covered) refuseUnlistedFile(request.path, entry, listed, request.flag);
  }
}

OutputStatus compareSubjects(const OutputRequest& request, const std::string& existing) {
  if (existing == request.subject) return OutputStatus::Replace;
  if (request.force) return OutputStatus::ForcedReplace;
  refuse(request, fmt::format("holds {} {}, not {}; pass {} to replace it, or choose another path",
                              withArticle(request.kind->noun), about(existing), about(request.subject),
                              request.forceFlag));
}

OutputStatus checkFolder(const OutputRequest& request) {
  std::error_code ec;
  if (!fs::is_directory(request.path, ec)) {
    refuse(request, fmt::format("exists and is {}, not {}; vsd-sumo replaces only its own output of the same kind — "
                                "choose another path",
                                describe(request.path), withArticle(request.kind->noun)));
  }
  const auto existing = request.kind->identify(request.path);
  if (!existing && manifestOf(request.path)) {
    refuse(request, fmt::format("exists and is {}, not {}; vsd-sumo replaces only its own output of the same kind — "
                                "choose another path",
                                describe(request.path), withArticle(request.kind->noun)));
  }
  refuseUnlistedEntries(request);
  return existing ? compareSubjects(request, *existing) : OutputStatus::New;
}

OutputStatus checkFile(const OutputRequest& request) {
  refusePartOfFolder(request);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(request.path, ec))) return OutputStatus::New;
  const auto existing = fs::is_regular_file(request.path, ec) ? request.kind->identify(request.path) : std::nullopt;
  if (!existing) {
    refuse(request, fmt::format("exists and is {}, not {}; vsd-sumo replaces only its own output of the same kind — "
                                "choose another path",
                                describe(request.path), withArticle(request.kind->noun)));
  }
  return compareSubjects(request, *existing);
}

}  // namespace

namespace output_kinds {

const OutputKind& runFolder() {
  static const OutputKind kind = folderKind(
      "run folder", {"concrete.csv", "traces.h5", "dataset.h5", "nets", "fcd"},
      byManifest(
          [](const json& m) {
            return has(m, "functional_scenario") && has(m, "samples") && !has(m, "command") && !has(m, "kind") &&
                   !has(m, "format");
          },
          field("functional_scenario")));
  return kind;
}

const OutputKind& searchFolder() {
  static const OutputKind kind = folderKind(
      "search folder",
      {"concrete.csv", "failures.csv", "learning_curve.csv", "coverage.csv", "estimate.json", "report.html",
       "traces.h5", "dataset.h5"},
      byManifest([](const json& m) { return stringField(m, "command") == "search"; },
                 [](const json& m) {
                   return fmt::format("{}: {}", stringField(m, "functional_scenario"), stringField(m, "criterion"));
                 }));
  return kind;
}

const OutputKind& comparisonFolder() {
  static const OutputKind kind =
      folderKind("comparison report folder", {"report.html", "index.html", "comparison.csv"},
                 byManifest([](const json& m) { return stringField(m, "kind") == "comparison"; }, field("subject")));
  return kind;
}

const OutputKind& deviationsFolder() {
  static const OutputKind kind =
      folderKind("deviations report folder", {"report.html", "deviations.csv"},
                 byManifest([](const json& m) { return stringField(m, "kind") == "deviations"; }, field("subject")));
  return kind;
}

const OutputKind& searchBenchmarkFolder() {
  static const OutputKind kind =
      folderKind("search benchmark folder", {"searches.csv", "surrogates.csv", "README.md"},
                 byManifest([](const json& m) { return stringField(m, "kind") == "search-benchmark"; }, field("subject")));
  return kind;
}

const OutputKind& experimentFolder() {
  static const OutputKind kind = folderKind(
      "experiment results folder", {"ade.csv", "ade.md", "mae.csv", "mae.md", "findings.md"},
      byManifest([](const json& m) { return startsWith(stringField(m, "schema"), "vsd-experiment-results/"); },
                 field("name")));
  return kind;
}

const OutputKind& scenarioExportFolder() {
  static const OutputKind kind = folderKind(
      "scenario export folder", {},
      byManifest([](const json& m) { return has(m, "format") && has(m, "exported"); }, field("functional_scenario")));
  return kind;
}

const OutputKind& datasetFile() {
  static const OutputKind kind = fileKind("dataset file", byHdf5Schema("vsd-dataset/", [](const H5::Group& root) {
                                            return joined(h5::readStrings(root, "labels"));
                                          }));
  return kind;
}

const OutputKind& predictionsFile() {
  static const OutputKind kind =
      fileKind("predictions file", byHdf5Schema("vsd-predictions/", [](const H5::Group& root) {
                 return fmt::format("{} on {}", h5::readStringAttribute(root, "model"),
                                    h5::readStringAttribute(root, "dataset"));
               }));
  return kind;
}

const OutputKind& modelFile() {
  // A torch archive (zip, entries stored uncompressed) whose model description names the
  // format; reading it properly needs libtorch, which core does not link.
  static const OutputKind kind = fileKind("model file", [](const fs::path& path) -> std::optional<std::string> {
    if (!startsWith(headOf(path, 4), "PK\x03\x04")) return std::nullopt;
    if (!fileContains(path, "vsd-model/", std::size_t{1} << 30)) return std::nullopt;
    return std::string();
  });
  return kind;
}

const OutputKind& distributionFile() {
  static const OutputKind kind =
      fileKind("OpenSCENARIO parameter distribution", [](const fs::path& path) -> std::optional<std::string> {
        const std::string head = headOf(path, 1 << 16);
        if (head.find("<OpenSCENARIO") == std::string::npos ||
            head.find("ParameterValueDistribution") == std::string::npos) {
          return std::nullopt;
        }
        return std::string();
      });
  return kind;
}

const OutputKind& sceneDrawing() {
  static const OutputKind kind = fileKind("scene drawing", [](const fs::path& path) -> std::optional<std::string> {
    if (!startsWith(headOf(path, 64), "<svg xmlns=\"http://www.w3.org/2000/svg\" width=")) return std::nullopt;
    return std::string();
  });
  return kind;
}

const std::vector<const OutputKind*>& all() {
  static const std::vector<const OutputKind*> kinds = {
      &runFolder(),   &searchFolder(), &comparisonFolder(), &deviationsFolder(), &searchBenchmarkFolder(), &experimentFolder(),
      &scenarioExportFolder(), &datasetFile(), &predictionsFile(), &modelFile(), &distributionFile(), &sceneDrawing()};
  return kinds;
}

}  // namespace output_kinds

OutputKind textFileKind(const std::string& noun, const std::string& start) {
  return fileKind(noun, [start](const fs::path& path) -> std::optional<std::string> {
    if (!startsWith(headOf(path, start.size()), start)) return std::nullopt;
    return std::string();
  });
}

OutputStatus checkOutput(const OutputRequest& request) {
  if (request.kind == nullptr) throw Error("internal: checkOutput without a kind");
  if (request.path.empty()) throw ConfigError(fmt::format("{}: empty path; expected a path to write to", request.flag));
  refuseInputs(request);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(request.path, ec))) {
    if (!request.kind->folder) refusePartOfFolder(request);
    return OutputStatus::New;
  }
  return request.kind->folder ? checkFolder(request) : checkFile(request);
}

void refuseUnlistedFile(const fs::path& folder, const std::string& relative, const std::vector<std::string>& listed,
                        const std::string& flag) {
  if (std::find(listed.begin(), listed.end(), relative) != listed.end()) return;
  throw ConfigError(fmt::format("{}{}: {} there was not written by vsd-sumo (no manifest.json lists it); it is left "
                                "alone — move it or choose another folder",
                                flag.empty() ? "" : flag + " ", folder.string(), relative));
}

}  // namespace vsd
