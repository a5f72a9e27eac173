#pragma once
// Evaluation metrics of one run, computed from a Trace (simulated or
// predicted) - never from SUMO state, so predicted trajectories are scored by
// the same code.
//
// Frame: the scenario frame. Reference point: the centre of each vehicle.
// Instants: every recorded instant k = 0..K where the vehicles involved are valid.
// gap_k(Ego, O) = |p_O,k - p_Ego,k| - (L_Ego + L_O) / 2   (m; <= 0 means the boxes touch)
//
//   a_min           min_{k>=1} a_Ego,k, a_k = (v_k - v_{k-1}) / dt                 [m/s^2]
//   d_min           min_k min_O gap_k(Ego, O)                                      [m]
//   p_lat_max       max_k y_Ego,k                                                  [m]
//   ttc_min         min over k, O ahead and closing of gap_k / closing speed_k;    [s]
//                   closing speed = (v_Ego u_Ego - v_O u_O) . n, n = unit(p_O - p_Ego),
//                   u = heading unit vector; "ahead": (p_O - p_Ego) . u_Ego > 0;
//                   +inf if the Ego never closes in
//   thw_min         min over k, O ahead, v_Ego > 0.1 m/s of gap_k / v_Ego,k        [s]; +inf if never
//   lane_offset_max max_k |signed distance of the Ego's centre from its lane's     [m]
//                   centre line|
//
// d_min, ttc_min and thw_min need another vehicle; lane_offset_max needs the lane.

#include <optional>
#include <string>
#include <vector>

#include "vsd/core/trace.hpp"

namespace vsd::metrics {

struct MetricInfo {
  std::string name;
  std::string unit;
  std::string description;
  bool needsOtherVehicle = false;
  bool needsLane = false;
};

/// Every metric this tool computes, in a fixed order.
const std::vector<MetricInfo>& allMetrics();
/// Looks a metric up by name.
std::optional<MetricInfo> findMetric(const std::string& name);

double aMin(const VehicleTrack& ego);
double dMin(const Trace& trace);
double pLatMax(const VehicleTrack& ego);
double ttcMin(const Trace& trace);
double thwMin(const Trace& trace);
double laneOffsetMax(const VehicleTrack& ego, const Polyline& lane_centre);

/// A chosen list of metrics, validated once.
class MetricSet {
 public:
  /// `names` empty: all metrics that apply to a scenario with / without other vehicles.
  /// Throws ConfigError for an unknown name (listing the known ones) or a metric the
  /// scenario cannot provide (e.g. d_min without another vehicle); `where` prefixes messages.
  MetricSet(const std::vector<std::string>& names, bool has_other_vehicles, const std::string& where);

  const std::vector<std::string>& names() const { return names_; }
  /// Values in names() order; NaN where a metric cannot be computed (no valid instant).
  std::vector<double> evaluate(const Trace& trace, const Polyline& ego_lane_centre) const;

 private:
  std::vector<std::string> names_;
};

}  // namespace vsd::metrics
