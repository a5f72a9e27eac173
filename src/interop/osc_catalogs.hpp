#pragma once
// OpenSCENARIO catalogs (private to the interop module).
//
// A scenario names catalog directories (<CatalogLocations>); a <CatalogReference> names a
// catalog (catalogName) and an entry (entryName). The directories must lie inside the
// scenario file's folder, like its road file (core/files.hpp requirePathInside): a file
// from elsewhere reads nothing else. The catalog is the file in one of those directories
// whose <Catalog name> is catalogName, or else (as esmini finds them) whose file name is
// catalogName.xosc. The entry's own ParameterDeclarations are evaluated with the
// reference's ParameterAssignments.

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "osc_findings.hpp"
#include "vsd/interop/openscenario_import.hpp"
#include "osc_parameters.hpp"
#include "xml_support.hpp"

namespace vsd::interop::osc {

struct CatalogEntry {
  std::shared_ptr<xml::Reader> reader;  ///< the catalog file, its parameters set for this entry
  pugi::xml_node node;                  ///< <Vehicle>, <Pedestrian>, <MiscObject> or <Controller>
};

/// The file `text` (relative to `namingFile`'s folder) that `namingFile` names: a road
/// network, a catalog directory, a distribution's template. It must lie inside
/// options.dataRoot or, without one, in namingFile's folder or below (never /dev/zero, never
/// ../../elsewhere unless the user widened the root). Throws ConfigError naming where/field.
std::filesystem::path referencedFile(const OscImportOptions& options, const std::filesystem::path& namingFile,
                                     const std::string& text, const std::string& where, const std::string& field);

class Catalogs {
 public:
  /// Reads <CatalogLocations> of `root` (none: no catalogs), directories as referencedFile
  /// admits them. Catalog types the import does not use (environment, maneuver, route,
  /// trajectory) are noted, not read.
  Catalogs(const xml::Reader& scenario, const pugi::xml_node& root, const OscImportOptions& options,
           Findings& findings);

  /// The entry a <CatalogReference> names, which must be one of `kinds` (e.g. {"Vehicle",
  /// "Pedestrian", "MiscObject"}). Throws ConfigError naming the reference for a missing
  /// catalog or entry, or an entry of another kind. Its reader stays valid and keeps this
  /// entry's parameters until the next resolve() of the same catalog.
  CatalogEntry resolve(const xml::Reader& scenario, const pugi::xml_node& reference,
                       const std::vector<std::string>& kinds);
  /// xml::Reader::unreadAttributes of every catalog file read, by file.
  std::vector<std::string> unreadAttributes() const;

 private:
  std::shared_ptr<xml::Reader> catalog(const xml::Reader& scenario, const pugi::xml_node& reference,
                                       const std::string& name);

  Findings& findings_;
  std::vector<std::filesystem::path> directories_;
  std::vector<std::filesystem::path> missing_;  ///< named in the file, not directories: listed in errors
  std::map<std::filesystem::path, std::shared_ptr<xml::Reader>> files_;
};

}  // namespace vsd::interop::osc
