#pragma once
// Deterministic random numbers.
//
// Every concrete scenario draws from streams derived from (run seed, sample
// index, purpose). Results therefore do not depend on the order in which
// scenarios are processed, on the batch size or on the number of worker
// processes: "same seed, same outputs".
//
// The distributions are implemented here from raw 64-bit draws instead of
// std::uniform_real_distribution / std::normal_distribution, whose algorithms
// are implementation-defined; this keeps sampled scenarios identical across
// standard libraries.

#include <cstdint>
#include <random>
#include <vector>

namespace vsd {

/// What a stream is used for. Separate streams keep, e.g., the road noise of
/// sample 17 unchanged when a new input is added to its logical scenario.
enum class RandomStream : std::uint64_t {
  Inputs = 1,
  RoadNoise = 2,
  VehicleNoise = 3,
  ControllerNoise = 4,
  DataSplit = 5,
  Training = 6,
  EgoSelection = 7,
  OtherHeadingNoise = 8,
  SearchSelection = 9,  ///< `search`: importance draws from a round's candidate pool
  PredictionSamples = 10,  ///< `predict --samples`, compare's drawn futures
  GridSamples = 11,  ///< `run VARIATION.xosc --samples`: which parameter sets of a grid run
};

class Rng {
 public:
  explicit Rng(std::uint64_t seed);

  /// A stream for one (seed, index, purpose) triple; independent of all others.
  static Rng derive(std::uint64_t seed, std::uint64_t index, RandomStream stream);

  std::uint64_t nextU64() { return engine_(); }
  /// Uniform in [0, 1), 53 bits of resolution.
  double uniform01();
  /// Uniform in [lo, hi); returns lo when lo == hi.
  double uniform(double lo, double hi);
  /// Normal via Box-Muller (both values of a pair are used).
  double normal(double mean, double stddev);
  /// Unbiased integer in [0, n); n must be > 0.
  std::uint64_t below(std::uint64_t n);
  /// Fisher-Yates shuffle of 0..n-1.
  std::vector<std::size_t> permutation(std::size_t n);

 private:
  std::mt19937_64 engine_;
  bool hasSpareNormal_ = false;
  double spareNormal_ = 0.0;
};

/// SplitMix64 finaliser: a well-mixed 64-bit hash of a 64-bit value.
std::uint64_t mix64(std::uint64_t value);

}  // namespace vsd
