#pragma once
// A logical scenario (YAML, see scenarios/*.yaml and the README): open inputs
// with their distributions, the road, the vehicles, the Ego's controller, the
// random variations ("noise") and the metrics to compute.
//
// Units: SI (m, s, m/s, m/s^2); angles in the YAML are degrees where the key
// says so (`heading_noise_deg`), radians everywhere in C++.
// Frame: x along the road, y lateral (left positive); the Ego drives towards +x.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/core/control_domains.hpp"
#include "vsd/core/defaults.hpp"
#include "vsd/core/road_user.hpp"
#include "vsd/scenario/expression.hpp"

namespace vsd::scenario {

/// A random draw: uniform [min, max] (the default), normal (optionally
/// truncated to [min, max]), constant, or uniform over a list of choices.
/// Parameters may be expressions over earlier inputs.
struct Distribution {
  enum class Kind { Uniform, Normal, Constant, Choice };
  Kind kind = Kind::Constant;
  Expression min;     ///< uniform lower bound / normal truncation (if hasBounds)
  Expression max;     ///< uniform upper bound / normal truncation (if hasBounds)
  Expression mean;    ///< normal
  Expression stddev;  ///< normal, >= 0
  Expression value;   ///< constant
  std::vector<double> choices;
  bool hasBounds = false;  ///< normal only: truncate to [min, max] by resampling
  double unitScale = 1.0;  ///< multiplies every draw (e.g. degrees in the YAML -> rad)
  std::string where;       ///< "file:line: field" for error messages

  bool isZero() const { return kind == Kind::Constant && value.isConstant() && value.evaluate({}) == 0.0; }
};

/// One open parameter of the logical scenario (a row of the paper's Table I).
struct InputSpec {
  std::string name;
  std::string unit;
  std::string description;
  Distribution distribution;
};

/// Road: a centre line of one of three shapes, `lanes` lanes of lane_width + lane_width_noise
/// each, and straight extensions along the end tangents that keep vehicles on the road
/// beyond the scenario region.
///   polynomial (the paper's): y = f(x, inputs) sampled at `points` equally spaced x in
///              x_range, each point shifted laterally by centre_noise;
///   arc:       constant curvature (0: straight), `length` m along the road from the
///              origin heading +x, sampled densely enough that the polyline stays within
///              1 cm of the circle;
///   polyline:  the region's centre line as given points (e.g. an imported OpenDRIVE road
///              sampled within 1 cm), each segment heading at most kMaxArcTurn from +x.
/// Positions "along the road" (s) are arc lengths on the centre line from the region's start.
struct RoadSpec {
  enum class Shape { Polynomial, Arc, Polyline };
  Shape shape = Shape::Polynomial;
  double xMin = -55.0;   ///< m (polynomial)
  double xMax = 55.0;    ///< m (polynomial)
  int points = 25;       ///< lane points (polynomial); vectors per boundary = points - 1
  Expression centre;     ///< y of the road centre (m) as a function of x and the inputs (polynomial)
  Distribution centreNoise;     ///< m, drawn independently at every point (polynomial)
  Expression curvature;  ///< 1/m, > 0 turns left (arc); |curvature| * length <= kMaxArcTurn
  Expression length;     ///< m, the scenario region along the road (arc), > 0
  std::vector<std::pair<double, double>> centreLine;  ///< m, (x, y) of the region's centre line (polyline)
  int lanes = 1;
  Expression laneWidth = Expression::constant(kDefaultLaneWidth);  ///< m
  Distribution laneWidthNoise;  ///< m, drawn once per concrete scenario
  /// m, one width per lane (lane 0 first) instead of laneWidth (and without noise); empty: laneWidth.
  std::vector<Expression> laneWidths;
  double speedLimit = 50.0;     ///< m/s (SUMO edge speed; scripted vehicles ignore it)
  double extensionBefore = 30.0;  ///< m, straight lead-in before the region
  double extensionAfter = 150.0;  ///< m, straight lead-out after the region
  /// m of paved ground beyond the outer lanes (right of lane 0, left of the last lane)
  /// where pedestrians may stand; not part of SUMO's network or of the vectors.
  double shoulderRight = 0.0;
  double shoulderLeft = 0.0;
};
/// rad: the largest turn of an arc road's region, and the largest angle between +x and a
/// polyline road's segment. Scenes clip lanes by x (as the paper's region is an x range),
/// which needs x to advance along the whole region.
inline constexpr double kMaxArcTurn = 1.4;

/// Scripted speed of a non-Ego vehicle: `initial`, then each phase accelerates
/// with `accel` for `duration`; afterwards constant. Braking stops at 0 (no
/// reversing); a later phase with accel > 0 starts the vehicle again.
struct SpeedPhase {
  Expression duration;  ///< s, >= 0
  Expression accel;     ///< m/s^2
};
struct SpeedProfile {
  Expression initial;  ///< m/s
  std::vector<SpeedPhase> phases;
};

/// The Ego's controller: a built-in name or a name exported by a shared library.
struct ControllerSpec {
  std::string name;
  std::filesystem::path library;  ///< empty for built-ins; relative paths are relative to the scenario file
  std::vector<std::pair<std::string, Expression>> params;  ///< numeric, may use inputs
  /// s (>= 0) from which the controller drives; before, the Ego keeps its initial speed on its
  /// lane's centre line (OpenSCENARIO's scripted phase before an ActivateControllerAction).
  Expression activeFrom = Expression::constant(0.0);
  std::string where;
};

/// A place a trigger measures distances to: along the road (`s` from the region's start,
/// on `lane`'s centre plus `offset`) or in the scenario frame (`x`, `y`).
struct PositionSpec {
  bool inFrame = false;  ///< x/y (true) or s/lane/offset (false)
  Expression s;          ///< m (relative: ds from the road user's centre along the road)
  Expression lane;       ///< lane index (0 = rightmost; relative: lanes left of the road user's lane)
  Expression offset;     ///< m from the lane's centre, > 0 left (relative, acrossFromCentre: from its centre)
  Expression x;          ///< m
  Expression y;          ///< m
  /// Relative to road user `from` ("ego" or an id; empty: a fixed place) where it is when the
  /// place is asked for (a teleport's start; a distance trigger's every check: it moves with it).
  std::string from;
  bool acrossFromCentre = false;  ///< relative: `offset` m left of its centre, on the lane there
  /// Relative in the plane (`{from, dx, dy}`): `x` m ahead along its heading and `y` m to its left
  /// of its reference point (OpenSCENARIO's RelativeObjectPosition); with `axes: frame`, along the
  /// scenario frame's x and y instead (RelativeWorldPosition).
  bool inPlane = false;
  bool frameAxes = false;
};

/// When an action starts (docs/scenario-language.md "Actions and triggers"). Conditions are
/// checked at every recorded instant; the action starts at the first instant the condition
/// holds, plus `delay`. `All` holds when all its members hold at the same instant, `Any`
/// fires when the first of its members fires (each with its own delay).
struct TriggerSpec {
  enum class Kind {
    Time,     ///< simulation time >= value (s); not quantised to instants
    Gap,      ///< bumper-to-bumper gap along the Ego's lane to `reference` vs value (m, `bound`)
    Headway,  ///< time headway of the rear one of the two, or of `subject` (gap / its speed) vs value (s)
    Ttc,      ///< time to collision along the Ego's lane (gap / closing speed) vs value (s; undefined not closing)
    After,    ///< `action` ended (+ delay)
    Speed,          ///< the subject's speed vs value (m/s, `bound`)
    RelativeSpeed,  ///< the subject's speed minus `reference`'s vs value (m/s)
    Accel,          ///< the subject's longitudinal acceleration vs value (m/s^2, < 0 braking)
    Travelled,      ///< the subject has travelled >= value (m) since t = 0
    Distance,       ///< the subject's centre's distance to `position` vs value (m)
    EndOfRoad,      ///< the subject's front has been at or beyond the road region's end for >= value (s)
    All,            ///< every member holds
    Any,            ///< a member fired
  };
  /// Gap, Headway, Ttc, Speed, RelativeSpeed, Accel, Distance: the condition is `quantity <= value`
  /// or `>= value`.
  enum class Bound { AtMost, AtLeast };
  Kind kind = Kind::Time;
  Bound bound = Bound::AtMost;
  Expression value;
  Expression delay;           ///< s, >= 0
  std::string reference = "ego";  ///< road user the condition relates to (Gap, Headway, Ttc, RelativeSpeed)
  /// `of`: whose quantity (the new kinds); empty: the acting road user. Headway: the acting one
  /// or `reference`, whose headway to the other counts, undefined unless the other is ahead
  /// (OpenSCENARIO's); empty: the rear one's, whichever it is.
  std::string subject;
  /// Gap, Headway, Ttc: measured between the two road users' reference points (VehicleSpec::
  /// referencePoint) along the Ego's lane, else bumper to bumper.
  bool betweenReferencePoints = false;
  /// Gap, Headway, Ttc (`measure`): the distance along the Ego's lane (AlongLane), the
  /// straight-line distance between those points (reference points) or between the two bodies
  /// (bumpers) (StraightLine); Gap only: across the Ego's lane, between the points or between
  /// the bodies' sides (< 0 where they overlap sideways) (Lateral).
  enum class Measure { AlongLane, StraightLine, Lateral };
  /// Gap, Headway, Ttc: along the Ego's lane by default. Distance: along or across the Ego's
  /// lane, or in a straight line (what the parser sets where a distance trigger names none).
  Measure measure = Measure::AlongLane;
  /// Distance: from the nearest point of the road user's body (OpenSCENARIO's freespace), from
  /// its reference point (`reference_point`: OpenSCENARIO's freespace="false"), else from its centre.
  bool fromBody = false;
  bool fromReferencePoint = false;
  std::string action;         ///< After: id of the action whose end starts this one
  /// After: at the end of the action's last run (the n-th of its `repeat: n`; OpenSCENARIO's
  /// completeState), not at its first end.
  bool lastRun = false;
  PositionSpec position;      ///< Distance
  std::vector<TriggerSpec> members;  ///< All, Any
  /// Conditions (not Time, After, All, Any): fires only when the condition becomes true, at an
  /// instant it holds after an instant it was checked and did not (OpenSCENARIO's rising edge);
  /// one that holds from its first check waits until it has not held. Else: when it holds.
  bool rising = false;
  /// Conditions as `rising`: fires when the condition stops holding, at an instant it does not
  /// hold after an instant it was checked and did (OpenSCENARIO's falling edge). With `rising`
  /// too: at either (risingOrFalling).
  bool falling = false;
  std::string where;

  /// True for the kinds whose value may be negative.
  bool signedValue() const { return kind == Kind::RelativeSpeed || kind == Kind::Accel; }
};

/// Shape of a speed or lateral transition over its duration.
enum class TransitionShape {
  Step,    ///< at once (speed only)
  Linear,  ///< constant rate
  Smooth,  ///< half a cosine: zero rate at both ends, peak rate pi/2 times the mean rate
  Cubic,   ///< 3 tau^2 - 2 tau^3 (OpenSCENARIO's cubic): zero rate at both ends, peak rate 1.5 times the mean rate
};

/// One scripted manoeuvre of a road user. Numbers are expressions over the inputs.
struct ActionSpec {
  enum class Kind {
    Speed,          ///< change the longitudinal speed
    LaneChange,     ///< move to the centre of another lane
    LateralOffset,  ///< move to an offset from the current lane's centre (0: back)
    Cross,          ///< walk across the road at a speed to an offset (pedestrians)
    /// the Ego only: its controller's set speed (m/s) from the action's start on; the
    /// controller decides how to reach it (as esmini's ACC reads a speed action on its Ego)
    SetSpeed,
    /// the Ego only: from the action's start `controller` drives it (OpenSCENARIO's
    /// AssignControllerAction with ActivateControllerAction)
    Controller,
    /// moves at once to `place` (a lane), keeping its speed and direction (OpenSCENARIO's
    /// TeleportAction in a Story)
    Teleport,
  };
  std::string id;
  Kind kind = Kind::Speed;
  TriggerSpec trigger;
  TransitionShape shape = TransitionShape::Smooth;
  // Speed: target = value (absolute), another road user's speed (`speedReference`, the Ego's
  // by default) + value or * value, or its own speed + value.
  enum class SpeedTarget { Absolute, Relative, Factor, Delta };
  SpeedTarget speedTarget = SpeedTarget::Absolute;
  std::string speedReference = "ego";  ///< Relative, Factor: whose speed ("ego" or a road user's id)
  /// Relative, Factor: keep tracking the reference's speed (shape step) until another speed
  /// action replaces this one; else the target is fixed when the action starts. LateralOffset:
  /// hold the offset, never ending on its own (a later lateral action, a teleport or `ends` ends it).
  bool continuous = false;
  Expression target;     ///< m/s (Speed, SetSpeed); lanes (LaneChange); m (LateralOffset, Cross)
  /// LaneChange: m from the target lane's centre where it ends, > 0 left (OpenSCENARIO's
  /// targetLaneOffset); 0: on the centre.
  Expression targetLaneOffset;
  /// Teleport: where its centre lands, along the road (s from the region's start, lane, offset).
  PositionSpec place;
  /// Ids of actions (any road user's) that end where this one starts if they are under way then:
  /// their road user keeps the speed and the place across the road they have reached
  /// (OpenSCENARIO's Event priority overwrite, which ends the running Events of its Maneuver).
  std::vector<std::string> ends;
  /// LaneChange: target is relative to the road user's own lane (false) or the Ego's (true).
  bool relativeToEgoLane = false;
  /// LaneChange: target is a lane of the road (0: rightmost), not a number of lanes (`lane`).
  bool toRoadLane = false;
  // How fast: exactly one of these (Speed: rate, duration or distance travelled while the speed
  // changes; lateral: lateral speed, lateral acceleration (smooth only) or duration; lane changes
  // also a distance along the road, covered at the speed it has when it starts; Cross: speed).
  enum class Pace { Rate, Duration, LateralSpeed, LateralAccel, Distance };
  Pace pace = Pace::Duration;
  Expression paceValue;  ///< m/s^2 | s | m/s | m/s^2 | m
  /// How many times it may start (>= 1): after it ends, its trigger is checked again from the
  /// next instant on (OpenSCENARIO's maximumExecutionCount). > 1 only with a trigger that can
  /// hold again (no time or after in it).
  int repeat = 1;
  /// Controller: the controller that drives the Ego from the action's start (no active_from).
  ControllerSpec controller;
  /// Controller: what it drives (`domains`); the other domain stays with its controller.
  ControlDomains domains = ControlDomains::Both;
  std::string where;
};

struct VehicleSpec {
  std::string id;
  RoadUserType type = RoadUserType::Car;
  /// The type drawn per concrete scenario: an expression giving a RoadUserType code (an input
  /// whose choices name types, e.g. `choices: [car, truck]`); absent: `type`.
  std::optional<Expression> typeCode;
  bool lengthGiven = false;  ///< else the length comes from the (drawn) type's table entry
  bool widthGiven = false;   ///< else the width does
  int lane = 0;            ///< 0 = rightmost (when given as a number; see laneExpression)
  Distribution headingNoise;  ///< rad, added to the heading at every step (Ego and others)
  /// Where along the road it starts: scenario-frame x on its lane's centre line (the
  /// paper's `x`), arc length `s` along the road centre, `ds` m along the road from the
  /// Ego's start (centre to centre, > 0 ahead; others only), or `gap` m ahead of the Ego
  /// (bumper to bumper along the road, whatever the two lengths; others only).
  enum class Along { X, S, EgoRelative, EgoGap };
  Along along = Along::X;
  Expression x;            ///< m, initial x of the vehicle's centre (Along::X)
  Expression alongValue;   ///< m, s, ds or gap
  /// `ds` and `gap` count from this road user ("ego", or one listed before this one).
  std::string alongFrom = "ego";
  /// The lane as an expression (e.g. an input drawn from choices); absent: `lane`.
  std::optional<Expression> laneExpression;
  bool laneRelativeToEgo = false;  ///< laneExpression counts from the Ego's lane (+1: left of it)
  Expression offset;       ///< m, lateral offset from the lane centre, > 0 left
  Expression headingDeg;   ///< deg, heading relative to the road's direction (pedestrians, objects)
  /// Others that drive in lanes (`direction: against`): it drives against the road's direction,
  /// s decreasing (oncoming traffic, or an overtaker on the Ego's lane); default along it.
  bool againstRoad = false;
  /// Others (`may_start_overlapping: true`): it may start overlapping any road user but the Ego
  /// (obstacles an OpenSCENARIO file places closer than their lengths); default false: refused.
  bool mayStartOverlapping = false;
  double length = 0.0;     ///< m, from the type's table entry unless given
  double width = 0.0;      ///< m
  /// m ahead of its centre along its heading (< 0 behind; within half its length): the point
  /// gap, headway and ttc triggers measure from with `between: reference_points` (an imported
  /// vehicle's OpenSCENARIO reference point, e.g. its rear axle).
  double referencePoint = 0.0;
  // Ego, and others without a speed_profile:
  Expression speed;                   ///< m/s, initial speed
  bool speedRelativeToEgo = false;    ///< others: `relative_speed`, added to the Ego's initial speed
  ControllerSpec controller;
  // Others only:
  bool hasSpeedProfile = false;
  SpeedProfile speedProfile;
  Distribution speedNoise;            ///< m/s, added to the scripted speed at every instant
  /// Others: their manoeuvres; the Ego: set_speed actions only (its controller drives it).
  std::vector<ActionSpec> actions;
  std::string where;

  /// Lane keeping by pure pursuit (the paper's Co): a road user with a heading disturbance
  /// needs a controller that brings it back. Everything else moves exactly in the lane
  /// frame (lateral actions are exact, with no controller lag).
  bool keepsLaneByPurePursuit() const { return !headingNoise.isZero(); }
};

/// Pass/fail criterion over metrics, e.g. `d_min < 2` (true = critical).
struct Criterion {
  std::string name;
  std::string expression;
  std::string where;
};

/// Extra options for SUMO, per logical scenario.
struct SumoOptions {
  std::string collisionAction = "warn";  ///< SUMO --collision.action: none|warn|teleport|remove
  std::vector<std::string> netconvertOptions;
  std::vector<std::string> sumoOptions;
};

struct LogicalScenario {
  std::string name;          ///< functional-scenario label (acc, lk, acc_lk, ...)
  std::string description;
  std::filesystem::path sourceFile;
  double step = kDefaultStep;          ///< s
  double duration = kDefaultHorizon;  ///< s
  std::vector<InputSpec> inputs;
  RoadSpec road;
  VehicleSpec ego;
  std::vector<VehicleSpec> others;
  std::vector<std::string> metrics;  ///< empty: all metrics that apply
  std::vector<Criterion> criteria;
  SumoOptions sumo;

  /// Number of steps (duration / step); instants recorded = steps() + 1.
  int steps() const;
  std::vector<std::string> inputNames() const;
  /// Index of an input by name, if any.
  std::optional<std::size_t> inputIndex(const std::string& input_name) const;
  /// True if some road user moves across lanes (lateral actions, start offsets, crossing).
  bool hasLateralMotion() const;
};

/// Loads and validates a logical scenario. Throws ConfigError with
/// "file:line: field: problem" for malformed YAML, unknown keys, min > max,
/// expressions referencing unknown inputs, non-positive durations, etc.
std::shared_ptr<const LogicalScenario> loadLogicalScenario(const std::filesystem::path& file);
/// Same, from YAML text (`source_name` is used in messages).
std::shared_ptr<const LogicalScenario> parseLogicalScenario(const std::string& yaml_text,
                                                            const std::filesystem::path& source_name);

}  // namespace vsd::scenario
