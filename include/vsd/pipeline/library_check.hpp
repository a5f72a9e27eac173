#pragma once
// `vsd-sumo bench library`: runs a scenario library (e.g. scenarios/alks/) and checks what
// the scenario language promises of every simulated road user (docs/alks-scenarios.md):
//   - which simulations failed, and why;
//   - no road user moves further in a step than its speed allows (|p_k+1 - p_k| <=
//     max(v_k, v_k+1) * dt, with 1 % and 1 mm of slack for rounding);
//   - a scripted lane change paced by its lateral speed peaks at that speed (within 5 %,
//     measured over the recorded steps) and ends on its target lane's centre (1 cm).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace vsd::pipeline {

struct LibraryScenarioCheck {
  std::filesystem::path file;
  std::string name;
  std::uint64_t samples = 0;
  std::uint64_t failed = 0;
  std::map<std::string, std::uint64_t> failures;  ///< reason (numbers replaced by #) -> count
  std::uint64_t collisions = 0;                   ///< completed runs meeting the collision rule (if any)
  std::uint64_t steps = 0;                        ///< road-user steps checked
  std::uint64_t jumps = 0;                        ///< steps further than the speed allows
  double worstStepRatio = 0.0;                    ///< max |p_k+1 - p_k| / (max(v_k, v_k+1) dt)
  std::uint64_t laneChangesPastPeak = 0;  ///< lane changes by lateral speed that passed their midpoint in the window
  std::uint64_t laneChangesAtSpeed = 0;   ///< ... whose peak lateral speed is within 5 % of the commanded one
  double worstLateralSpeedError = 0.0;    ///< max |peak / commanded - 1| over those
  std::uint64_t laneChangesEnded = 0;     ///< lane changes that ended within the window
  std::uint64_t laneChangesOnLane = 0;    ///< ... on their target lane's centre (1 cm)
  double seconds = 0.0;
};

/// Runs `samples` concrete scenarios (seed, jobs) of `file` (outputs are not written) and checks them.
LibraryScenarioCheck checkLibraryScenario(const std::filesystem::path& file, std::uint64_t samples,
                                          std::uint64_t seed, int jobs);

/// The table `bench library` prints.
std::string libraryReport(const std::vector<LibraryScenarioCheck>& checks);

}  // namespace vsd::pipeline
