#pragma once
// A logical scenario's inputs as an OpenSCENARIO 1.2 ParameterValueDistribution
// (`vsd-sumo scenario distribution`):
//   stochastic (default): uniform -> UniformDistribution, normal -> NormalDistribution
//     (variance = std^2, truncation bounds as its Range), choices and constants ->
//     ProbabilityDistributionSet (equal weights); numberOfTestRuns = samples, randomSeed = seed.
//   deterministic grid (`--grid N`): uniform and bounded normal -> DistributionRange of N
//     points over [min, max]; choices and constants -> DistributionSet.
// Not expressible, and therefore listed (FileHeader description, an XML comment and the
// summary) instead of written: dependent ranges (bounds that are expressions over other
// inputs — OpenSCENARIO distributions are independent per parameter), unbounded normals
// on a grid, and the random variations drawn per point or step (road-centre, lane-width,
// heading and speed noise), which are not scenario parameters.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vsd/scenario/logical_scenario.hpp"

namespace vsd::interop {

struct DistributionOptions {
  std::filesystem::path output;  ///< the .xosc to write
  std::uint64_t samples = 0;     ///< numberOfTestRuns (stochastic)
  std::uint64_t seed = 0;        ///< randomSeed (stochastic)
  std::optional<int> grid;       ///< points per input (>= 2): a deterministic grid instead

  /// Throws ConfigError naming the flag (--grid < 2, --samples 0).
  void validate() const;
};

struct DistributionSummary {
  std::filesystem::path output;
  std::vector<std::string> written;                             ///< inputs in the file
  std::vector<std::pair<std::string, std::string>> notWritten;  ///< input -> why not
  std::string report() const;
};

/// Writes the distribution (atomically). Throws ConfigError if no input can be expressed.
DistributionSummary writeParameterDistribution(const scenario::LogicalScenario& logical,
                                               const DistributionOptions& options);

}  // namespace vsd::interop
