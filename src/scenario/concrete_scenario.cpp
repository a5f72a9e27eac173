#include "vsd/scenario/concrete_scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vsd/core/error.hpp"
#include "vsd/core/random.hpp"

namespace vsd::scenario {

namespace {

double evaluateFinite(const Expression& expression, const std::vector<double>& values, const std::string& where,
                      const std::string& what) {
  const double value = expression.evaluate(values);
  if (!std::isfinite(value)) {
    throw ConfigError(fmt::format("{}: {} '{}' evaluates to {} (expected a finite number)", where, what,
                                  expression.text(), value));
  }
  return value;
}

double sampleDistribution(const Distribution& distribution, Rng& rng, const std::vector<double>& values) {
  double draw = 0.0;
  switch (distribution.kind) {
    case Distribution::Kind::Constant:
      draw = evaluateFinite(distribution.value, values, distribution.where, "value");
      break;
    case Distribution::Kind::Choice:
      draw = distribution.choices[static_cast<std::size_t>(rng.below(distribution.choices.size()))];
      break;
    case Distribution::Kind::Uniform: {
      const double lo = evaluateFinite(distribution.min, values, distribution.where, "min");
      const double hi = evaluateFinite(distribution.max, values, distribution.where, "max");
      if (lo > hi) {
        throw ConfigError(fmt::format("{}: min '{}' = {} > max '{}' = {} (expected min <= max)", distribution.where,
                                      distribution.min.text(), lo, distribution.max.text(), hi));
      }
      draw = rng.uniform(lo, hi);
      break;
    }
    case Distribution::Kind::Normal: {
      const double mean = evaluateFinite(distribution.mean, values, distribution.where, "mean");
      const double stddev = evaluateFinite(distribution.stddev, values, distribution.where, "std");
      if (stddev < 0.0) {
        throw ConfigError(fmt::format("{}: std '{}' = {} (expected >= 0)", distribution.where,
                                      distribution.stddev.text(), stddev));
      }
      draw = rng.normal(mean, stddev);
      if (distribution.hasBounds) {
        const double lo = evaluateFinite(distribution.min, values, distribution.where, "min");
        const double hi = evaluateFinite(distribution.max, values, distribution.where, "max");
        if (lo > hi) {
          throw ConfigError(fmt::format("{}: min {} > max {} (expected min <= max)", distribution.where, lo, hi));
        }
        // Truncation by resampling; bounded so that a far-away window cannot hang a run.
        int attempts = 0;
        while ((draw < lo || draw > hi) && ++attempts < 10000) draw = rng.normal(mean, stddev);
        if (draw < lo || draw > hi) {
          throw ConfigError(fmt::format("{}: normal({}, {}) almost never falls into [{}, {}]", distribution.where, mean,
                                        stddev, lo, hi));
        }
      }
      break;
    }
  }
  return draw * distribution.unitScale;
}

ConcreteVehicle placeVehicle(const VehicleSpec& spec, const std::vector<double>& inputs) {
  ConcreteVehicle vehicle;
  vehicle.id = spec.id;
  vehicle.lane = spec.lane;
  vehicle.length = spec.length;
  vehicle.width = spec.width;
  vehicle.x = evaluateFinite(spec.x, inputs, spec.where, "x");
  return vehicle;
}

}  // namespace

double scriptedSpeedAt(double initial, const std::vector<std::pair<double, double>>& duration_accel_phases, double t) {
  double speed = initial;
  double phase_start = 0.0;
  for (const auto& [duration, accel] : duration_accel_phases) {
    if (t <= phase_start) break;
    const double active = std::min(t, phase_start + duration) - phase_start;
    // Braking ends at standstill (vehicles do not reverse); a later phase may start again.
    speed = std::max(0.0, speed + accel * active);
    phase_start += duration;
  }
  return std::max(speed, 0.0);
}

ConcreteScenario sampleConcreteScenario(const std::shared_ptr<const LogicalScenario>& logical, std::uint64_t seed,
                                        std::uint64_t index) {
  const LogicalScenario& spec = *logical;
  ConcreteScenario concrete;
  concrete.logical = logical;
  concrete.seed = seed;
  concrete.index = index;

  Rng input_rng = Rng::derive(seed, index, RandomStream::Inputs);
  concrete.inputs.assign(spec.inputs.size(), 0.0);
  for (std::size_t i = 0; i < spec.inputs.size(); ++i) {
    concrete.inputs[i] = sampleDistribution(spec.inputs[i].distribution, input_rng, concrete.inputs);
  }
  const auto& inputs = concrete.inputs;

  Rng road_rng = Rng::derive(seed, index, RandomStream::RoadNoise);
  concrete.centreNoise.resize(static_cast<std::size_t>(spec.road.points));
  for (auto& noise : concrete.centreNoise) noise = sampleDistribution(spec.road.centreNoise, road_rng, inputs);
  concrete.laneWidth = evaluateFinite(spec.road.laneWidth, inputs, spec.sourceFile.string() + ": road.lane_width",
                                      "lane_width") +
                       sampleDistribution(spec.road.laneWidthNoise, road_rng, inputs);
  if (!(concrete.laneWidth > 0.5 && concrete.laneWidth <= 50.0)) {
    throw ConfigError(fmt::format("{}: road.lane_width: realised lane width {} m (expected 0.5 .. 50 m)",
                                  spec.sourceFile.string(), concrete.laneWidth));
  }

  const int steps = spec.steps();
  Rng vehicle_rng = Rng::derive(seed, index, RandomStream::VehicleNoise);
  concrete.ego = placeVehicle(spec.ego, inputs);
  concrete.ego.speed = evaluateFinite(spec.ego.speed, inputs, spec.ego.where, "speed");
  if (concrete.ego.speed < 0.0) {
    throw ConfigError(fmt::format("{}: speed '{}' = {} (expected >= 0 m/s)", spec.ego.where, spec.ego.speed.text(),
                                  concrete.ego.speed));
  }
  concrete.ego.headingNoise.resize(static_cast<std::size_t>(steps));
  for (auto& noise : concrete.ego.headingNoise) noise = sampleDistribution(spec.ego.headingNoise, vehicle_rng, inputs);
  // The others' heading noise has its own stream: adding it leaves every other draw as it was.
  Rng heading_rng = Rng::derive(seed, index, RandomStream::OtherHeadingNoise);

  for (const auto& other_spec : spec.others) {
    ConcreteVehicle other = placeVehicle(other_spec, inputs);
    std::vector<std::pair<double, double>> phases;
    for (std::size_t p = 0; p < other_spec.speedProfile.phases.size(); ++p) {
      const auto& phase = other_spec.speedProfile.phases[p];
      const double duration = evaluateFinite(phase.duration, inputs, other_spec.where, "phase duration");
      if (duration < 0.0) {
        throw ConfigError(fmt::format("{}: speed_profile.phases[{}].duration '{}' = {} (expected >= 0 s)",
                                      other_spec.where, p, phase.duration.text(), duration));
      }
      phases.emplace_back(duration, evaluateFinite(phase.accel, inputs, other_spec.where, "phase accel"));
    }
    const double initial = evaluateFinite(other_spec.speedProfile.initial, inputs, other_spec.where, "initial speed");
    other.scriptedSpeed.resize(static_cast<std::size_t>(steps) + 1);
    for (int k = 0; k <= steps; ++k) {
      const double nominal = scriptedSpeedAt(initial, phases, k * spec.step);
      const double noise = sampleDistribution(other_spec.speedNoise, vehicle_rng, inputs);
      other.scriptedSpeed[static_cast<std::size_t>(k)] = std::max(0.0, nominal + noise);
    }
    other.speed = other.scriptedSpeed.front();
    other.headingNoise.resize(static_cast<std::size_t>(steps));
    for (auto& noise : other.headingNoise) noise = sampleDistribution(other_spec.headingNoise, heading_rng, inputs);
    concrete.others.push_back(std::move(other));
  }

  for (const auto& [name, expression] : spec.ego.controller.params) {
    concrete.controllerParams.emplace_back(
        name, evaluateFinite(expression, inputs, spec.ego.controller.where, "parameter " + name));
  }
  return concrete;
}

}  // namespace vsd::scenario
