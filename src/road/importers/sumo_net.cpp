// Map importer: a SUMO network (.net.xml) is simulated as it is.
#include <fmt/format.h>

#include "vsd/core/error.hpp"
#include "vsd/road/map_importers.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

MapImporter sumoNetImporter() {
  MapImporter importer;
  importer.name = "sumo";
  importer.description = "SUMO network (netconvert's output), simulated as it is";
  importer.extensions = {".net.xml"};
  importer.toNet = [](const fs::path& map, const fs::path& /*work_dir*/) {
    if (!fs::is_regular_file(map)) throw ConfigError(fmt::format("{}: SUMO network does not exist", map.string()));
    return map;
  };
  return importer;
}

}  // namespace vsd::road
