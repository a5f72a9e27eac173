#pragma once
// What the Ego's sensors report: every other road user within the sensor's coverage, with
// its state, kind, size and where it is relative to the Ego's lane and path.
//
// The relation fields come from relateToPath (vsd/core/path_relation.hpp), the one
// definition the in-path metrics use too: a cut-in is "in path" for the controller at the
// same instant as for the metric - as soon as it reaches into the corridor the Ego sweeps
// along its lane, not when SUMO re-assigns the cut-in vehicle's lane.
//
// Units: m, s, rad. Scenario frame.

#include <optional>
#include <string>
#include <vector>

#include "vsd/core/path_relation.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/core/trace.hpp"

namespace vsd::sim {

/// Another road user as the world knows it at one instant (what the simulation hands the
/// Ego's driver): its identity, kind, state and size.
struct RoadUserState {
  int id = 0;  ///< > 0: its place in its scenario's list of road users (1 = the first after the Ego)
  RoadUserType type = RoadUserType::Car;
  VehicleState state;  ///< centre, heading, speed, acceleration
  double length = 0.0;  ///< m, > 0
  double width = 0.0;   ///< m, > 0
};

/// A road user in the Ego's object list: its state and its relation to the Ego's lane and path.
struct ObservedObject : RoadUserState {
  PathRelation relation;
  /// m/s along the Ego's lane at the object's foot point (< 0: it drives against it).
  double longitudinalSpeed() const;
  /// m/s across the Ego's lane, > 0 to the left of its direction of travel.
  double lateralSpeed() const;
};

/// The region an Ego's sensors cover. The defaults are the detection ranges UN Regulation
/// No. 157 (ALKS) asks of a system for speeds up to 60 km/h, original version
/// (E/ECE/TRANS/505/Rev.3/Add.156):
///   forward: paragraph 7.1.1 - at least 46 m ahead, measured from the vehicle's front;
///   lateral: paragraph 7.1.2 - at least the full width of the lanes immediately left and
///            right of the vehicle;
///   rear:    no requirement (the original version has no lane change; the 01 series asks
///            a rearward range of a system that changes lanes, paragraph 7.1.3) - 0 m.
/// A scenario may set each of them (and a field of view) for the system it tests.
struct ObjectSensor {
  /// m, bumper to bumper along the Ego's lane, for road users ahead (>= 0).
  double forwardRange = 46.0;
  /// m, bumper to bumper along the Ego's lane, for road users behind (>= 0).
  double rearRange = 0.0;
  /// m, across the Ego's lane from the side of the corridor the Ego sweeps to the nearest
  /// side of a road user (>= 0; relateToPath's lateral gap); absent: 1.5 widths of the
  /// Ego's lane minus half the Ego's width, which for an Ego on its lane's centre line
  /// covers the full width of both neighbouring lanes.
  std::optional<double> lateralRange;
  /// rad, full opening angle around the Ego's heading in which a road user's centre must
  /// lie, seen from the Ego's centre ((0, 2 pi]; 2 pi: all around).
  double fieldOfView = 2.0 * kPi;

  /// Throws ConfigError "<where>.<field>: got <value>, expected <range>" for a value out of range.
  void validate(const std::string& where) const;
};

/// The object list of an Ego whose lane centre line is `reference_line` (lanes
/// `lane_width` wide, > 0): the road users of `others` within `sensor`'s coverage, in the
/// order given. `ego` is the Ego's footprint (centre, heading, length, width).
std::vector<ObservedObject> observeObjects(const MeasuredPolyline& reference_line, double lane_width,
                                           const Footprint& ego, const std::vector<RoadUserState>& others,
                                           const ObjectSensor& sensor);

/// The nearest road user ahead in the Ego's path (smallest bumper gap along the lane), if any.
const ObservedObject* nearestInPath(const std::vector<ObservedObject>& objects);

}  // namespace vsd::sim
