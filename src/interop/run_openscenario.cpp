#include "vsd/interop/run_openscenario.hpp"

#include <fmt/format.h>

#include "vsd/core/error.hpp"
#include "vsd/core/files.hpp"
#include "vsd/core/log.hpp"
#include "vsd/interop/roundtrip.hpp"

namespace fs = std::filesystem;

namespace vsd::interop {

namespace {
/// The bound for netconvert's reading of an exported road.
constexpr double kNetconvertTolerance = 0.05;  // m
}  // namespace

double netconvertDeviation(const ImportedScenario& imported) {
  TemporaryDirectory work("vsd-xodr-check");
  const auto lanes = netconvertLanes(imported.roadFile, imported.roadId, work.path());
  if (lanes.size() != static_cast<std::size_t>(imported.road.lanes)) {
    throw SumoError(fmt::format("netconvert reads {} lanes from {}, vsd-sumo {}", lanes.size(),
                                imported.roadFile.string(), imported.road.lanes));
  }
  double worst = 0.0;
  for (int lane = 0; lane < imported.road.lanes; ++lane) {
    worst = std::max(worst, polylineDeviation(imported.road.laneCentre(lane), lanes[static_cast<std::size_t>(lane)]));
  }
  return worst;
}

pipeline::RunSummary runOpenScenario(pipeline::RunOptions options, const ImportOptions& import) {
  const ImportedScenario imported = importOpenScenario(options.scenarioFile, import);
  const double deviation = netconvertDeviation(imported);
  if (deviation > kNetconvertTolerance) {
    spdlog::warn("{}: netconvert's lane centres are up to {:.3f} m from vsd-sumo's reading (simulating vsd-sumo's)",
                 imported.roadFile.string(), deviation);
  }
  options.samples = 1;
  options.firstSample = imported.concrete.index;
  options.seed = imported.concrete.seed;
  if (options.outputDir.empty()) options.outputDir = fs::path("out") / options.scenarioFile.stem();
  options.source = [&imported](std::uint64_t) { return pipeline::ScenarioWithRoad{imported.concrete, imported.road}; };
  return pipeline::runScenarios(imported.logical, options);
}

}  // namespace vsd::interop
