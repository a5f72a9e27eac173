#pragma once
// An OpenSCENARIO scenario simulated on SUMO's own network of its OpenDRIVE file (`--network`;
// private to the interop module; docs/openscenario-import.md "Network scenarios").
//
// The scenario language has one road; a file whose roads it cannot carry (several roads with
// road users on each, junctions, lanes that open or close) runs on the network netconvert
// builds from the OpenDRIVE file, or on the network and traffic of a SUMO controller's
// configuration (esmini's SumoController). What such a run simulates is the Init: every road
// user starts where the Init places it (world, road or lane positions, anywhere in the file's
// roads) at its Init speed; the Ego is driven by its controller, the others keep their lane and
// speed along the road (straight on where it branches). Stories are refused, one line each.
// The run writes the vectorized scenes around the Ego that `vsd-sumo export` writes for maps.

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "osc_findings.hpp"
#include "osc_road.hpp"
#include "vsd/interop/openscenario_import.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/sim/map_simulation.hpp"

namespace vsd::interop::osc {

/// The roads of an OpenDRIVE file, for positions anywhere on them.
class OpenDriveRoads {
 public:
  /// Reads every road's plan view, lane offsets and lane sections. Throws ConfigError naming
  /// file and line for a road outside what positions are evaluated on (lane <border>s).
  explicit OpenDriveRoads(const std::filesystem::path& xodr);

  /// Where a position on a road is: a point of the file's frame and the direction (rad) of the
  /// road's reference line there.
  struct Pose {
    Vec2 point = Vec2::Zero();
    double heading = 0.0;
  };
  /// The point `t` m left of road `road`'s reference line at `s` (0 .. its length). Throws
  /// ConfigError naming `where` for an unknown road or an s off it.
  Pose roadPoint(const std::string& road, double s, double t, const std::string& where) const;
  /// t (m, > 0 left) of the centre of lane `lane_id` of road `road` at `s`. Throws ConfigError
  /// naming `where` for a lane the road's section at s does not have.
  double laneCentreT(const std::string& road, long lane_id, double s, const std::string& where) const;
  /// rad relative to the reference line: the driving direction of `lane_id` (0 along, pi against)
  /// under the road's traffic rule.
  double laneDirection(const std::string& road, long lane_id) const;
  /// Every road's heights, noted (warned of where they matter): SUMO's network of them is flat.
  void noteElevations(Findings& findings) const;

 private:
  struct Road {
    pugi::xml_node node;
    std::vector<PlanGeometry> geometries;
    double length = 0.0;
    bool leftHandTraffic = false;
  };
  const Road& road(const std::string& id, const std::string& where) const;
  /// m the lanes lie left of the reference line at s (<laneOffset> records).
  double laneOffset(const Road& road, double s) const;

  xml::Reader reader_;
  std::map<std::string, Road> roads_;
};

/// What a network scenario simulates.
struct NetworkScenario {
  std::string name;                      ///< the file's stem
  std::filesystem::path openDrive;       ///< the RoadNetwork's LogicFile
  /// A SUMO controller's configuration: its network and traffic (then openDrive only places the
  /// road users); empty: netconvert's network of openDrive, no other traffic.
  std::filesystem::path sumoConfig;
  std::vector<sim::PlacedRoadUser> roadUsers;  ///< in the OpenDRIVE file's frame; the Ego among them
  std::string ego;                              ///< its id
  std::string controller;                       ///< the Ego's vsd-sumo controller
  std::filesystem::path controllerLibrary;      ///< a plugin's; empty: built-in
  std::vector<std::pair<std::string, double>> controllerParams;
  double duration = 0.0;  ///< s simulated
};

/// Reads `xosc` as a network scenario; refusals go to `findings` (and throw unless it collects).
/// Returns nullopt when something was refused.
std::optional<NetworkScenario> translateNetwork(const std::filesystem::path& xosc, const OscImportOptions& options,
                                                Findings& findings);

/// A network scenario's map for SUMO and its road users in the network's frame (`work`: a folder
/// the caller owns, for netconvert's network).
struct PreparedNetwork {
  sim::MapSource source;
  std::vector<sim::PlacedRoadUser> placed;
};
PreparedNetwork prepareNetwork(const NetworkScenario& scenario, const std::filesystem::path& work);

/// Loads the scenario's network and starts its road users (one step of `step` s): throws
/// ConfigError naming the road user that cannot start, SumoError for a network SUMO rejects;
/// says so in `findings` otherwise.
void checkNetworkStart(const NetworkScenario& scenario, double step, Findings& findings);

/// `run FILE.xosc --network`: the scenario's scenes around the Ego (closed loop), written as
/// `export` writes a dataset file: to run.outputDir (default out/<file stem>.h5).
std::string runNetworkScenario(const pipeline::RunOptions& run, const OscImportOptions& import);

}  // namespace vsd::interop::osc
