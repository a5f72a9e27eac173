#include "vsd/core/statistics.hpp"

#include <gtest/gtest.h>

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
