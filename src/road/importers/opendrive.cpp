// Map importer: OpenDRIVE (.xodr), converted to a SUMO network by netconvert.
#include <fmt/format.h>

#include "vsd/core/error.hpp"
#include "vsd/core/process.hpp"
#include "vsd/road/map_importers.hpp"
#include "vsd/road/network.hpp"

namespace fs = std::filesystem;

namespace vsd::road {

void convertOpenDrive(const fs::path& xodr, const fs::path& net, OpenDriveOrigin origin,
                      const std::vector<std::string>& extra) {
  ensureSumoHome();
  if (!fs::exists(xodr)) throw ConfigError(fmt::format("{}: OpenDRIVE file does not exist", xodr.string()));
  const fs::path log = net.string() + ".netconvert.log";
  std::vector<std::string> command = {"netconvert", "--opendrive-files", xodr.string(), "--output-file", net.string(),
                                      "--no-warnings", "true"};
  if (origin == OpenDriveOrigin::AsWritten) command.insert(command.end(), {"--offset.disable-normalization", "true"});
  command.insert(command.end(), extra.begin(), extra.end());
  const auto result = runProcess(command, log);
  std::error_code ignored;
  fs::remove(log, ignored);
  if (result.exitCode != 0 || !fs::exists(net)) {
    fs::remove(net, ignored);
    throw SumoError(fmt::format("netconvert rejects {} (exit code {}): {}", xodr.string(), result.exitCode,
                                firstErrorLine(result.output)));
  }
}

MapImporter openDriveImporter() {
  MapImporter importer;
  importer.name = "opendrive";
  importer.description = "ASAM OpenDRIVE road network, converted by netconvert (elevation dropped)";
  importer.extensions = {".xodr"};
  importer.toNet = [](const fs::path& map, const fs::path& work_dir) {
    const fs::path net = work_dir / "opendrive.net.xml";
    convertOpenDrive(map, net);
    return net;
  };
  return importer;
}

}  // namespace vsd::road
