#pragma once
// The experiment's artefact cache (internal to the experiment module).
//
// An artefact is a folder under <out>/cache; next to it, "<folder>.key" holds the
// text of everything it was built from (tool version, input file hashes, sizes,
// seeds, options, the keys of the artefacts it depends on). An artefact is reused
// only if its key file exists and matches exactly. The key is written after the
// artefact is complete and removed before it is rebuilt, so an interrupted run
// never leaves an artefact that looks valid.

#include <filesystem>
#include <string>

namespace vsd::experiment {

/// "name: value" lines, in the order added.
class CacheKey {
 public:
  explicit CacheKey(const std::string& artefact_kind);
  template <typename T>
  CacheKey& add(const std::string& name, const T& value);
  const std::string& text() const { return text_; }
  /// SHA-256 of the text: how dependent artefacts refer to this one.
  std::string digest() const;

 private:
  CacheKey& addText(const std::string& name, const std::string& value);
  std::string text_;
};

class ArtefactCache {
 public:
  explicit ArtefactCache(std::filesystem::path root) : root_(std::move(root)) {}
  std::filesystem::path folder(const std::string& relative) const { return root_ / relative; }
  bool valid(const std::filesystem::path& artefact, const CacheKey& key) const;
  /// Removes the key, then the folder, and recreates the folder empty.
  void clear(const std::filesystem::path& artefact) const;
  /// Marks the artefact complete.
  void commit(const std::filesystem::path& artefact, const CacheKey& key) const;
  static std::filesystem::path keyFile(const std::filesystem::path& artefact);

 private:
  std::filesystem::path root_;
};

}  // namespace vsd::experiment

#include <fmt/format.h>

namespace vsd::experiment {

template <typename T>
CacheKey& CacheKey::add(const std::string& name, const T& value) {
  return addText(name, fmt::format("{}", value));
}

}  // namespace vsd::experiment
