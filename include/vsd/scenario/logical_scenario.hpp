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

/// Road: a centre line y = f(x, inputs) sampled at `points` equally spaced x in
/// x_range, each shifted laterally by centre_noise; `lanes` lanes of
/// lane_width + lane_width_noise each. Straight extensions along the end
/// tangents keep vehicles on the road beyond the scenario region.
struct RoadSpec {
  double xMin = -55.0;   ///< m
  double xMax = 55.0;    ///< m
  int points = 25;       ///< lane points; vectors per boundary = points - 1
  Expression centre;     ///< y of the road centre (m) as a function of x and the inputs
  Distribution centreNoise;     ///< m, drawn independently at every point
  int lanes = 1;
  Expression laneWidth = Expression::constant(3.5);  ///< m
  Distribution laneWidthNoise;  ///< m, drawn once per concrete scenario
  double speedLimit = 50.0;     ///< m/s (SUMO edge speed; scripted vehicles ignore it)
  double extensionBefore = 30.0;  ///< m, straight lead-in before x_min
  double extensionAfter = 150.0;  ///< m, straight lead-out after x_max
};

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
  std::string where;
};

struct VehicleSpec {
  std::string id;
  int lane = 0;            ///< 0 = rightmost
  Distribution headingNoise;  ///< rad, added to the heading at every step (Ego and others)
  Expression x;            ///< m, initial x of the vehicle's centre (on its lane's centre line)
  double length = 5.0;     ///< m
  double width = 1.8;      ///< m
  // Ego only:
  Expression speed;                   ///< m/s, initial speed
  ControllerSpec controller;
  // Others only:
  SpeedProfile speedProfile;
  Distribution speedNoise;            ///< m/s, added to the scripted speed at every instant
  std::string where;
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
  double step = 0.2;         ///< s
  double duration = 5.0;     ///< s
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
};

/// Loads and validates a logical scenario. Throws ConfigError with
/// "file:line: field: problem" for malformed YAML, unknown keys, min > max,
/// expressions referencing unknown inputs, non-positive durations, etc.
std::shared_ptr<const LogicalScenario> loadLogicalScenario(const std::filesystem::path& file);
/// Same, from YAML text (`source_name` is used in messages).
std::shared_ptr<const LogicalScenario> parseLogicalScenario(const std::string& yaml_text,
                                                            const std::filesystem::path& source_name);

}  // namespace vsd::scenario
