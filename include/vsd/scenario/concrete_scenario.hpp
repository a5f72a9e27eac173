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

struct ConcreteVehicle {
  std::string id;
  int lane = 0;
  double length = 5.0;  ///< m
  double width = 1.8;   ///< m
  double x = 0.0;       ///< m, initial x of the centre (on the lane's centre line)
  double speed = 0.0;   ///< m/s, initial speed
  /// Non-Ego vehicles: scripted speed (m/s, >= 0, noise included) at every instant t_k, k = 0..steps.
  std::vector<double> scriptedSpeed;
  /// rad, disturbance of the vehicle's heading in step k (steps values; all 0 without heading noise).
  std::vector<double> headingNoise;
};

struct ConcreteScenario {
  std::shared_ptr<const LogicalScenario> logical;
  std::uint64_t seed = 0;   ///< run seed
  std::uint64_t index = 0;  ///< sample index within the run
  std::vector<double> inputs;        ///< values in logical->inputs order
  std::vector<double> centreNoise;   ///< m, lateral shift at each road point (logical->road.points values)
  double laneWidth = 3.5;            ///< m, realised (nominal + noise)
  ConcreteVehicle ego;
  std::vector<ConcreteVehicle> others;
  std::vector<std::pair<std::string, double>> controllerParams;  ///< evaluated

  double step() const { return logical->step; }
  int steps() const { return logical->steps(); }
};

/// Samples concrete scenario `index` of a run with `seed`. Throws ConfigError if a
/// distribution is invalid for the drawn values (e.g. min > max after evaluating
/// `min: v_ego + 4, max: v_ego - 4`, or a negative phase duration).
ConcreteScenario sampleConcreteScenario(const std::shared_ptr<const LogicalScenario>& logical, std::uint64_t seed,
                                        std::uint64_t index);

/// Scripted speed of a profile at time t (s), without noise; never below 0.
double scriptedSpeedAt(double initial, const std::vector<std::pair<double, double>>& duration_accel_phases, double t);

}  // namespace vsd::scenario
