// The registry of map importers: built-ins listed in withBuiltins(), one file each here.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "vsd/core/error.hpp"
#include "vsd/road/map_importers.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

namespace {

std::string lowerCase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool endsWith(const std::string& text, const std::string& ending) {
  return text.size() >= ending.size() && text.compare(text.size() - ending.size(), ending.size(), ending) == 0;
}

}  // namespace

MapImporterRegistry MapImporterRegistry::withBuiltins() {
  MapImporterRegistry registry;
  registry.add(sumoNetImporter());
  registry.add(openDriveImporter());
  return registry;
}

void MapImporterRegistry::add(MapImporter importer) {
  if (importer.name.empty() || importer.extensions.empty() || !importer.toNet) {
    throw ConfigError(fmt::format("map importer '{}': needs a name, at least one file ending and a conversion",
                                  importer.name));
  }
  for (const auto& existing : importers_) {
    if (existing.name == importer.name) throw ConfigError(fmt::format("map importer '{}' is registered twice", importer.name));
    for (const auto& ending : importer.extensions) {
      const auto& taken = existing.extensions;
      if (std::find(taken.begin(), taken.end(), lowerCase(ending)) != taken.end()) {
        throw ConfigError(fmt::format("map importer '{}': files ending in '{}' are read by '{}' already", importer.name,
                                      ending, existing.name));
      }
    }
  }
  for (auto& ending : importer.extensions) ending = lowerCase(ending);
  importers_.push_back(std::move(importer));
}

const MapImporter& MapImporterRegistry::find(const std::string& name) const {
  std::vector<std::string> known;
  for (const auto& importer : importers_) {
    if (importer.name == name) return importer;
    known.push_back(importer.name);
  }
  throw ConfigError(fmt::format("unknown map format '{}' (known: {})", name, fmt::join(known, ", ")));
}

const MapImporter& MapImporterRegistry::forFile(const fs::path& map) const {
  const std::string file_name = lowerCase(map.filename().string());
  // The longest matching ending wins (".net.xml" before a hypothetical ".xml").
  const MapImporter* best = nullptr;
  std::size_t best_length = 0;
  std::vector<std::string> endings;
  for (const auto& importer : importers_) {
    for (const auto& ending : importer.extensions) {
      endings.push_back(fmt::format("{} ({})", ending, importer.name));
      if (endsWith(file_name, ending) && ending.size() > best_length) {
        best = &importer;
        best_length = ending.size();
      }
    }
  }
  if (best == nullptr) {
    throw ConfigError(fmt::format("{}: not a map format vsd-sumo reads (known file endings: {})", map.string(),
                                  fmt::join(endings, ", ")));
  }
  return *best;
}

}  // namespace vsd::road
