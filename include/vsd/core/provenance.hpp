#pragma once
// What a binary was built from, and the rule that committed results name the code that
// produced them.

#include <filesystem>
#include <string>

namespace vsd {

/// Taken when the binary is built (cmake/GitVersion.cmake runs at every build), not when
/// CMake configures: a rebuild after a commit or an edit updates it.
struct BuildProvenance {
  std::string commit;  ///< short git commit; empty when built outside a git checkout
  bool dirty = false;  ///< tracked files differed from that commit when the binary was built
};
BuildProvenance buildProvenance();

/// Throws ConfigError if `output` lies inside the repository's committed results
/// (<source tree>/results) and the binary was built from a dirty tree, unless
/// `allow_dirty`: committed results must name the exact code that ran.
void refuseDirtyCommittedResults(const std::filesystem::path& output, bool allow_dirty, const std::string& flag);
/// The same rule for a given build and source tree (what the overload above applies to this binary).
void refuseDirtyCommittedResults(const std::filesystem::path& output, bool allow_dirty, const std::string& flag,
                                 const BuildProvenance& built, const std::filesystem::path& source_tree);

}  // namespace vsd
