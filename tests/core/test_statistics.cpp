#include "vsd/core/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "vsd/core/error.hpp"

using namespace vsd;

TEST(Statistics, MedianOfOddAndEvenCountsInAnyOrder) {
  EXPECT_DOUBLE_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(median({7.0}), 7.0);
  EXPECT_THROW(median({}), Error);
}

TEST(Statistics, UpperMedianIsAlwaysOneOfTheValues) {
  EXPECT_DOUBLE_EQ(upperMedian({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(upperMedian({4.0, 1.0, 3.0, 2.0}), 3.0);  // the upper of 2 and 3, not 2.5
  EXPECT_DOUBLE_EQ(upperMedian({7.0}), 7.0);
  EXPECT_THROW(upperMedian({}), Error);
}

TEST(Statistics, UpperMedianIndexPointsAtTheUpperMedianAndBreaksTiesByPosition) {
  const std::vector<double> values = {0.5, 0.1, 0.9, 0.3};
  EXPECT_EQ(upperMedianIndex(values), 0u);  // sorted 0.1 0.3 0.5 0.9: the third is 0.5 at index 0
  EXPECT_DOUBLE_EQ(values[upperMedianIndex(values)], upperMedian(values));
  // Equal values, sorted by (value, index): the middle of three 1.0 is the one at index 1;
  // of (1.0, 1), (1.0, 2), (1.0, 3), (2.0, 0) position 2 is index 3.
  EXPECT_EQ(upperMedianIndex({1.0, 1.0, 1.0}), 1u);
  EXPECT_EQ(upperMedianIndex({2.0, 1.0, 1.0, 1.0}), 3u);
  EXPECT_THROW(upperMedianIndex({}), Error);
}

TEST(Statistics, WilsonIntervalMatchesItsTextbookValuesAndStaysInsideZeroToOne) {
  // 50 of 100: 0.5 ± 0.0962 (Wilson 1927; e.g. R's prop.test without continuity correction).
  const auto half = wilsonInterval(0.5, 100);
  EXPECT_NEAR(half.low, 0.4038, 1e-4);
  EXPECT_NEAR(half.high, 0.5962, 1e-4);
  // 90 of 100: [0.8256, 0.9448].
  const auto ninety = wilsonInterval(0.9, 100);
  EXPECT_NEAR(ninety.low, 0.8256, 1e-4);
  EXPECT_NEAR(ninety.high, 0.9448, 1e-4);
  // All covered in 10 trials: not [1, 1] but [0.7225, 1].
  const auto all = wilsonInterval(1.0, 10);
  EXPECT_NEAR(all.low, 0.7225, 1e-4);
  EXPECT_DOUBLE_EQ(all.high, 1.0);
  EXPECT_DOUBLE_EQ(wilsonInterval(0.0, 10).low, 0.0);
  // More trials, narrower.
  EXPECT_LT(wilsonInterval(0.9, 10000).high - wilsonInterval(0.9, 10000).low, ninety.high - ninety.low);
  EXPECT_THROW(wilsonInterval(0.5, 0), Error);
  EXPECT_THROW(wilsonInterval(1.5, 10), Error);
}

TEST(Statistics, MeanAndSampleStandardDeviationOverSeeds) {
  // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, sum of squares 32, sample std sqrt(32 / 7).
  const std::vector<double> values = {2, 4, 4, 4, 5, 5, 7, 9};
  EXPECT_DOUBLE_EQ(sampleMean(values), 5.0);
  EXPECT_DOUBLE_EQ(sampleStd(values), std::sqrt(32.0 / 7.0));
  EXPECT_DOUBLE_EQ(sampleStd({3.0}), 0.0);  // one seed: no spread
  EXPECT_THROW(sampleMean({}), Error);
}
