#pragma once
// A kinematic cut-in without SUMO: a controller drives the Ego through the kinematic
// vehicle model on a straight road while another vehicle, scripted in closed form, changes
// into the Ego's lane. The Ego observes exactly what it observes in a simulation - its state,
// its lane (straight, `laneWidth` wide) and the object list (observeObjects) - so the
// controllers, which are functions of their observations, run unchanged and a whole grid of
// cut-ins takes seconds. `vsd-sumo bench reference` runs the regulation's cases with it.
//
// Frame: x along the road, y left; the Ego's lane centre line is y = 0. Units: m, s, rad.

#include <cmath>
#include <limits>

#include "vsd/core/defaults.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/sim/controller.hpp"
#include "vsd/sim/object_list.hpp"

namespace vsd::sim {

/// One cut-in. At t = 0 the Ego drives on its lane's centre line at `egoSpeed`; the other
/// vehicle drives on the centre line of the lane `fromLane` (+1: left, -1: right) at
/// `targetSpeed` with its rear `gap` m ahead of the Ego's front (bumper to bumper, as
/// ASAM's OSC-ALKS cut-ins trigger: CutInVehicle_HeadwayDistanceTrigger_dx0), and starts
/// moving sideways at `lateralSpeed` until its centre is on the Ego's lane centre line. It
/// keeps its speed along the road; its heading follows its velocity.
struct CutIn {
  double egoSpeed = 0.0;      ///< m/s, > 0
  double targetSpeed = 0.0;   ///< m/s along the road, >= 0
  double gap = 0.0;           ///< m, bumper to bumper at t = 0
  double lateralSpeed = 0.0;  ///< m/s, > 0
  int fromLane = 1;           ///< +1 or -1
  double laneWidth = kDefaultLaneWidth;  ///< m (ASAM's ALKS road)
  RoadUserType targetType = RoadUserType::Car;
  double duration = 15.0;  ///< s simulated (stops at a collision)
  double step = 0.01;      ///< s, the controller's step
  ObjectSensor sensor;     ///< the Ego's object list coverage
};

struct CutInOutcome {
  bool collision = false;
  double collisionTime = std::numeric_limits<double>::quiet_NaN();  ///< s
  double impactSpeed = 0.0;  ///< m/s, the Ego's speed minus the other's along the road at the collision
  double minClearance = std::numeric_limits<double>::infinity();  ///< m, footprintGap over the run (<= 0: collision)
  /// s, start of the first step in which the Ego's command decelerates (NaN: never).
  double brakeOnset = std::numeric_limits<double>::quiet_NaN();
  double maxDecel = 0.0;  ///< m/s^2, the largest deceleration commanded (average over a step)
  /// s, start of the first step whose average deceleration reaches `decelMark` (NaN: never).
  double decelMarkTime = std::numeric_limits<double>::quiet_NaN();
};

/// When the other vehicle's centre has moved `deviation` m from its lane's centre (s).
double cutInTimeAtDeviation(const CutIn& cut_in, double deviation);

/// Runs the cut-in with `controller` (initialised and reset by the caller) as the Ego, a
/// car of the road-user table's size. `decel_mark` (m/s^2): the deceleration whose first
/// instant is reported as decelMarkTime.
CutInOutcome simulateCutIn(EgoController& controller, const CutIn& cut_in, double decel_mark = 0.0);

}  // namespace vsd::sim
