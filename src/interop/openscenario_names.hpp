#pragma once
// Names shared by the OpenSCENARIO writer and reader (private to the interop module).

namespace vsd::interop::names {

/// Revision written (and the newest read).
inline constexpr int kRevMajor = 1;
inline constexpr int kRevMinor = 2;
/// The road every exported scenario lives on.
inline constexpr const char* kRoadId = "1";

// FileHeader properties: what a re-simulation needs beyond OpenSCENARIO's own elements.
inline constexpr const char* kFunctionalScenario = "vsd-sumo.functional_scenario";
inline constexpr const char* kScenarioFile = "vsd-sumo.scenario_file";
inline constexpr const char* kScenarioSha256 = "vsd-sumo.scenario_sha256";
inline constexpr const char* kSeed = "vsd-sumo.seed";
inline constexpr const char* kSample = "vsd-sumo.sample";
inline constexpr const char* kStep = "vsd-sumo.step";
inline constexpr const char* kRegion = "vsd-sumo.road.x_range";         ///< "x_min x_max" (m)
inline constexpr const char* kExtension = "vsd-sumo.road.extension";    ///< "before after" (m)
inline constexpr const char* kCollisionAction = "vsd-sumo.sumo.collision_action";
inline constexpr const char* kSumoOptions = "vsd-sumo.sumo.options";    ///< JSON array
inline constexpr const char* kNetconvertOptions = "vsd-sumo.sumo.netconvert_options";  ///< JSON array
inline constexpr const char* kMetrics = "vsd-sumo.metrics";             ///< JSON array
inline constexpr const char* kCriteria = "vsd-sumo.criteria";           ///< JSON array of {name, fail_if}
inline constexpr const char* kToolVersion = "vsd-sumo.tool_version";

// Controller properties that are not controller parameters.
inline constexpr const char* kHeadingDisturbance = "vsd-sumo.heading_disturbance_rad";  ///< one value per step
inline constexpr const char* kLibrary = "vsd-sumo.library";
inline constexpr const char* kDescription = "description";

}  // namespace vsd::interop::names
