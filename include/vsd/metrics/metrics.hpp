#pragma once
// Evaluation metrics of one run, computed from a Trace (simulated or predicted)
// and its scene context - never from SUMO state, so predicted trajectories are
// scored by the same code as simulated ones.
//
// Every metric is one entry of one table (the registry, src/metrics/registry.cpp):
// name, unit, one-line definition, frame, what it needs, and the function that
// computes it. Run, compare, experiment, baseline targets and criteria all read
// that table; adding a metric touches the table, its function and its test.
//
// Conventions shared by all entries (README "Metrics"):
//   frame:      the scenario frame (x along the road, y left) unless an entry says otherwise;
//   reference:  the centre of each vehicle's bounding box;
//   instants:   every recorded instant k = 0..K where the vehicles involved are valid;
//   footprint:  a rectangle of the vehicle's own length and width along its heading;
//   clearance:  footprintGap (core/geometry.hpp): the distance between two footprints,
//               minus the overlap depth when they overlap (d_min; <= 0 means they touch);
//   gap:        gap_k(Ego, O) = |p_O,k - p_Ego,k| - (L_Ego + L_O) / 2 with each vehicle's own
//               length: the bumper gap to a vehicle ahead or behind in the Ego's lane
//               (d_lon_min, and the gaps of ttc_min and thw_min).

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"

namespace vsd::metrics {

namespace detail {
struct PathRelations;  ///< path_metrics.cpp
}  // namespace detail

/// What a metric is computed from: one run's trace and the lane the Ego starts on.
struct MetricContext {
  const Trace& trace;            ///< vehicles[0] is the Ego; each track carries its length and width
  const Polyline& egoLaneCentre; ///< centre line of the Ego's starting lane (scene frame); empty if unknown
  /// Every lane boundary of the scene (scene frame), or nullptr. Used by sources that do
  /// not know the Ego's lane along its whole path (map exports: lanes cross junctions,
  /// end and split): lane offsets are then measured at each instant against the lane the
  /// Ego is in. MetricSet::evaluate passes it on only for such sources.
  const std::vector<Polyline>* laneBoundaries = nullptr;
  /// How each road user relates to the Ego's path at each instant: worked out by the first
  /// metric that needs it (in-path time to collision and headway, lateral clearance) and
  /// shared by the others of the same evaluation.
  mutable std::shared_ptr<const detail::PathRelations> pathRelations = nullptr;
};

/// What a source of traces can provide to metrics.
struct Availability {
  bool otherVehicles = false;  ///< the trace holds vehicles besides the Ego
  /// The centre line of the Ego's starting lane is known along its whole path (generated
  /// roads). Map exports only know lanes near t0, so lane-relative metrics do not apply.
  bool egoLane = false;
  /// Coordinates are a generated scenario's frame (x along the road, y lateral); a map's
  /// network frame has no such meaning.
  bool scenarioFrame = false;
};

/// One metric: an entry of the registry.
struct MetricDefinition {
  std::string name;        ///< identifier used in YAML, CSV columns and criteria
  std::string unit;        ///< "m", "s", "m/s^2"
  std::string definition;  ///< one line, as printed in reports
  std::string frame;       ///< what its coordinates are relative to
  bool needsOtherVehicle = false;
  bool needsEgoLane = false;
  bool needsScenarioFrame = false;
  /// A value <= this counts as a collision in summaries (e.g. d_min <= 0); nullopt: no rule.
  std::optional<double> collisionAtOrBelow;
  /// NaN where it cannot be computed (no valid instant); +inf where documented (e.g. never closing).
  std::function<double(const MetricContext&)> compute;

  bool appliesTo(const Availability& available) const {
    return (!needsOtherVehicle || available.otherVehicles) && (!needsEgoLane || available.egoLane) &&
           (!needsScenarioFrame || available.scenarioFrame);
  }
};

/// Every metric this tool computes, in a fixed order (the registry's table).
const std::vector<MetricDefinition>& registry();
/// Looks a metric up by name; nullptr if unknown.
const MetricDefinition* findMetric(const std::string& name);
/// Looks a metric up by name; throws ConfigError "<where>: unknown metric 'x' (known: ...)".
const MetricDefinition& metric(const std::string& name, const std::string& where);
/// Names of every registered metric, in registry order.
std::vector<std::string> metricNames();
/// The metrics that apply to a source with `available` context, in registry order.
std::vector<std::string> defaultMetrics(const Availability& available);

/// A chosen list of metrics, validated once.
class MetricSet {
 public:
  /// `names` empty: every metric that applies (defaultMetrics). Throws ConfigError for an
  /// unknown name (listing the known ones), a name listed twice, or a metric the source
  /// cannot provide (e.g. d_min without another vehicle); `where` prefixes messages.
  MetricSet(const std::vector<std::string>& names, const Availability& available, const std::string& where);

  const std::vector<std::string>& names() const { return names_; }
  std::vector<std::string> units() const;
  /// Values in names() order; NaN where a metric cannot be computed (no valid instant).
  /// For a source without the Ego's lane along its whole path (maps), lane offsets are
  /// measured at each instant between context.laneBoundaries; else against egoLaneCentre.
  std::vector<double> evaluate(const MetricContext& context) const;
  /// True if any value is at or below its metric's collision threshold.
  bool collision(const std::vector<double>& values) const;
  /// "d_min <= 0" (the rules of this set's metrics, joined by " or "); empty if none applies.
  std::string collisionRule() const;

 private:
  std::vector<std::string> names_;
  std::vector<const MetricDefinition*> definitions_;
  Availability available_;
};

}  // namespace vsd::metrics
