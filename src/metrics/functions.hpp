#pragma once
// The functions behind the registry's entries (internal to the metrics module).
// Each takes the run's context and returns the metric's value (README "Metrics").

#include "vsd/metrics/metrics.hpp"

namespace vsd::metrics::detail {

// Ego alone (ego_metrics.cpp)
double egoMinAcceleration(const MetricContext& context);
double egoMaxLateralOffsetFromLane(const MetricContext& context);
double egoMaxScenarioY(const MetricContext& context);
double egoMaxAbsLaneOffset(const MetricContext& context);

// Ego and the other vehicles (pair_metrics.cpp)
double minGap(const MetricContext& context);
double minLongitudinalGapInLane(const MetricContext& context);
double minTimeToCollision(const MetricContext& context);
double minTimeHeadway(const MetricContext& context);

// Relative to the Ego's lane and swept path (path_metrics.cpp)
double minInPathTimeToCollision(const MetricContext& context);
double minInPathTimeHeadway(const MetricContext& context);
double minLateralClearance(const MetricContext& context);
double egoMaxDeceleration(const MetricContext& context);
double egoMaxJerk(const MetricContext& context);

// The measures SUMO's SSM device reports (criticality_metrics.cpp)
double minPostEncroachmentTime(const MetricContext& context);
double maxDecelerationToAvoidCrash(const MetricContext& context);
double minLaneGap(const MetricContext& context);
double minLaneTimeToCollision(const MetricContext& context);
double minLaneTimeHeadway(const MetricContext& context);
double maxLaneDecelerationToAvoidCrash(const MetricContext& context);

}  // namespace vsd::metrics::detail
