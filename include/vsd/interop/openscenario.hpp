#pragma once
// OpenSCENARIO 1.2 (XML) for concrete scenarios, and back.
//
// A concrete scenario becomes <stem>.xosc + <stem>.xodr (opendrive.hpp):
//   FileHeader      author vsd-sumo, revision 1.2, date = the scenario file's modification
//                   time; Properties "vsd-sumo.*": functional scenario, scenario file and
//                   SHA-256, seed, sample, step, scenario region, SUMO options, metrics, criteria
//   ParameterDeclarations  every sampled input (double) — where the scenario came from
//   CatalogLocations  ControllerCatalog in the same folder (vsd_controllers.xosc: the built-ins)
//   RoadNetwork     LogicFile = the .xodr
//   Entities        one Vehicle per vehicle: BoundingBox (reference point = the box centre,
//                   the point vsd-sumo's traces use), Performance (the kinematic limits),
//                   nominal Axles (required by the schema; vsd-sumo's model has none)
//   Init            per vehicle: TeleportAction to a LanePosition (road 1, its lane, s, offset),
//                   SpeedAction (step) to its initial speed; the Ego: AssignControllerAction
//                   with an inline Controller named after the vsd-sumo controller, its
//                   parameters as Properties, plus "vsd-sumo.heading_disturbance_rad" (one value
//                   per step) and "vsd-sumo.library" for plugins
//   Story           per other vehicle one Event per step k: at simulation time t_k
//                   (SimulationTimeCondition greaterOrEqual) a step SpeedAction to the speed it
//                   drives with from t_k to t_k+1 (its scripted speed at t_k+1, noise included)
//   StopTrigger     SimulationTimeCondition at the scenario's duration
//
// importOpenScenario reads these files back — and simple hand-written ones within the
// supported subset (README "OpenSCENARIO subset") — into a scenario `vsd-sumo run` simulates.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::interop {

/// File name of the controller catalog written next to exported scenarios.
inline constexpr const char* kControllerCatalogFile = "vsd_controllers.xosc";

/// Fields of the FileHeader that do not come from the concrete scenario.
struct ExportHeader {
  std::string date;            ///< ISO 8601 (xsd:dateTime), e.g. 2024-05-01T12:00:00
  std::string scenarioSha256;  ///< of the logical scenario file (empty: unknown)
};

/// The .xosc text of one concrete scenario whose road file is `xodr_name` (relative to the .xosc).
/// Throws ConfigError if a vehicle starts outside its road.
std::string openScenarioText(const scenario::ConcreteScenario& concrete, const road::RoadGeometry& road,
                             const std::string& xodr_name, const ExportHeader& header);

struct ExportedFiles {
  std::filesystem::path xosc;
  std::filesystem::path xodr;
};
/// Writes <dir>/<stem>.xodr and <dir>/<stem>.xosc (each atomically).
ExportedFiles exportConcreteScenario(const scenario::ConcreteScenario& concrete, const std::filesystem::path& dir,
                                     const std::string& stem, const ExportHeader& header);

/// The controller catalog: one Controller per name the registry offers, its description as a Property.
std::string controllerCatalogText(const std::map<std::string, std::string>& controllers, const std::string& date);

/// ISO 8601 UTC modification time of a file (deterministic per input: exports of the same
/// scenario file are byte-identical).
std::string fileDate(const std::filesystem::path& file);

/// A scenario read from OpenSCENARIO, ready for pipeline::runScenarios.
struct ImportedScenario {
  std::shared_ptr<const scenario::LogicalScenario> logical;  ///< one concrete scenario's worth: inputs constant
  scenario::ConcreteScenario concrete;
  road::RoadGeometry road;
  std::filesystem::path roadFile;  ///< the OpenDRIVE file
  std::string roadId;              ///< its road's id
};

struct ImportOptions {
  /// Simulation step (s) for files that do not carry "vsd-sumo.step"; a file's own step wins.
  std::optional<double> step;
};

/// Reads `xosc` and the OpenDRIVE file it names. Throws ConfigError with
/// "file:line: ..." for malformed files, elements outside the supported subset
/// (naming the element), missing step, vehicles off their lanes, and the like.
ImportedScenario importOpenScenario(const std::filesystem::path& xosc, const ImportOptions& options = {});

}  // namespace vsd::interop
