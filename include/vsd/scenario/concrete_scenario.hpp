#pragma once
// A concrete scenario: every input of a logical scenario fixed, and every random
// variation (road-centre noise, lane width, heading noise, speed noise) drawn.
// Sampling is a pure function of (logical scenario, seed, sample index).

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::scenario {

/// A place (PositionSpec evaluated): along the road (s from the region's start, lane, offset),
/// in the scenario frame (x, y), or relative to a road user where it is when asked (s: ds from
/// its centre; lane: lanes left of its lane, or with acrossFromCentre offset from its centre).
struct ConcretePlace {
  bool inFrame = false;
  double s = 0.0;       ///< m
  int lane = 0;         ///< 0 = rightmost
  double offset = 0.0;  ///< m from the lane's centre, > 0 left
  double x = 0.0;       ///< m
  double y = 0.0;       ///< m
  bool relative = false;
  int from = -1;        ///< relative: -1 = the Ego, else index into ConcreteScenario::others
  bool acrossFromCentre = false;
  bool inPlane = false;  ///< relative: x ahead along its heading, y to its left of its reference point
  bool frameAxes = false;  ///< inPlane: x, y along the scenario frame's axes instead
};

/// A trigger with its numbers evaluated and its references resolved.
struct ConcreteTrigger {
  TriggerSpec::Kind kind = TriggerSpec::Kind::Time;
  TriggerSpec::Bound bound = TriggerSpec::Bound::AtMost;
  double value = 0.0;   ///< s, m, m/s or m/s^2
  double delay = 0.0;   ///< s
  int reference = -1;   ///< road user the condition relates to: -1 = the Ego, else index into `others`
  /// Whose quantity (Speed .. EndOfRoad; Headway if `directed`): -1 = the Ego, else index into `others`.
  int subject = -1;
  bool directed = false;  ///< Headway: `subject`'s to the other (undefined unless it is ahead), else the rear one's
  bool betweenReferencePoints = false;  ///< Gap, Headway, Ttc: between reference points, else bumper to bumper
  TriggerSpec::Measure measure = TriggerSpec::Measure::AlongLane;  ///< Gap, Headway, Ttc, Distance: as TriggerSpec's
  bool fromBody = false;  ///< Distance: TriggerSpec::fromBody
  bool fromReferencePoint = false;  ///< Distance: TriggerSpec::fromReferencePoint
  int action = -1;      ///< After: index into ConcreteScenario::actions
  bool lastRun = false;  ///< After: TriggerSpec::lastRun
  ConcretePlace place;  ///< Distance: the place
  std::vector<ConcreteTrigger> members;  ///< All, Any
  bool rising = false;   ///< TriggerSpec::rising
  bool falling = false;  ///< TriggerSpec::falling
};

/// An action with its numbers evaluated (see ActionSpec).
struct ConcreteAction {
  std::string id;
  int owner = 0;  ///< -1: the Ego, else index into ConcreteScenario::others
  ActionSpec::Kind kind = ActionSpec::Kind::Speed;
  ConcreteTrigger trigger;
  TransitionShape shape = TransitionShape::Smooth;
  ActionSpec::SpeedTarget speedTarget = ActionSpec::SpeedTarget::Absolute;
  int speedReference = -1;  ///< Relative, Factor: -1 = the Ego, else index into ConcreteScenario::others
  bool continuous = false;  ///< ActionSpec::continuous: it ends only where it is replaced or ended
  double target = 0.0;  ///< m/s (a factor for SpeedTarget::Factor) | lanes | m
  double targetLaneOffset = 0.0;  ///< m, LaneChange: ActionSpec::targetLaneOffset
  ConcretePlace place;            ///< Teleport: where its centre lands (along the road)
  std::vector<int> ends;          ///< ActionSpec::ends: indices into ConcreteScenario::actions
  bool relativeToEgoLane = false;
  bool toRoadLane = false;  ///< ActionSpec::toRoadLane
  ActionSpec::Pace pace = ActionSpec::Pace::Duration;
  double paceValue = 0.0;  ///< > 0 (a duration may be 0)
  int repeat = 1;          ///< ActionSpec::repeat
  /// Controller: its parameters, evaluated (its name and library: the ActionSpec's).
  std::vector<std::pair<std::string, double>> controllerParams;
  ControlDomains domains = ControlDomains::Both;  ///< Controller: ActionSpec::domains
  std::string where;
};

struct ConcreteVehicle {
  std::string id;
  RoadUserType type = RoadUserType::Car;
  int lane = 0;         ///< starting lane, resolved (relative lanes counted from the Ego's)
  double length = 0.0;  ///< m; no default: from the scenario (which takes it from the type's table entry)
  double width = 0.0;   ///< m
  double referencePoint = 0.0;  ///< m ahead of the centre (VehicleSpec::referencePoint)
  VehicleSpec::Along along = VehicleSpec::Along::X;
  double x = 0.0;       ///< m, initial x of the centre (on the lane's centre line; Along::X)
  double alongValue = 0.0;  ///< m, s, ds or gap (VehicleSpec::Along)
  int alongFrom = -1;       ///< ds and gap count from: -1 = the Ego, else an earlier index into `others`
  double offset = 0.0;  ///< m, lateral offset from the lane centre at the start, > 0 left
  double heading = 0.0; ///< rad, relative to the road's direction at the start (pi: against the road)
  bool againstRoad = false;  ///< drives against the road's direction, s decreasing (VehicleSpec::againstRoad)
  bool mayStartOverlapping = false;  ///< VehicleSpec::mayStartOverlapping
  double speed = 0.0;   ///< m/s, initial speed
  /// Non-Ego vehicles: scripted speed (m/s, >= 0, noise included) at every instant t_k, k = 0..steps,
  /// before any speed action.
  std::vector<double> scriptedSpeed;
  /// Non-Ego vehicles: the speed noise (m/s) in scriptedSpeed at every instant, added to a
  /// speed action's speed too (zeros without speed noise).
  std::vector<double> speedNoise;
  /// rad, disturbance of the vehicle's heading in step k (steps values; all 0 without heading noise).
  std::vector<double> headingNoise;
  /// Keeps its lane by pure pursuit (VehicleSpec::keepsLaneByPurePursuit). True by default:
  /// vehicles built elsewhere (imported from OpenSCENARIO) drive as the paper's Co.
  bool purePursuit = true;
};

struct ConcreteScenario {
  std::shared_ptr<const LogicalScenario> logical;
  std::uint64_t seed = 0;   ///< run seed
  std::uint64_t index = 0;  ///< sample index within the run
  std::vector<double> inputs;        ///< values in logical->inputs order
  std::vector<double> centreNoise;   ///< m, lateral shift at each road point (logical->road.points values)
  /// m, each lane's realised width (lane 0 rightmost): road.lane_width + lane_width_noise for
  /// every lane, or road.lane_widths.
  std::vector<double> laneWidths;
  ConcreteVehicle ego;
  std::vector<ConcreteVehicle> others;
  /// Every road user's actions, road user by road user, in file order; the Ego's last.
  std::vector<ConcreteAction> actions;
  std::vector<std::pair<std::string, double>> controllerParams;  ///< evaluated
  double controllerActiveFrom = 0.0;  ///< s, ControllerSpec::activeFrom evaluated (>= 0)

  double step() const { return logical->step; }
  int steps() const { return logical->steps(); }
  /// "<scenario file>: sample <index>" for messages about one concrete scenario.
  std::string where() const;
};

/// Samples concrete scenario `index` of a run with `seed`. Throws ConfigError if a
/// distribution is invalid for the drawn values (e.g. min > max after evaluating
/// `min: v_ego + 4, max: v_ego - 4`, or a negative phase duration), or a drawn value is
/// out of its range (a negative or NaN speed, a lane the road does not have).
ConcreteScenario sampleConcreteScenario(const std::shared_ptr<const LogicalScenario>& logical, std::uint64_t seed,
                                        std::uint64_t index);

/// The road lane (0: rightmost) a lane change `action` goes to, from the road user's lane
/// `own_lane` with the Ego in `ego_lane` (as written: not checked against the road's lanes).
double laneChangeTarget(const ConcreteAction& action, int own_lane, int ego_lane);

/// Lateral offset (m, left positive) of lane `lane`'s centre from the road centre, for
/// `lanes` lanes of `lane_width` spread symmetrically around it (lane 0 is rightmost).
double laneCentreOffset(int lane, int lanes, double lane_width);
/// The same for lanes of these widths (m, lane 0 rightmost) spread around the road centre
/// (their middle); lanes of one width as above, to the last bit.
double laneCentreOffset(int lane, const std::vector<double>& lane_widths);
/// True if every lane has the width of the first (also for no lanes).
bool oneLaneWidth(const std::vector<double>& lane_widths);
/// m from the road centre to either outer edge of lanes of these widths.
double halfRoadWidth(const std::vector<double>& lane_widths);
/// The lane whose span holds `offset` (m from the road centre, left positive), the outermost
/// lane beyond the edges.
int laneAtOffset(double offset, const std::vector<double>& lane_widths);

/// Scripted speed of a profile at time t (s), without noise; never below 0.
double scriptedSpeedAt(double initial, const std::vector<std::pair<double, double>>& duration_accel_phases, double t);

}  // namespace vsd::scenario
