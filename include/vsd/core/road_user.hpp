#pragma once
// The kinds of road users a scenario can hold, each with its documented default size.
// One table (roadUserKinds) is the single source of these sizes: the scenario language,
// the simulation, map exports and datasets take a road user's length and width from its
// scenario (which defaults them from here), never from a default of their own.
//
// Sizes are the bounding box of the road user (m): length along its heading, width across.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vsd {

/// m: the passenger car's bounding box (the paper's Ego and Co), the table's Car entry.
/// Named so that a struct describing a vehicle before it is known (an observation, a
/// snapshot) can default to a car without repeating the numbers.
inline constexpr double kCarLength = 5.0;
inline constexpr double kCarWidth = 1.8;

/// Codes are stable (concrete.csv, datasets, the controller ABI): new kinds are appended.
enum class RoadUserType : std::uint8_t { Car = 0, Van, Truck, Bus, Motorbike, Pedestrian, StationaryObject, Bicycle };

/// One entry of the road-user table: what the kind is and what it can do.
struct RoadUserKind {
  RoadUserType type = RoadUserType::Car;
  const char* name = "";         ///< identifier in scenario files ("car", "pedestrian", ...)
  const char* description = "";  ///< one line, for docs and error messages
  double length = 0.0;           ///< m, default bounding-box length (> 0)
  double width = 0.0;            ///< m, default bounding-box width (> 0)
  bool drivesInLanes = false;    ///< a vehicle: follows lanes, changes lanes (not a pedestrian or an object)
  bool stationary = false;       ///< never moves (speed 0 throughout)
  /// SUMO's vehicle class (also what sumo-gui draws): pedestrians and objects are SUMO vehicles
  /// too, so that SUMO's collision checks and SSM devices see them.
  const char* sumoClass = "passenger";
};

/// Every kind, in RoadUserType order.
const std::vector<RoadUserKind>& roadUserKinds();
/// The table entry of a type.
const RoadUserKind& roadUserKind(RoadUserType type);
/// The entry named `name` ("car", "van", ...), if any.
std::optional<RoadUserType> findRoadUserType(const std::string& name);
/// "car, van, truck, bus, motorbike, pedestrian, stationary_object" (for error messages).
std::string roadUserTypeList();

}  // namespace vsd
