#pragma once
// Round trips of exported roads through a real consumer: SUMO's netconvert
// (its OpenDRIVE importer). The reference is the network vsd-sumo generates for
// the same scenario (netconvert plain XML, the net a run simulates on).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "vsd/core/geometry.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::interop {

/// Lane centres of a SUMO .net.xml by lane id (edges of junctions left out), in net coordinates.
/// Throws IoError / DatasetError for unreadable files.
std::map<std::string, Polyline> readNetLanes(const std::filesystem::path& net);

/// Largest distance (m) of a vertex of either polyline from the other polyline.
/// O((n + m) log(n + m)) for typical shapes (a tree of segment boxes), so roads of the
/// largest size the OpenDRIVE reader accepts take milliseconds.
double polylineDeviation(const Polyline& a, const Polyline& b);

/// Converts an OpenDRIVE file with netconvert (coordinates kept as in the file) into
/// `net`. Throws SumoError "netconvert rejects FILE: <its first error line>".
void importWithNetconvert(const std::filesystem::path& xodr, const std::filesystem::path& net);

/// Lane centres netconvert builds from an OpenDRIVE file, by vsd-sumo lane (0 = rightmost)
/// of road `road_id`. Throws SumoError if netconvert rejects the file or the road is missing.
std::vector<Polyline> netconvertLanes(const std::filesystem::path& xodr, const std::string& road_id,
                                      const std::filesystem::path& work_dir);

struct RoundTripDeviation {
  std::uint64_t sample = 0;
  double maxDeviation = 0.0;  ///< m, largest lane-centre distance over all lanes
};

/// For each scenario: exports its road as OpenDRIVE, imports it with netconvert and
/// compares the lane centres with those of the network vsd-sumo generates for it (one
/// plain-XML network for all, as `run` builds it). Files go to `work_dir`.
std::vector<RoundTripDeviation> netconvertRoundTrip(const std::vector<scenario::ConcreteScenario>& scenarios,
                                                    const std::filesystem::path& work_dir);

}  // namespace vsd::interop
