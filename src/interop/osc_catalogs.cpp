#include "osc_catalogs.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"

namespace fs = std::filesystem;

namespace vsd::interop::osc {

namespace {
/// Files looked at per catalog directory: a directory of thousands of files is no catalog.
constexpr std::size_t kMaxCatalogFiles = 256;
}  // namespace

fs::path referencedFile(const OscImportOptions& options, const fs::path& naming_file, const std::string& text,
                        const std::string& where, const std::string& field) {
  const fs::path folder = fs::absolute(naming_file).parent_path();
  if (options.dataRoot.empty()) {
    try {
      return requirePathInside(folder, text, where, field);
    } catch (const ConfigError& error) {
      throw ConfigError(fmt::format("{}; --data-root DIR admits files anywhere inside DIR", error.what()));
    }
  }
  const fs::path path(text);
  return requirePathInside(options.dataRoot, path.is_absolute() ? path : folder / path, where, field);
}

Catalogs::Catalogs(const xml::Reader& scenario, const pugi::xml_node& root, const OscImportOptions& options,
                   Findings& findings)
    : findings_(findings) {
  const pugi::xml_node locations = root.child("CatalogLocations");
  if (!locations) return;
  scenario.requireSubset(locations, {"VehicleCatalog", "PedestrianCatalog", "MiscObjectCatalog", "ControllerCatalog",
                                     "EnvironmentCatalog", "ManeuverCatalog", "RouteCatalog", "TrajectoryCatalog"});
  for (const pugi::xml_node& location : locations.children()) {
    if (location.type() != pugi::node_element) continue;
    const std::string kind = location.name();
    if (kind != "VehicleCatalog" && kind != "PedestrianCatalog" && kind != "MiscObjectCatalog" &&
        kind != "ControllerCatalog") {
      findings.note(scenario.where(location), "not read (references to it are refused where they occur)");
      continue;
    }
    scenario.requireSubset(location, {"Directory"});
    const pugi::xml_node directory = scenario.only(location, "Directory");
    // Catalogs are files the scenario makes the tool read: inside its folder (or --data-root) only.
    const fs::path path =
        referencedFile(options, scenario.file(), scenario.text(directory, "path"), scenario.where(directory), "path");
    if (!fs::is_directory(path)) {
      // Files name catalog folders they never use (esmini's examples do); a reference into
      // one fails where it occurs, naming the folders searched.
      findings.note(scenario.where(directory), fmt::format("{} is not a directory: not read", path.string()));
      missing_.push_back(path);
      continue;
    }
    directories_.push_back(path);
    findings.mapped(scenario.where(location), fmt::format("catalog directory {}", path.string()));
  }
}

std::shared_ptr<xml::Reader> Catalogs::catalog(const xml::Reader& scenario, const pugi::xml_node& reference,
                                               const std::string& name) {
  std::shared_ptr<xml::Reader> by_file_name;
  for (const auto& directory : directories_) {
    std::vector<fs::path> files;
    for (const auto& item : fs::directory_iterator(directory)) {
      if (item.path().extension() == ".xosc" && item.is_regular_file()) files.push_back(item.path());
      if (files.size() > kMaxCatalogFiles) {
        scenario.fail(reference, fmt::format("{} holds more than {} .xosc files", directory.string(), kMaxCatalogFiles));
      }
    }
    std::sort(files.begin(), files.end());
    for (const auto& file : files) {
      auto& reader = files_[file];
      if (!reader) reader = std::make_shared<xml::Reader>(file, read_limits::kScenario);
      const pugi::xml_node catalog = reader->root().child("Catalog");
      if (catalog && std::string(catalog.attribute("name").value()) == name) return reader;
      if (file.stem() == name && catalog) by_file_name = reader;
    }
  }
  if (by_file_name) return by_file_name;
  std::vector<std::string> searched;
  for (const auto& directory : directories_) searched.push_back(directory.string());
  for (const auto& directory : missing_) searched.push_back(directory.string() + " (no such directory)");
  scenario.fail(reference, fmt::format("catalogName=\"{}\": no catalog of that name in the catalog directories ({})",
                                       name, searched.empty() ? std::string("none declared")
                                                              : fmt::format("{}", fmt::join(searched, ", "))));
}

std::vector<std::string> Catalogs::unreadAttributes() const {
  std::vector<std::string> unread;
  for (const auto& [file, reader] : files_) {
    const auto more = reader->unreadAttributes();
    unread.insert(unread.end(), more.begin(), more.end());
  }
  return unread;
}

CatalogEntry Catalogs::resolve(const xml::Reader& scenario, const pugi::xml_node& reference,
                               const std::vector<std::string>& kinds) {
  scenario.requireSubset(reference, {"ParameterAssignments"});
  const std::string catalog_name = scenario.text(reference, "catalogName");
  const std::string entry_name = scenario.text(reference, "entryName");
  ParameterValues assigned;
  if (const pugi::xml_node assignments = reference.child("ParameterAssignments")) {
    scenario.requireSubset(assignments, {"ParameterAssignment"});
    for (const pugi::xml_node& assignment : assignments.children("ParameterAssignment")) {
      // OpenSCENARIO names the parameter; esmini also reads a name written as a reference ("$Name").
      scenario.leave(assignment, {"parameterRef"});  // a name, read as written (no parameter resolved in it)
      std::string name = assignment.attribute("parameterRef").value();
      if (!name.empty() && name[0] == '$') {
        name.erase(0, 1);
        findings_.note(scenario.where(assignment),
                       fmt::format("parameterRef=\"${0}\": read as the parameter '{0}' (OpenSCENARIO names it "
                                   "without '$'), as esmini reads it",
                                   name));
      } else {
        name = scenario.text(assignment, "parameterRef");
      }
      assigned[name] = scenario.text(assignment, "value");
    }
  }
  CatalogEntry entry;
  entry.reader = catalog(scenario, reference, catalog_name);
  const pugi::xml_node catalog = entry.reader->root().child("Catalog");
  for (const pugi::xml_node& candidate : catalog.children()) {
    if (candidate.type() == pugi::node_element && entry_name == candidate.attribute("name").value()) {
      entry.node = candidate;
      break;
    }
  }
  if (!entry.node) {
    scenario.fail(reference, fmt::format("entryName=\"{}\": catalog '{}' ({}) has no such entry", entry_name,
                                         catalog_name, entry.reader->file().string()));
  }
  if (std::find(kinds.begin(), kinds.end(), entry.node.name()) == kinds.end()) {
    scenario.fail(reference, fmt::format("entry '{}' is a <{}>, expected {}", entry_name, entry.node.name(),
                                         fmt::join(kinds, " or ")));
  }
  const Parameters parameters = readParameters(*entry.reader, entry.node, {}, assigned, scenario.where(reference));
  for (const auto& [where, what] : parameters.notes) findings_.note(where, what);
  // A catalog entry's constraints hold for the values the reference gives it, as the scenario's own do.
  if (const auto violated = violatedConstraint(*entry.reader, entry.node, parameters.values)) {
    throw ConfigError(fmt::format("{} (as {} uses the entry)", *violated, scenario.where(reference)));
  }
  return entry;
}

}  // namespace vsd::interop::osc
