#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

#include "vsd/core/random.hpp"

using namespace vsd;

TEST(Random, SameSeedIndexAndStreamGiveSameSequence) {
  Rng a = Rng::derive(7, 123, RandomStream::Inputs);
  Rng b = Rng::derive(7, 123, RandomStream::Inputs);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.nextU64(), b.nextU64());
}

TEST(Random, StreamsSeedsAndIndicesAreIndependent) {
  const auto first = [](Rng rng) { return rng.nextU64(); };
  std::set<std::uint64_t> values = {
      first(Rng::derive(7, 123, RandomStream::Inputs)), first(Rng::derive(7, 123, RandomStream::RoadNoise)),
      first(Rng::derive(7, 124, RandomStream::Inputs)), first(Rng::derive(8, 123, RandomStream::Inputs))};
  EXPECT_EQ(values.size(), 4u);
}

TEST(Random, UniformStaysInRangeWithCorrectMean) {
  Rng rng(1);
  double sum = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform(-0.5, 0.5);
    ASSERT_GE(u, -0.5);
    ASSERT_LT(u, 0.5);
    sum += u;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_EQ(rng.uniform(3.0, 3.0), 3.0);
}

TEST(Random, NormalHasRequestedMoments) {
  Rng rng(2);
  const int n = 200000;
  double sum = 0.0;
  double sum_sq = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = rng.normal(2.0, 0.5);
    sum += x;
    sum_sq += x * x;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 2.0, 0.01);
  EXPECT_NEAR(std::sqrt(sum_sq / n - mean * mean), 0.5, 0.01);
}

TEST(Random, PermutationContainsEveryIndexOnce) {
  Rng rng(3);
  auto order = rng.permutation(1000);
  std::vector<std::size_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(sorted[i], i);
  EXPECT_FALSE(std::is_sorted(order.begin(), order.end()));
}
