#include "cache.hpp"

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::experiment {

CacheKey::CacheKey(const std::string& artefact_kind) { addText("artefact", artefact_kind); }

CacheKey& CacheKey::addText(const std::string& name, const std::string& value) {
  text_ += name + ": " + value + "\n";
  return *this;
}

std::string CacheKey::digest() const { return sha256OfString(text_); }

bool ArtefactCache::valid(const fs::path& artefact, const CacheKey& key) const {
  const auto key_file = keyFile(artefact);
  if (!fs::is_directory(artefact) || !fs::is_regular_file(key_file)) return false;
  try {
    return readTextFile(key_file) == key.text();
  } catch (const IoError&) {
    return false;
  }
}

void ArtefactCache::clear(const fs::path& artefact) const {
  std::error_code ignored;
  fs::remove(keyFile(artefact), ignored);
  fs::remove_all(artefact, ignored);
  ensureDirectory(artefact);
}

void ArtefactCache::commit(const fs::path& artefact, const CacheKey& key) const {
  writeTextFileAtomically(keyFile(artefact), key.text());
}

fs::path ArtefactCache::keyFile(const fs::path& artefact) { return fs::path(artefact.string() + ".key"); }

}  // namespace vsd::experiment
