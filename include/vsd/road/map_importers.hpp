#pragma once
// Map importers: one registry entry per map input format (a SUMO network, OpenDRIVE, ...).
// An entry says which files it reads (by their names' endings) and how it turns one into
// a SUMO network; callers pick the entry with forFile() or find(), never by comparing
// format names themselves.
//
// Adding a map format: one source file with a function returning its MapImporter, and one
// line adding it (built-ins: withBuiltins() in src/road/importers/registry.cpp; a test or a
// tool may add() its own). docs/design.md "Adding a surrogate, a decoder, a controller, a
// map importer" has the recipe.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace vsd::road {

struct MapImporter {
  std::string name;         ///< e.g. "opendrive"; unique in a registry
  std::string description;  ///< one line: what the format is and how it is converted
  /// Endings of the file names it reads, lower case, with the dot (".xodr", ".net.xml");
  /// matched case-insensitively; each ending belongs to one entry of a registry.
  std::vector<std::string> extensions;
  /// The SUMO network of `map`: the file itself for a SUMO network, otherwise a network
  /// written into `work_dir` (an existing folder the caller owns and later removes).
  /// Throws ConfigError for a missing or unreadable map, SumoError if a converter fails.
  std::function<std::filesystem::path(const std::filesystem::path& map, const std::filesystem::path& work_dir)> toNet;
};

class MapImporterRegistry {
 public:
  /// The built-in formats: SUMO networks and OpenDRIVE.
  static MapImporterRegistry withBuiltins();

  /// Throws ConfigError if the name or one of the endings is taken, or the entry is incomplete.
  void add(MapImporter importer);
  /// Throws ConfigError naming `name` and listing the known formats.
  const MapImporter& find(const std::string& name) const;
  /// The entry reading `map` (by its name's ending). Throws ConfigError naming the file and
  /// listing the endings every entry reads.
  const MapImporter& forFile(const std::filesystem::path& map) const;
  const std::vector<MapImporter>& importers() const { return importers_; }

 private:
  std::vector<MapImporter> importers_;
};

// Built-in entries, one file each (src/road/importers/).
MapImporter sumoNetImporter();
MapImporter openDriveImporter();

}  // namespace vsd::road
