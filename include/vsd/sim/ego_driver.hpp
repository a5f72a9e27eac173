#pragma once
// Closed loop of one Ego in a running libsumo simulation:
//   observe (SUMO lane geometry + leader; the object list of the road users the simulation
//   hands over) -> controller -> kinematic model -> moveToXY.
// Used for generated scenarios and for closed-loop Egos on arbitrary maps.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "vsd/core/control_domains.hpp"
#include "vsd/sim/controller.hpp"
#include "vsd/sim/sumo_session.hpp"
#include "vsd/sim/vehicle_model.hpp"

namespace vsd::sim {

/// Lane shapes fetched from SUMO once and kept in a frame shifted by a per-lane offset.
class LaneCache {
 public:
  /// The lane in the frame net - offset (the offset must be the same on every call for a lane).
  const MeasuredPolyline& centre(const std::string& lane_id, const Vec2& offset);
  double width(const std::string& lane_id, const Vec2& offset);
  /// Stores a lane known without asking SUMO (its centre in the frame its users pass the offset of).
  void put(const LaneGeometry& lane);

 private:
  struct Entry {
    MeasuredPolyline centre;
    double width;
  };
  const Entry& get(const std::string& lane_id, const Vec2& offset);
  std::unordered_map<std::string, Entry> entries_;
};

/// The lane part of an observation: offsets relative to `projection` (the vehicle's foot
/// point on its lane) and preview points along `preview_line` (the lane, or the lane
/// continued along the route), in the vehicle's frame; `shift` (m, > 0 left) moves the lane
/// sideways (the scenario's lane changes of the Ego: the lane its controller keeps).
Observation::Lane observeLane(const MeasuredPolyline& preview_line, const PolylineProjection& projection,
                              const VehicleState& state, double width, double shift = 0.0);

/// How exactly placeInSumo puts a vehicle across its lane. SUMO without the sublane model
/// uses a vehicle's lateral position only for drawing and position outputs: leaders, gaps,
/// collisions and lane changes use positions along the lane. A vehicle inside its lane can
/// then be matched to the lane (moveToXY keepRoute 1: same lane, same position along it,
/// lateral offset 0) instead of being placed exactly (keepRoute 3), which saves SUMO a
/// sideways-moved copy of the lane shape on every call (a quarter of `vsd-sumo run`'s CPU
/// time) and changes nothing SUMO computes for the simulation. A vehicle near or beyond
/// its lane's edge is still placed exactly: SUMO takes it off the lane then.
class SumoPlacement {
 public:
  /// Every vehicle placed exactly (maps, and whenever SUMO may use lateral positions).
  SumoPlacement() = default;
  /// Vehicles well inside one of `lanes` (in the frame net - offset, as fetched from SUMO)
  /// are matched to it; only for a SUMO for which sumoIgnoresLateralPositions() holds.
  explicit SumoPlacement(const std::vector<LaneGeometry>& lanes);
  /// moveToXY's keepRoute for a vehicle `width` m wide whose front bumper is at `front`
  /// (frame net - offset): 1 (matched) or 3 (exact).
  int keepRoute(const Vec2& front, double width) const;

 private:
  std::vector<MeasuredPolyline> lanes_;
  double narrowest_ = 0.0;  ///< m, the narrowest lane's width
  /// The lane the last vehicle matched (asked first next time; the answer does not depend on it).
  mutable std::size_t lastInside_ = 0;
};

/// True if the running simulation uses no lateral position of a vehicle on a lane: no
/// sublane model, no FCD output, no collision checks on junctions (SUMO's options).
bool sumoIgnoresLateralPositions();

/// Places a vehicle in SUMO at `state` (its centre, in the frame shifted by `offset` from
/// the network's): SUMO positions vehicles by their front bumper. keepRoute 3 matches only
/// along the vehicle's own route (never onto a neighbouring scenario's road) and places it
/// exactly, even off the lane; keepRoute 1 (where `placement` allows) matches the same way.
/// `against_road`: it drives against its lanes' direction, and SUMO, whose vehicles occupy the
/// lane from their front back along it, gets its rear bumper (the end that leads along the
/// lane), so that its body covers the stretch of lane it does (SUMO's leaders, gaps, collisions).
void placeInSumo(const std::string& vehicle_id, const VehicleState& state, double length, double width,
                 const Vec2& offset, const SumoPlacement& placement, bool against_road);

/// placeInSumo for a vehicle SUMO has not inserted yet, on the road whose lanes are `lanes` (frame net - offset).
/// SUMO inserts a vehicle first placed beyond every lane (a pedestrian on the shoulder: the network has only the
/// lanes) with no lane at all, and SUMO 1.15's FCD output, which names every vehicle's lane, then crashes. Such a
/// vehicle is first put on the nearest lane (libsumo's moveTo inserts it at once), and placeInSumo then moves it
/// to where it is, off the lane, as it moves a vehicle that leaves its lane later: SUMO has it there, on no lane.
void enterSumo(const std::string& vehicle_id, const VehicleState& state, double length, double width,
               const Vec2& offset, const SumoPlacement& placement, const std::vector<LaneGeometry>& lanes,
               bool against_road);

class EgoDriver {
 public:
  /// `offset`: net coordinates of the scenario frame's origin. The vehicle must
  /// already exist in SUMO (added, not necessarily inserted yet).
  EgoDriver(std::string vehicle_id, std::unique_ptr<EgoController> controller, const VehicleState& initial,
            double length, double width, const Vec2& offset, VehicleLimits limits = {});

  const VehicleState& state() const { return state_; }
  const std::string& vehicleId() const { return vehicleId_; }

  /// How pushToSumo places the vehicle from now on (default: exactly).
  void placeBy(SumoPlacement placement) { placement_ = std::move(placement); }
  /// The coverage of the object list from now on (default: ObjectSensor{}, UN R157's ranges).
  void observeWith(const ObjectSensor& sensor) { sensor_ = sensor; }
  /// The SUMO ids of the road users that drive against the road: SUMO reports a leader's speed
  /// as a magnitude, and one of them closes in with it (Observation::Leader::speed < 0).
  void knowAgainstRoad(std::vector<std::string> vehicle_ids);
  /// The set speed (m/s) the scenario commands from now on (Observation::commandedSetSpeed).
  void commandSetSpeed(std::optional<double> set_speed) { commandedSetSpeed_ = set_speed; }
  /// The road's SUMO edge and its lanes (m across the road from its centre line to each lane's
  /// centre, lane 0 rightmost: RoadGeometry::laneOffset), for commandLaneOffset.
  void knowRoad(std::string edge, std::vector<double> lane_offsets) {
    roadEdge_ = std::move(edge);
    laneOffsets_ = std::move(lane_offsets);
  }
  /// Where the scenario's lane changes and lateral offsets of the Ego have moved the lane its
  /// controller keeps (m across the road, as knowRoad; none: the lane it is in). The
  /// observation's lane is that lane: a controller that keeps its lane follows the move.
  void commandLaneOffset(std::optional<double> road_offset) { commandedLaneOffset_ = road_offset; }
  /// The controller drives from `time` (s) on; before, the Ego keeps its speed and follows its
  /// lane's centre line by pure pursuit (the scripted phase before a scenario activates it),
  /// and the controller is not asked.
  void activateFrom(double time) { activeFrom_ = {time, time}; }
  /// Adds a controller the scenario may hand the Ego to (useController); returns its slot
  /// (the one given at construction is slot 0).
  std::size_t addController(std::unique_ptr<EgoController> controller);
  /// The controller in `slot` drives the `domains` from `time` (s) on, also before
  /// activateFrom's time (a hand-over activates them); one that takes over while it drives no
  /// domain starts afresh (reset), as a newly activated controller does. A controller driving
  /// no domain is not asked; one driving both is asked once per step.
  void useController(std::size_t slot, double time, ControlDomains domains = ControlDomains::Both);
  /// Places the vehicle in SUMO at the current state (moveToXY + speed).
  void pushToSumo() const;
  /// pushToSumo for the first time, before SUMO has inserted the vehicle (enterSumo; `lanes`: its road's).
  void enterSumo(const std::vector<LaneGeometry>& lanes) const;
  /// Moves the vehicle at once to `placed`'s position and heading (a scenario's teleport; it keeps
  /// its speed and its controller), in SUMO on the nearest of `lanes` (its road's).
  void teleport(const VehicleState& placed, const std::vector<LaneGeometry>& lanes);
  /// Builds the controller's observation from SUMO's current state; for a controller that
  /// observes objects, the object list of `road_users` (the other road users at `time`).
  Observation observe(double time, LaneCache& lanes, const std::vector<RoadUserState>& road_users = {}) const;
  /// One closed-loop step: observe, decide, advance the model by dt with the
  /// heading disturbance, push the new pose to SUMO. Throws vsd::Error if the
  /// controller fails.
  void step(double time, double dt, double heading_noise, LaneCache& lanes,
            const std::vector<RoadUserState>& road_users = {});

  /// Range within which a vehicle ahead counts as leader (m).
  static constexpr double kLeaderRange = 200.0;

 private:
  /// m (> 0 left): how far the commanded lane offset lies from the centre of SUMO's lane `lane_id`.
  double keptLaneShift(const std::string& lane_id) const;
  /// The lane centre from `lane_id` on along the Ego's route, at least `length` m if the route allows.
  MeasuredPolyline routeAhead(const std::string& lane_id, LaneCache& lanes, double length) const;

  std::string vehicleId_;
  std::vector<std::unique_ptr<EgoController>> controllers_;
  /// The ones that drive the longitudinal [0] and the lateral [1] domain: of controllers_.
  std::array<EgoController*, 2> drivers_{};
  VehicleState state_;
  double length_;
  double width_;
  Vec2 offset_;
  VehicleLimits limits_;
  double minGap_ = 0.0;
  SumoPlacement placement_;
  ObjectSensor sensor_;
  std::optional<double> commandedSetSpeed_;
  std::string roadEdge_;             ///< the road's SUMO edge (knowRoad)
  std::vector<double> laneOffsets_;  ///< m, per lane of the road (knowRoad)
  std::vector<std::string> againstRoad_;  ///< sorted SUMO ids of road users driving against the road
  std::optional<double> commandedLaneOffset_;
  std::array<double, 2> activeFrom_{0.0, 0.0};  ///< s, per domain as drivers_
};

}  // namespace vsd::sim
