#pragma once
// Seeds by role (docs/results.md "Seeds: training, validation, test"). Data made with the
// training seed trains models; every configuration choice (decoder options, lane smoothing,
// schedules) is made on data of the validation seed (`vsd-sumo bench model`); a reported
// figure comes from data of a sealed test seed, which no choice has seen. One source for the
// commands that make data of a role themselves; an experiment spec names its seeds and its
// results say whether its test data are sealed.

#include <cstdint>

namespace vsd {

inline constexpr std::uint64_t kTrainingDataSeed = 1;
/// The data configurations are chosen on. The project chose its decoder configuration and
/// lane smoothing on the first 2,000 scenarios of this seed.
inline constexpr std::uint64_t kValidationDataSeed = 2;
/// Test seeds start here; figures reported in the docs use one of them.
inline constexpr std::uint64_t kFirstSealedTestSeed = 1001;

/// True for a test seed no configuration choice has seen.
constexpr bool isSealedTestSeed(std::uint64_t seed) { return seed >= kFirstSealedTestSeed; }

}  // namespace vsd
