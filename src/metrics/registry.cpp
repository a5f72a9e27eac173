#include <fmt/format.h>

#include <algorithm>

#include "functions.hpp"
#include "vsd/core/error.hpp"
#include "vsd/metrics/metrics.hpp"

namespace vsd::metrics {

namespace {

/// The table: one entry per metric (README "Metrics" renders the same text).
std::vector<MetricDefinition> buildRegistry() {
  using namespace detail;
  const std::string any_frame = "distances between vehicles (any frame)";
  const std::string ego_lane = "the Ego's starting lane (centre line, left positive)";
  std::vector<MetricDefinition> table;
  // name, unit, definition, frame, needs: other vehicle, Ego lane, scenario frame; collision rule; function
  table.push_back({"a_min", "m/s^2", "Ego's minimum longitudinal acceleration, min over k>=1 of (v_k - v_{k-1})/dt",
                   "Ego's direction of travel", false, false, false, std::nullopt, egoMinAcceleration});
  table.push_back({"d_min", "m",
                   "minimum over instants and other vehicles of the clearance between their footprints (rectangles "
                   "of each vehicle's length and width along its heading; negative: overlap depth)",
                   any_frame, true, false, false, 0.0, minGap});
  table.push_back({"d_lon_min", "m",
                   "minimum over instants of the bumper gap to a vehicle in the Ego's lane (footprints overlapping "
                   "across the lane): distance along the lane between centres minus half of both lengths",
                   any_frame, true, false, false, std::nullopt, minLongitudinalGapInLane});
  table.push_back({"p_lat_max", "m",
                   "Ego's maximum signed lateral offset (centre, left positive) from the centre line of the lane it "
                   "starts on - the paper's road-relative p_lat_max",
                   ego_lane, false, true, false, std::nullopt, egoMaxLateralOffsetFromLane});
  table.push_back({"y_max", "m", "Ego's maximum y (centre) in the scenario frame", "scenario frame", false, false,
                   true, std::nullopt, egoMaxScenarioY});
  table.push_back({"ttc_min", "s",
                   "minimum time to collision with a vehicle ahead: gap / closing speed along the line between "
                   "centres; +inf if never closing",
                   any_frame, true, false, false, std::nullopt, minTimeToCollision});
  table.push_back({"thw_min", "s", "minimum time headway to a vehicle ahead: gap / Ego speed (Ego > 0.1 m/s); +inf if never",
                   any_frame, true, false, false, std::nullopt, minTimeHeadway});
  table.push_back({"lane_offset_max", "m",
                   "Ego's maximum distance (centre) from the centre line of its lane: the lane it starts on (generated "
                   "roads); on maps the lane it is in at each instant, midway between the nearest boundaries left and "
                   "right",
                   "the Ego's lane", false, false, false, std::nullopt, egoMaxAbsLaneOffset});
  // The measures of SUMO's SSM device (README "Criticality measures and SUMO's SSM device").
  table.push_back({"pet_min", "s",
                   "minimum post-encroachment time where the Ego's centre path crosses another vehicle's: the second "
                   "one's entry into the other's body strip minus the first one's exit; +inf if no crossing",
                   any_frame, true, false, false, std::nullopt, minPostEncroachmentTime});
  table.push_back({"drac_max", "m/s^2",
                   "maximum deceleration rate to avoid a crash with a vehicle ahead: closing speed^2 / (2 gap), gap and "
                   "closing speed as for ttc_min; 0 if never closing",
                   any_frame, true, false, false, std::nullopt, maxDecelerationToAvoidCrash});
  table.push_back({"gap_min_lane", "m",
                   "minimum bumper gap to a vehicle ahead measured along the Ego's lane (SSM's SGAP); +inf if none ahead",
                   ego_lane, true, true, false, std::nullopt, minLaneGap});
  table.push_back({"ttc_min_lane", "s",
                   "minimum time to collision along the Ego's lane: lane gap / (v_Ego - v_leader) (SSM's TTC); +inf if "
                   "never closing",
                   ego_lane, true, true, false, std::nullopt, minLaneTimeToCollision});
  table.push_back({"thw_min_lane", "s",
                   "minimum time headway along the Ego's lane: lane gap / Ego speed (Ego > 0.1 m/s; SSM's TGAP); +inf "
                   "if never",
                   ego_lane, true, true, false, std::nullopt, minLaneTimeHeadway});
  table.push_back({"drac_max_lane", "m/s^2",
                   "maximum deceleration rate to avoid a crash along the Ego's lane: (v_Ego - v_leader)^2 / (2 lane "
                   "gap) (SSM's DRAC); 0 if never closing",
                   ego_lane, true, true, false, std::nullopt, maxLaneDecelerationToAvoidCrash});
  // Relative to the Ego's lane and the path it sweeps (core/path_relation.hpp, as the Ego's object list).
  const std::string ego_path = "the Ego's starting lane and the corridor of its own width along it";
  table.push_back({"ttc_inpath_min", "s",
                   "minimum time to collision with the in-path object (the nearest road user ahead reaching into the "
                   "Ego's swept corridor, which changes during a cut-in): bumper gap along the lane / closing speed "
                   "along it; +inf if never closing",
                   ego_path, true, true, false, std::nullopt, minInPathTimeToCollision});
  table.push_back({"thw_inpath_min", "s",
                   "minimum time headway to the in-path object: bumper gap along the lane / the Ego's speed along it "
                   "(> 0.1 m/s); +inf if there never is one",
                   ego_path, true, true, false, std::nullopt, minInPathTimeHeadway});
  table.push_back({"lat_clearance_min", "m",
                   "minimum lateral clearance to road users beside the Ego (their extents along the lane overlapping "
                   "the Ego's): distance across the lane between the footprints, negative when they reach into the "
                   "Ego's corridor; +inf if none is ever beside it",
                   ego_path, true, true, false, std::nullopt, minLateralClearance});
  table.push_back({"decel_max", "m/s^2", "Ego's maximum longitudinal deceleration, max(0, -a_min)",
                   "Ego's direction of travel", false, false, false, std::nullopt, egoMaxDeceleration});
  table.push_back({"jerk_max", "m/s^3",
                   "Ego's maximum longitudinal jerk, max over k>=2 of |a_k - a_{k-1}|/dt",
                   "Ego's direction of travel", false, false, false, std::nullopt, egoMaxJerk});
  return table;
}

std::string collisionRuleOf(const MetricDefinition& definition) {
  return fmt::format("{} <= {}", definition.name, formatValue(*definition.collisionAtOrBelow));
}

}  // namespace

const std::vector<MetricDefinition>& registry() {
  static const std::vector<MetricDefinition> table = buildRegistry();
  return table;
}

const MetricDefinition* findMetric(const std::string& name) {
  for (const auto& definition : registry()) {
    if (definition.name == name) return &definition;
  }
  return nullptr;
}

std::vector<std::string> metricNames() {
  std::vector<std::string> names;
  for (const auto& definition : registry()) names.push_back(definition.name);
  return names;
}

const MetricDefinition& metric(const std::string& name, const std::string& where) {
  if (const auto* definition = findMetric(name)) return *definition;
  throw ConfigError(fmt::format("{}: unknown metric '{}' (known: {})", where, name, fmt::join(metricNames(), ", ")));
}

std::vector<std::string> defaultMetrics(const Availability& available) {
  std::vector<std::string> names;
  for (const auto& definition : registry()) {
    if (definition.appliesTo(available)) names.push_back(definition.name);
  }
  return names;
}

MetricSet::MetricSet(const std::vector<std::string>& names, const Availability& available, const std::string& where)
    : names_(names.empty() ? defaultMetrics(available) : names), available_(available) {
  for (const auto& name : names_) {
    const auto& definition = metric(name, where);
    if (definition.needsOtherVehicle && !available.otherVehicles) {
      throw ConfigError(fmt::format("{}: metric '{}' needs another vehicle, but there is only the Ego", where, name));
    }
    if (definition.needsEgoLane && !available.egoLane) {
      throw ConfigError(fmt::format("{}: metric '{}' needs the Ego's lane along its whole path, which this source "
                                    "does not provide (map exports know lanes only around t0)",
                                    where, name));
    }
    if (definition.needsScenarioFrame && !available.scenarioFrame) {
      throw ConfigError(fmt::format("{}: metric '{}' is defined in a generated scenario's frame; this source is in "
                                    "a map's network frame",
                                    where, name));
    }
    if (std::count(names_.begin(), names_.end(), name) > 1) {
      throw ConfigError(fmt::format("{}: metric '{}' is listed twice", where, name));
    }
    definitions_.push_back(&definition);
  }
}

std::vector<std::string> MetricSet::units() const {
  std::vector<std::string> units;
  for (const auto* definition : definitions_) units.push_back(definition->unit);
  return units;
}

std::vector<double> MetricSet::evaluate(const MetricContext& context) const {
  // Lane offsets per instant only where the starting lane does not cover the path.
  MetricContext scoped = context;
  if (available_.egoLane) scoped.laneBoundaries = nullptr;
  std::vector<double> values;
  values.reserve(definitions_.size());
  for (const auto* definition : definitions_) values.push_back(definition->compute(scoped));
  return values;
}

bool MetricSet::collision(const std::vector<double>& values) const {
  for (std::size_t m = 0; m < definitions_.size() && m < values.size(); ++m) {
    const auto& threshold = definitions_[m]->collisionAtOrBelow;
    if (threshold && values[m] <= *threshold) return true;
  }
  return false;
}

std::string MetricSet::collisionRule() const {
  std::vector<std::string> rules;
  for (const auto* definition : definitions_) {
    if (definition->collisionAtOrBelow) rules.push_back(collisionRuleOf(*definition));
  }
  return fmt::format("{}", fmt::join(rules, " or "));
}

}  // namespace vsd::metrics
