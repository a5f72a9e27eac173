#include "vsd/core/random.hpp"

#include <cmath>
#include <numeric>

namespace vsd {

std::uint64_t mix64(std::uint64_t value) {
  value += 0x9E3779B97F4A7C15ULL;
  value = (value ^ (value >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  value = (value ^ (value >> 27U)) * 0x94D049BB133111EBULL;
  return value ^ (value >> 31U);
}

Rng::Rng(std::uint64_t seed) : engine_(mix64(seed)) {}

Rng Rng::derive(std::uint64_t seed, std::uint64_t index, RandomStream stream) {
  const std::uint64_t key = mix64(mix64(seed) ^ mix64(index + 0x632BE59BD9B4E019ULL) ^
                                  mix64(static_cast<std::uint64_t>(stream) * 0xD6E8FEB86659FD93ULL));
  return Rng(key);
}

double Rng::uniform01() { return static_cast<double>(engine_() >> 11U) * 0x1.0p-53; }

double Rng::uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }

double Rng::normal(double mean, double stddev) {
  if (hasSpareNormal_) {
    hasSpareNormal_ = false;
    return mean + stddev * spareNormal_;
  }
  double u1 = uniform01();
  while (u1 <= 0.0) u1 = uniform01();
  const double u2 = uniform01();
  const double radius = std::sqrt(-2.0 * std::log(u1));
  constexpr double kTwoPi = 6.283185307179586476925286766559;
  spareNormal_ = radius * std::sin(kTwoPi * u2);
  hasSpareNormal_ = true;
  return mean + stddev * radius * std::cos(kTwoPi * u2);
}

std::uint64_t Rng::below(std::uint64_t n) {
  // Lemire-style rejection keeps the result unbiased for any n.
  const std::uint64_t limit = (~std::uint64_t{0}) - ((~std::uint64_t{0}) % n);
  std::uint64_t draw = engine_();
  while (draw >= limit) draw = engine_();
  return draw % n;
}

std::vector<std::size_t> Rng::permutation(std::size_t n) {
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  for (std::size_t i = n; i > 1; --i) {
    const auto j = static_cast<std::size_t>(below(i));
    std::swap(order[i - 1], order[j]);
  }
  return order;
}

}  // namespace vsd
