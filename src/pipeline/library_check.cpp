#include "vsd/pipeline/library_check.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <regex>

#include "vsd/metrics/metrics.hpp"
#include "vsd/pipeline/run.hpp"
#include "vsd/pipeline/scenes.hpp"
#include "vsd/road/road_geometry.hpp"
#include "vsd/scenario/concrete_scenario.hpp"

namespace vsd::pipeline {

namespace {

/// Displacements of every road user against its speeds.
void checkSteps(const Trace& trace, LibraryScenarioCheck& check) {
  for (const auto& track : trace.vehicles) {
    for (std::size_t k = 0; k + 1 < track.states.size(); ++k) {
      if (!track.validAt(k) || !track.validAt(k + 1)) continue;
      const double moved = (track.states[k + 1].position() - track.states[k].position()).norm();
      const double allowed = std::max(track.states[k].speed, track.states[k + 1].speed) * trace.step;
      ++check.steps;
      if (moved > 1.01 * allowed + 1e-3) ++check.jumps;
      if (allowed > 0.01) check.worstStepRatio = std::max(check.worstStepRatio, moved / allowed);
    }
  }
}

/// Lane changes paced by a lateral speed, of road users with no other lateral action.
void checkLaneChanges(const ScenarioOutcome& outcome, const scenario::ConcreteScenario& concrete,
                      const road::RoadGeometry& road, LibraryScenarioCheck& check) {
  const road::LaneFrame frame(road.centre);
  for (std::size_t o = 0; o < concrete.others.size(); ++o) {
    const scenario::ConcreteAction* lane_change = nullptr;
    int lateral_actions = 0;
    for (const auto& action : concrete.actions) {
      if (action.owner != static_cast<int>(o) || action.kind == scenario::ActionSpec::Kind::Speed) continue;
      ++lateral_actions;
      if (action.kind == scenario::ActionSpec::Kind::LaneChange) lane_change = &action;
    }
    if (lateral_actions != 1 || lane_change == nullptr || lane_change->pace != scenario::ActionSpec::Pace::LateralSpeed) {
      continue;
    }
    const int own_lane = concrete.others[o].lane;
    const double target_lane = scenario::laneChangeTarget(*lane_change, own_lane, concrete.ego.lane);
    if (std::abs(target_lane - own_lane) != 1.0) continue;  // one lane over: the magnitude is known
    const auto& track = outcome.trace.vehicles.at(1 + o);
    std::vector<double> d;
    for (const auto& state : track.states) d.push_back(frame.coordinates(state.position()).second);
    double peak = 0.0;
    for (std::size_t k = 0; k + 1 < d.size(); ++k) peak = std::max(peak, std::abs(d[k + 1] - d[k]) / outcome.trace.step);
    const double moved = std::abs(d.back() - d.front());
    const double span = std::abs(road.laneOffset(static_cast<int>(target_lane)) - road.laneOffset(own_lane));
    // A smooth profile peaks at its midpoint: past it (with a step to spare), the peak is in the record.
    if (moved < 0.5 * span + lane_change->paceValue * outcome.trace.step) continue;
    ++check.laneChangesPastPeak;
    const double error = std::abs(peak / lane_change->paceValue - 1.0);
    check.worstLateralSpeedError = std::max(check.worstLateralSpeedError, error);
    if (error <= 0.05) ++check.laneChangesAtSpeed;
    const double last_step = std::abs(d.back() - d[d.size() - 2]);
    if (last_step > 1e-6) continue;  // still moving at the end of the window
    ++check.laneChangesEnded;
    const double target = d.front() + std::copysign(span, d.back() - d.front());
    if (std::abs(d.back() - target) <= 0.01) ++check.laneChangesOnLane;
  }
}

}  // namespace

LibraryScenarioCheck checkLibraryScenario(const std::filesystem::path& file, std::uint64_t samples,
                                          std::uint64_t seed, int jobs) {
  const auto logical = scenario::loadLogicalScenario(file);
  const metrics::MetricSet metric_set(logical->metrics, scenarioAvailability(*logical), file.string());
  LibraryScenarioCheck check;
  check.file = file;
  check.name = logical->name;
  check.samples = samples;
  RunOptions options;
  options.scenarioFile = file;
  options.samples = samples;
  options.seed = seed;
  options.jobs = jobs;
  options.writeFiles = false;
  const auto start = std::chrono::steady_clock::now();
  runScenarios(logical, options, [&](const ScenarioOutcome& outcome) {
    if (!outcome.ok()) {
      ++check.failed;
      static const std::regex numbers("[-+]?[0-9]+(\\.[0-9]+)?");
      ++check.failures[std::regex_replace(outcome.failure, numbers, "#")];
      return;
    }
    if (metric_set.collision(outcome.metrics)) ++check.collisions;
    checkSteps(outcome.trace, check);
    const auto concrete = scenario::sampleConcreteScenario(logical, seed, outcome.index);
    checkLaneChanges(outcome, concrete, road::buildRoadGeometry(concrete), check);
  });
  check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return check;
}

std::string libraryReport(const std::vector<LibraryScenarioCheck>& checks) {
  std::string text = fmt::format("  {:<34} {:>7} {:>6} {:>10} {:>9} {:>6} {:>10} {:>12} {:>10} {:>8}\n", "scenario",
                                 "samples", "failed", "collisions", "steps", "jumps", "worst step", "lane changes",
                                 "at speed", "on lane");
  for (const auto& c : checks) {
    text += fmt::format("  {:<34} {:>7} {:>6} {:>10} {:>9} {:>6} {:>10.4f} {:>12} {:>10} {:>8}\n", c.name, c.samples,
                        c.failed, c.collisions, c.steps, c.jumps, c.worstStepRatio, c.laneChangesPastPeak,
                        fmt::format("{} ({:.1f} %)", c.laneChangesAtSpeed, 100.0 * c.worstLateralSpeedError),
                        fmt::format("{}/{}", c.laneChangesOnLane, c.laneChangesEnded));
    for (const auto& [reason, count] : c.failures) text += fmt::format("      failed {} x {}\n", count, reason);
  }
  text += "  worst step: largest distance moved in a step over max(v_k, v_k+1) * dt (a jump: > 1.01, + 1 mm);\n"
          "  lane changes: scripted, paced by a lateral speed, past their midpoint in the window; at speed: peak\n"
          "  lateral speed within 5 % of the commanded (largest deviation); on lane: ended on the target lane's\n"
          "  centre (1 cm) / ended in the window\n";
  return text;
}

}  // namespace vsd::pipeline
