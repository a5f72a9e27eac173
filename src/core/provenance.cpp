#include "vsd/core/provenance.hpp"

#include <fmt/format.h>

#include "vsd/core/error.hpp"

#ifndef VSD_SOURCE_DIR
#define VSD_SOURCE_DIR ""
#endif

namespace fs = std::filesystem;

namespace vsd {

namespace {
/// True if `path` is `folder` or lies below it (both made absolute and normal).
bool isInside(const fs::path& path, const fs::path& folder) {
  const fs::path a = fs::absolute(path).lexically_normal();
  const fs::path b = fs::absolute(folder).lexically_normal();
  const auto relative = a.lexically_relative(b);
  return !relative.empty() && *relative.begin() != "..";
}
}  // namespace

void refuseDirtyCommittedResults(const fs::path& output, bool allow_dirty, const std::string& flag) {
  refuseDirtyCommittedResults(output, allow_dirty, flag, buildProvenance(), VSD_SOURCE_DIR);
}

void refuseDirtyCommittedResults(const fs::path& output, bool allow_dirty, const std::string& flag,
                                 const BuildProvenance& provenance, const fs::path& source) {
  if (allow_dirty || !provenance.dirty || source.empty() || !isInside(output, source / "results")) return;
  throw ConfigError(fmt::format(
      "{}: vsd-sumo was built from commit {} with uncommitted changes, and {} is part of the repository's committed "
      "results, which must name the code that ran; commit and rebuild, or pass {} to write anyway",
      output.string(), provenance.commit, output.string(), flag));
}

}  // namespace vsd
